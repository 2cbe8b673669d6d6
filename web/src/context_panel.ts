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

// What a legend shows: its title, the bar's colours and its labels.
interface LegendContent {
  title: string;
  colors: string[];
  labels: { at?: number; text: string }[];
}

const kLegendBarWidth = 200;

function legendContent(e: LegendEntry): LegendContent {
  const colors: string[] = [];
  for (let x = 0; x < kLegendBarWidth; x++) {
    const [r, g, b] = e.colorAt((x + 0.5) / kLegendBarWidth);
    colors.push(`rgb(${Math.round(r * 255)},${Math.round(g * 255)},${Math.round(b * 255)})`);
  }
  const labels = e.ticks
    ? e.ticks.map((t) => ({ at: t.at, text: t.text }))
    : [e.valueAt(0), e.valueAt(0.5), e.valueAt(1)].map((v) => ({ text: legendNumber(v) }));
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
    if (e.labels.some((l) => l.at !== undefined)) {
      labels.style.position = 'relative';
      labels.style.height = '1.2em';
      for (const t of e.labels) {
        const span = document.createElement('span');
        span.textContent = t.text;
        span.style.position = 'absolute';
        span.style.left = `${((t.at ?? 0) * 100).toFixed(2)}%`;
        span.style.transform = 'translateX(-50%)';
        labels.appendChild(span);
      }
    } else {
      for (const t of e.labels) {
        const span = document.createElement('span');
        span.textContent = t.text;
        labels.appendChild(span);
      }
    }
    div.append(title, bar, labels);
    box.appendChild(div);
  }
}
