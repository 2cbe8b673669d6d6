// The Context section: reference shells at editable depths, the graticule, the coastlines
// (state.reference; the server draws them into every frame, composited by depth with the volume)
// and the colour legends (state.legend: drawn here on the view, and by the server into screenshots
// and `raypc render` pictures).
import type { StateStore } from './store';
import type { ShellKeyEntry } from './connection';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;

export interface ContextPanelHost {
  commit(interactive: boolean): void;
  showError(message: string): void;
}

// "410, 660 km" -> [410, 660]; throws an Error naming the bad entry.
export function parseDepths(text: string): number[] {
  const parts = text.split(/[,;\s]+/).map((p) => p.replace(/km$/i, '')).filter((p) => p !== '');
  return parts.map((p) => {
    const v = Number(p);
    if (!Number.isFinite(v) || v < 0 || v > 6371) throw new Error(`shell depth '${p}': expected km between 0 and 6371`);
    return v;
  });
}

export class ContextPanel {
  constructor(private readonly store: StateStore, private readonly host: ContextPanelHost) {
    const ref = () => this.store.state.reference;
    const toggle = (id: string, set: (on: boolean) => void) => $(id).addEventListener('change', () => {
      set($<HTMLInputElement>(id).checked);
      this.host.commit(false);
    });
    toggle('refShells', (on) => { ref().shells.visible = on; });
    toggle('refGraticule', (on) => { ref().graticule.visible = on; });
    toggle('refCoastlines', (on) => { ref().coastlines.visible = on; });
    toggle('legend', (on) => { this.store.state.legend = on; });
    $('refDepths').addEventListener('change', () => {
      try {
        ref().shells.depthsKm = parseDepths($<HTMLInputElement>('refDepths').value);
        ref().shells.visible = true;
        this.sync();
        this.host.commit(false);
      } catch (e) {
        this.host.showError((e as Error).message);
        this.sync();
      }
    });
  }

  sync(): void {
    const s = this.store.state;
    $<HTMLInputElement>('refShells').checked = s.reference.shells.visible;
    $<HTMLInputElement>('refDepths').value = s.reference.shells.depthsKm.join(', ');
    $<HTMLInputElement>('refGraticule').checked = s.reference.graticule.visible;
    $<HTMLInputElement>('refCoastlines').checked = s.reference.coastlines.visible;
    $<HTMLInputElement>('legend').checked = s.legend;
  }
}

// One colour legend on the view: title, a bar and the values at its ends and middle.
export interface LegendEntry {
  title: string;
  colorAt(u: number): [number, number, number]; // along the bar, 0 = left
  valueAt(u: number): number;
  // Labels at positions along the bar instead of the values at its ends and middle (categories such
  // as feature ids, as the server's legends: render/legend.h).
  ticks?: { at: number; text: string }[];
}

function legendNumber(v: number): string {
  if (v === 0) return '0';
  const m = Math.abs(v);
  return m >= 1e5 || m < 1e-2 ? v.toExponential(2) : String(+v.toPrecision(4));
}

// The text size of the legends' labels, px (style.css .legendLabels).
const kLegendFontPx = 12;

// The values a colour bar `barPx` wide labels, by the rule of the server's legends
// (render::colorBarTicks, src/render/legend.h): round numbers (multiples of 1, 2 or 5 × 10^k, or of
// twice that; powers of ten on a log scale spanning a decade or more) inside [lo, hi], as many as
// fit (at most 6) with their labels (widths from `measure`) at least `gapPx` apart and inside the
// bar; at least one.
// `at`: 0 the bar's left end (lo), 1 its right end.
export function colorBarTicks(lo: number, hi: number, log: boolean, barPx: number, gapPx: number,
  measure: (text: string) => number): { at: number; text: string }[] {
  log = log && lo > 0;
  const at = (v: number) => Math.min(1, Math.max(0, log ? Math.log(v / lo) / Math.log(hi / lo) : (v - lo) / (hi - lo)));
  if (!(hi > lo) || !Number.isFinite(lo) || !Number.isFinite(hi)) return [{ at: 0.5, text: legendNumber(lo) }];
  const fits = (ticks: { at: number; text: string }[]) => {
    let right = -Infinity;
    for (const t of ticks) {
      const w = measure(t.text);
      if (w > barPx) return false;
      const left = tickLabelLeft(t.at, w, barPx);
      if (left < right + gapPx) return false;
      right = left + w;
    }
    return ticks.length > 0;
  };
  if (log && Math.log10(hi / lo) >= 1) {
    const d0 = Math.ceil(Math.log10(lo) - 1e-9), d1 = Math.floor(Math.log10(hi) + 1e-9);
    for (let every = 1; every <= Math.max(1, d1 - d0); every++) {
      const ticks = [];
      for (let d = d0; d <= d1; d += every) ticks.push({ at: at(10 ** d), text: String(+(10 ** d).toPrecision(6)) });
      if (ticks.length <= 6 && fits(ticks)) return ticks;
    }
  }
  // Steps of 1, 2 or 5 × 10^k from the finest giving at most 6 values, each also with every other
  // value: the first that fits with two values or more, else the first with one.
  const roundStep = (raw: number) => {
    const base = 10 ** Math.floor(Math.log10(raw));
    return [1, 2, 5, 10].map((m) => m * base).find((x) => x >= raw * (1 - 1e-9)) ?? 10 * base;
  };
  let single: { at: number; text: string }[] | null = null;
  for (let step = roundStep((hi - lo) / 6); step <= 2 * (hi - lo); step = roundStep(step * 1.5)) {
    for (const every of [1, 2]) {
      const s = step * every;
      const decimals = Math.max(0, -Math.floor(Math.log10(s) + 1e-9));
      const ticks = [];
      const slack = 1e-6 * (hi - lo);
      for (let k = Math.ceil((lo - slack) / s); k * s <= hi + slack; k++) {
        const v = k * s;
        if (log && v <= 0) continue;
        const m = Math.abs(v);
        const text = m < s * 1e-6 ? '0' : m >= 1e5 || m < 1e-2 ? String(+v.toPrecision(3)) : v.toFixed(decimals);
        ticks.push({ at: at(v), text });
      }
      if (ticks.length > 6 || !fits(ticks)) continue;
      if (ticks.length >= 2) return ticks;
      single ??= ticks;
    }
  }
  if (single) return single;
  const mid = log ? Math.sqrt(lo * hi) : (lo + hi) / 2;
  return [{ at: at(mid), text: legendNumber(mid) }];
}

// A tick label's left edge along the bar: centred on its position, shifted inside the bar, px.
export function tickLabelLeft(at: number, labelPx: number, barPx: number): number {
  return Math.min(Math.max(0, barPx - labelPx), Math.max(0, Math.round(at * barPx) - labelPx / 2));
}

let measureContext: CanvasRenderingContext2D | null = null;
function measureLegendText(text: string): number {
  if (!measureContext) {
    measureContext = document.createElement('canvas').getContext('2d')!;
    measureContext.font = `${kLegendFontPx}px ${getComputedStyle(document.body).fontFamily || 'sans-serif'}`;
  }
  return measureContext.measureText(text).width;
}

// What a legend shows: its title, the bar's colours and its labels.
interface LegendContent {
  title: string;
  colors: string[];
  labels: { at: number; text: string }[];
}

const kLegendBarWidth = 200;

function legendContent(e: LegendEntry): LegendContent {
  const colors: string[] = [];
  for (let x = 0; x < kLegendBarWidth; x++) {
    const [r, g, b] = e.colorAt((x + 0.5) / kLegendBarWidth);
    colors.push(`rgb(${Math.round(r * 255)},${Math.round(g * 255)},${Math.round(b * 255)})`);
  }
  // A log scale's middle is the ends' geometric mean.
  const lo = e.valueAt(0), hi = e.valueAt(1), mid = e.valueAt(0.5);
  const log = lo > 0 && hi > lo && Math.abs(mid - Math.sqrt(lo * hi)) < 1e-6 * hi && Math.abs(mid - (lo + hi) / 2) > 1e-6 * hi;
  const labels = e.ticks
    ? e.ticks.map((t) => ({ at: t.at, text: t.text }))
    : colorBarTicks(Math.min(lo, hi), Math.max(lo, hi), log, kLegendBarWidth, kLegendFontPx / 2, measureLegendText)
      .map((t) => ({ at: hi >= lo ? t.at : 1 - t.at, text: t.text }));
  return { title: e.title, colors, labels };
}

// The content shown last (showLegends rebuilds the overlay only when it changes: the camera's
// state changes at every pointer move of a drag, and rebuilding it each time made the page lay
// out, paint and composite it 40-50 times a second).
let shownLegends = '';

// Draws the legends into the view's overlay (#legends), and the reference shells' key (each shell's
// label beside a swatch of its colour, from the frame header: as the server draws and names them);
// none when both are empty.
export function showLegends(entries: LegendEntry[], shells: ShellKeyEntry[] = []): void {
  const contents = entries.map(legendContent);
  const key = JSON.stringify([contents, shells]);
  if (key === shownLegends) return;
  shownLegends = key;
  const box = $('legends');
  box.innerHTML = '';
  box.hidden = entries.length === 0 && shells.length === 0;
  if (shells.length) {
    const div = document.createElement('div');
    div.className = 'legend shellKey';
    div.append('shells');
    for (const s of shells) {
      const item = document.createElement('span');
      item.className = 'shellKeyItem';
      const swatch = document.createElement('span');
      swatch.className = 'shellSwatch';
      swatch.style.background = `rgb(${s.color.map((c) => Math.round(Math.min(1, Math.max(0, c)) * 255)).join(',')})`;
      item.append(swatch, s.label);
      div.appendChild(item);
    }
    box.appendChild(div);
  }
  for (const e of contents) {
    const div = document.createElement('div');
    div.className = 'legend';
    const title = document.createElement('div');
    title.className = 'legendTitle';
    title.textContent = e.title;
    const bar = document.createElement('canvas');
    bar.width = kLegendBarWidth;
    bar.height = 1;
    const ctx = bar.getContext('2d')!;
    e.colors.forEach((c, x) => {
      ctx.fillStyle = c;
      ctx.fillRect(x, 0, 1, 1);
    });
    const labels = document.createElement('div');
    labels.className = 'legendLabels';
    // Each label centred on its value's place, shifted inside the bar at the ends (as measured).
    for (const t of e.labels) {
      const span = document.createElement('span');
      span.textContent = t.text;
      span.style.left = `${tickLabelLeft(t.at, measureLegendText(t.text), kLegendBarWidth).toFixed(1)}px`;
      labels.appendChild(span);
    }
    div.append(title, bar, labels);
    box.appendChild(div);
  }
}
