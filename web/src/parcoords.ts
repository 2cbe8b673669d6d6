// Parallel coordinates of the dataset's volume-weighted sample (GET /api/sample), drawn by
// parcoord-es: one axis per column (coordinates, then variables, derived ones included), with
// units in the titles, fixed global ranges (so axes do not jump between steps), reorderable axes
// and 1-D brushes, several per axis where asked (parcoord-es "1D-axes-multi": OR-ed, docs/state.md).
// Brushes are reported as state.brushes ranges in each column's units, one entry per range.
import ParCoords from 'parcoord-es';
import * as d3 from 'd3';
import { inRanges, rangesByName, type Brush } from './state';
import type { Sample } from './api';
import { displayUnits } from './units';

export interface AxisInfo {
  name: string;
  units: string;
  min: number;
  max: number;
  // Names of integer values (a categorical axis such as the seed kind): ticks at those values.
  categories?: Record<number, string>;
  // How the column is made (stored, derived, computed when read), for the axis' tooltip.
  about?: string;
}

export interface ParcoordsOptions {
  onBrush(brushes: Brush[], interactive: boolean): void;
  alpha?: number; // line opacity (default 0.06, for many lines)
  // Runs `draw` once the 3D view shows the frame of the state onBrush just sent (or after a while):
  // the full redraw of the lines after a brush is released waits for it, so that drawing 100 000
  // lines does not compete with that frame for the CPU. Without it the lines are drawn at once.
  afterFrame?(draw: () => void): void;
  // Several ranges per axis (parcoord-es "1D-axes-multi"): brushing beside a brush adds a range, a
  // click on the axis outside the brushes clears its ranges. One plot per page may use it: that
  // mode finds its brushes by document-wide element ids.
  multi?: boolean;
  // The axis order changed (an axis dragged sideways), in display order.
  onOrder?(order: string[]): void;
  // Both layers show every line of the data set with `tag` (setData's; e.g. the step of the sample):
  // what the lines on screen describe.
  onDrawn?(tag: number): void;
}

export interface ParcoordsTiming {
  lastBrushMs: number; // cost of the UI's handler of the last brush event (after parcoord-es filtered)
  brushEvents: number;
  // The lines the last drawing of each layer draws (fewer than its rows while dragging or coarse).
  lines: { foreground: number; brushed: number };
  // When (performance.now()) the last drawing of each layer drew its last line; 0 while it draws.
  drawnAt: { foreground: number; brushed: number };
}

type Row = Record<string, number>;

// Lines are drawn by our own renderer (not parcoord-es's queue): in slices of at most kSliceMs of
// main-thread time that yield to the browser between them (so an arriving 3D frame is decoded and
// drawn without waiting for the lines), with each axis' scale reduced to x and y = a * v + b.
// A new brush event cancels the slices still pending for the same layer.
// While a brush is dragged, at most kDragLines brushed lines are drawn (every k-th, each k times
// as opaque, so the density looks alike): less main-thread and CPU time per move on a machine
// whose cores the browser shares with the server. Releasing the brush draws every line. In coarse
// mode (setCoarse: while the time series plays) both layers are drawn that way, so that a new
// step's sample costs a twentieth of a full redraw; leaving it draws every line. In coarse mode a
// layer is drawn off screen and shown once it is complete: the lines on screen are always every
// (drawn) line of one step, never a cleared layer nor a mix of two steps, however often new steps
// come (at 10 steps/s a drawing that the next step cancelled left no brushed line at all).
const kSliceMs = 6;
const kDragLines = 5000;

// Chromium rasterises 2D canvases on the GPU when it can. With only a software GL (SwiftShader, what a
// machine without a GPU has when GPU rasterisation is on) drawing 100 000 polylines there stalled
// the page for minutes (Chrome logged "GPU stall due to ReadPixels"). A context asked for with
// willReadFrequently stays in CPU memory and is drawn by Skia's software rasteriser, in the time
// budget of a slice, GPU rasterisation on or off. parcoord-es creates its layers' contexts itself,
// synchronously in its constructor: they are asked for with that option while `make` runs.
function withCpuCanvases<T>(make: () => T): T {
  const proto = HTMLCanvasElement.prototype;
  const original = proto.getContext;
  const patched = function (this: HTMLCanvasElement, type: string, options?: Record<string, unknown>) {
    return original.call(this, type, type === '2d' ? { ...options, willReadFrequently: true } : options);
  };
  proto.getContext = patched as typeof original;
  try {
    return make();
  } finally {
    proto.getContext = original;
  }
}

// Axes whose values grow downwards.
const kDownwards = new Set(['depth']);

// An axis' title: the column's full name (as the Variable menu and the server name it, from
// src/grid/names.json) with its units. Long titles wrap over up to three lines (wrapTitle).
export function axisTitle(a: AxisInfo): string {
  const units = displayUnits(a.units);
  return units ? `${a.name} [${units}]` : a.name;
}

// The text size of the plot's titles, ticks and brush labels, px: at least 12 px, so that they stay
// legible at 1366×768. kLineHeight: one title line.
const kFontPx = 12;
const kLineHeight = 14;
const kMaxTitleLines = 3;

// Greedy word wrap of `text` into lines no wider than `width` px (measured with `measure`); at most
// kMaxTitleLines, the last one ending in "…" when the text did not fit (the whole title is the
// axis' tooltip and ARIA label).
export function wrapTitle(text: string, width: number, measure: (s: string) => number): string[] {
  // Words too wide for a line are split after their hyphens ("transition-induced").
  const words = text.split(/\s+/).filter(Boolean)
    .flatMap((w) => (measure(w) > width && w.includes('-') ? w.split(/(?<=-)/) : [w]));
  const lines: string[] = [];
  let line = '';
  for (const w of words) {
    const next = !line ? w : line.endsWith('-') ? line + w : `${line} ${w}`;
    if (!line || measure(next) <= width) line = next;
    else {
      lines.push(line);
      line = w;
    }
  }
  if (line) lines.push(line);
  if (lines.length <= kMaxTitleLines) return lines;
  const kept = lines.slice(0, kMaxTitleLines);
  let last = `${kept[kMaxTitleLines - 1]} ${lines.slice(kMaxTitleLines).join(' ')}`;
  while (last.length > 1 && measure(`${last}…`) > width) last = last.slice(0, -1);
  kept[kMaxTitleLines - 1] = `${last.trimEnd()}…`;
  return kept;
}

// A typed range of an axis: "560-760", "560 to 760", "-5 -2", "<= 0" / "≤ 0" (from the axis' lowest
// value), ">= 100" (to its highest). Returns [lo, hi] (lo ≤ hi) or an error message.
export function parseRange(text: string, axisMin: number, axisMax: number): [number, number] | string {
  const t = text.trim().replace(/−/g, '-').replace(/[–—]/g, ' to ');
  const num = '(-?(?:\\d+\\.?\\d*|\\.\\d+)(?:e[-+]?\\d+)?)';
  let m = new RegExp(`^(<=|≤|<)\\s*${num}$`, 'i').exec(t);
  if (m) return [Math.min(axisMin, Number(m[2])), Number(m[2])];
  m = new RegExp(`^(>=|≥|>)\\s*${num}$`, 'i').exec(t);
  if (m) return [Number(m[2]), Math.max(axisMax, Number(m[2]))];
  m = new RegExp(`^${num}\\s*(?:\\s|to|,|\\.\\.|-)\\s*${num}$`, 'i').exec(t);
  if (m) {
    const a = Number(m[1]), b = Number(m[2]);
    if (Number.isFinite(a) && Number.isFinite(b)) return [Math.min(a, b), Math.max(a, b)];
  }
  return `'${text}' is not a range: type e.g. 560-760, <= 0 or >= 100`;
}

// Widths of text in the plot's font, px.
function textMeasure(): (s: string) => number {
  const ctx = document.createElement('canvas').getContext('2d')!;
  ctx.font = `${kFontPx}px sans-serif`; // parcoord-es's font family (its parcoords.css)
  return (s) => ctx.measureText(s).width;
}

// Tick labels that stay short for values like 3e-9 m/s or 2e-6 1/K.
function tickFormatFor(lo: number, hi: number): (v: number) => string {
  const m = Math.max(Math.abs(lo), Math.abs(hi));
  if (m > 0 && (m < 1e-2 || m >= 1e6)) return (v) => (v === 0 ? '0' : v.toExponential(1));
  return d3.format('~g');
}

// The step brush ends snap to while dragged: a tenth of the step between the axis' labelled ticks
// (d3's ticks of its scale, 5 per axis), e.g. 50 km on depth (ticks 500 km apart), 0.5 K on a
// temperature anomaly ticked every 5 K. The labelled step itself is too coarse (560–760 km would be
// out of reach); a tenth is a few pixels on a plot a few hundred pixels high. 0: no snapping.
export function snapStep(a: AxisInfo): number {
  if (a.categories) return 0;
  const hi = a.max > a.min ? a.max : a.min + 1;
  return d3.tickStep(a.min, hi, 5) / 10;
}

// v on the grid of `step`, written without binary noise (0.1 * 3 is 0.30000000000000004).
export function snapTo(v: number, step: number): number {
  if (!(step > 0)) return v;
  const decimals = Math.max(0, -Math.floor(Math.log10(step)) + 1);
  return +(Math.round(v / step) * step).toFixed(decimals);
}

// The key that marks a row of a pair's second sample (not a column name: it starts with a NUL).
const kSecondRow = '\u0000second';

export class ParallelCoordinates {
  private pc: any = null; // eslint-disable-line @typescript-eslint/no-explicit-any
  private rows: Row[] = [];
  // A pair's second sample (setSecond), marked by kSecondRow, and the two samples' colours.
  private second: Row[] = [];
  private pairColors: [string, string] | null = null;
  private suppress = 0;
  private order_: string[] | null = null;
  private shownOrder = '';
  private pending: Brush[] = [];
  private lineColor: (row: Row) => string = () => '#4a90d9';
  readonly timing: ParcoordsTiming = { lastBrushMs: 0, brushEvents: 0, lines: { foreground: 0, brushed: 0 }, drawnAt: { foreground: 0, brushed: 0 } };
  private readonly jobs: Record<string, number> = { foreground: 0, brushed: 0 };
  private readonly channel = new MessageChannel();
  private readonly slices: (() => void)[] = [];
  private dragging = false;
  private coarse = false;
  // The tag of the data set (setData) and, per layer, of the lines that layer shows complete.
  private dataTag = -1;
  private readonly drawnTags: Record<string, number> = { foreground: -1, brushed: -1 };
  // Off-screen layers of coarse mode (drawn there, then copied at once).
  private readonly offscreen: Record<string, CanvasRenderingContext2D | null> = { foreground: null, brushed: null };
  // Coarse mode: a layer's complete off-screen drawing waiting for the other layer's, and whether a
  // layer's drawing is under way.
  private readonly ready: Record<string, (() => void) | null> = { foreground: null, brushed: null };
  private readonly inProgress: Record<string, boolean> = { foreground: false, brushed: false };
  // The brushes last reported or set, in data units (typed values exact): an end of a brush that
  // a drag did not move keeps its value here, one it moved snaps (snapDragged).
  private known: Brush[] = [];
  // Ranges that lie wholly outside their axis (e.g. radial velocity ≤ 0 where the axis starts at
  // 0.99): parcoord-es cannot draw them, so they are kept here, drawn as a mark at the axis' end
  // they lie beyond and said in its label; they select nothing. Part of brushes().
  private outside: Brush[] = [];
  // The axis the keyboard is on (kept focused across a rebuild) and its open range field, if any.
  private focusName: string | null = null;

  constructor(private readonly container: HTMLElement, private axes: AxisInfo[], private readonly options: ParcoordsOptions) {
    this.channel.port1.onmessage = () => {
      const f = this.slices.shift();
      if (f) f();
    };
    let resizeTimer = 0;
    new ResizeObserver(() => {
      clearTimeout(resizeTimer);
      resizeTimer = window.setTimeout(() => this.rebuild(), 150);
    }).observe(container);
  }

  // New axes (e.g. the columns of another pathline window); drops brushes on axes that are gone.
  setAxes(axes: AxisInfo[]): void {
    const same = JSON.stringify(axes) === JSON.stringify(this.axes);
    this.axes = axes;
    if (!same && this.pc) {
      const names = new Set(axes.map((a) => a.name));
      const kept = (this.pc.getOrderedDimensionKeys() as string[]).filter((n) => names.has(n));
      this.order_ = [...kept, ...axes.map((a) => a.name).filter((n) => !kept.includes(n))];
      this.pending = this.brushes().filter((b) => names.has(b.name));
      this.pc = null;
    }
  }

  // New axes drawn at once with the rows already loaded (a shown or hidden axis).
  showAxes(axes: AxisInfo[]): void {
    this.setAxes(axes);
    if (!this.pc && this.rows.length) this.rebuild();
  }

  get rowCount(): number {
    return this.rows.length;
  }

  // The tag (setData's) of the lines both layers show complete; -1 while they differ or draw.
  get drawnTag(): number {
    return this.drawnTags.foreground === this.drawnTags.brushed ? this.drawnTags.foreground : -1;
  }

  // A sample of every column, or (a new step) of some of the columns the lines have: those change.
  // `tag` names the data (the step of the sample): onDrawn reports it once its lines are drawn.
  setData(sample: Sample, tag = -1): void {
    this.dataTag = tag;
    const n = sample.rows, c = sample.columns.length, v = sample.values;
    // A new step's sample has the same rows: its values go into the rows there are (100 000 objects
    // not made again, nor collected, for every step of a playback); the other columns stay.
    const same = this.rows.length === n && n > 0 && sample.columns.every((name) => name in this.rows[0]);
    const rows: Row[] = same ? this.rows : new Array(n);
    if (!same) for (let i = 0; i < n; i++) rows[i] = {};
    // Column by column: one property name per loop, so each store stays monomorphic.
    for (let k = 0; k < c; k++) {
      const name = sample.columns[k];
      for (let i = 0; i < n; i++) rows[i][name] = v[i * c + k];
    }
    this.rows = rows;
    this.redrawRows();
  }

  // The rows (both samples of a pair) drawn again with the brushes in force, or the plot rebuilt.
  private redrawRows(): void {
    if (!this.pc) {
      this.rebuild();
      return;
    }
    const brushes = this.brushes();
    this.suppress++;
    try {
      this.pc.data(this.allRows());
      // parcoord-es's render sizes the canvases again (autoscale), which clears them: in coarse mode
      // (playback) the lines are drawn by the renderer's queue alone, off screen, and the layers keep
      // the last step's lines until the new ones are complete. The axes' ranges are fixed.
      if (this.coarse) this.pc.render.queue();
      else this.pc.render();
      if (brushes.length) this.applyBrushes(brushes);
    } finally {
      this.suppress--;
    }
  }

  // A pair's second sample (docs/compare.md, "Side by side"): drawn and brushed with the first, each
  // in its own colour (`colors`: the first's, the second's) instead of the volume's; null: one sample.
  setSecond(sample: Sample | null, colors: [string, string] = ['#4aa3ff', '#ff9933']): void {
    const rows: Row[] = [];
    if (sample) {
      const n = sample.rows, c = sample.columns.length, v = sample.values;
      for (let i = 0; i < n; i++) rows.push({ [kSecondRow]: 1 });
      for (let k = 0; k < c; k++) for (let i = 0; i < n; i++) rows[i][sample.columns[k]] = v[i * c + k];
    }
    this.second = rows;
    this.pairColors = sample ? colors : null;
    this.redrawRows();
  }

  // The rows drawn: the sample's, then a pair's second sample's.
  private allRows(): Row[] {
    return this.second.length ? this.rows.concat(this.second) : this.rows;
  }

  // Coarse mode: at most kDragLines lines per layer (see above); turning it off redraws every line.
  setCoarse(on: boolean): void {
    if (on === this.coarse) return;
    this.coarse = on;
    if (!on && this.pc) {
      this.suppress++;
      try {
        this.pc.render();
      } finally {
        this.suppress--;
      }
    }
  }

  setColor(fn: (row: Row) => string): void {
    this.lineColor = fn;
    if (this.pc) this.pc.color(fn).render();
  }

  // The current brushes in data units, in axis order (an axis' ranges in the order drawn), then
  // the ranges wholly outside their axis. An end beyond its axis is drawn at the axis' end: it is
  // reported as known (the value set or typed), not as the end drawn.
  brushes(): Brush[] {
    const raw = this.rawBrushes().map((b) => this.knownFor(b) ?? b);
    return [...raw, ...this.outside];
  }

  // The axis' value range, low to high ([a.min, a.max] as drawn).
  private domain(name: string): [number, number] | null {
    const dims = this.pc?.dimensions() as Record<string, { yscale: { domain(): number[] } }> | undefined;
    const d = dims?.[name]?.yscale.domain();
    return d ? [Math.min(d[0], d[1]), Math.max(d[0], d[1])] : null;
  }

  // Half a pixel of the axis in its units (how near an end drawn is to a value).
  private halfPixel(name: string): number {
    const dims = this.pc?.dimensions() as Record<string, { yscale: { domain(): number[]; range(): number[] } }> | undefined;
    const dim = dims?.[name];
    if (!dim) return 0;
    const d = dim.yscale.domain(), r = dim.yscale.range();
    return 0.5 * Math.abs((d[1] - d[0]) / ((r[1] - r[0]) || 1));
  }

  // The known range drawn as `b` (its ends clamped to the axis), if any.
  private knownFor(b: Brush): Brush | undefined {
    const dom = this.domain(b.name);
    if (!dom) return undefined;
    const tol = this.halfPixel(b.name);
    const clamp = (v: number) => Math.min(dom[1], Math.max(dom[0], v));
    return this.known.find((k) => k.name === b.name && Math.abs(clamp(k.min) - b.min) <= tol && Math.abs(clamp(k.max) - b.max) <= tol &&
      (k.min < dom[0] || k.max > dom[1]));
  }

  // The brushes as parcoord-es has them (ends within the axis).
  private rawBrushes(): Brush[] {
    if (!this.pc || !this.pc.brushExtents) return [];
    type Extent = { selection: { scaled: number[] } };
    const ext = this.pc.brushExtents() as Record<string, Extent | Extent[]>;
    const keys: string[] = this.pc.getOrderedDimensionKeys ? this.pc.getOrderedDimensionKeys() : Object.keys(ext);
    return keys.filter((k) => ext[k]).flatMap((k) => {
      const list = Array.isArray(ext[k]) ? ext[k] as Extent[] : [ext[k] as Extent];
      return list.map((e) => {
        const s = e.selection.scaled;
        return { name: k, min: Math.min(s[0], s[1]), max: Math.max(s[0], s[1]) };
      });
    });
  }

  // The axes in display order.
  order(): string[] {
    return this.pc ? this.pc.getOrderedDimensionKeys() as string[] : this.order_ ?? this.axes.map((a) => a.name);
  }

  // Puts the axes in this order (names not shown are ignored; shown ones not named keep their
  // relative order after the named ones) without reporting it back.
  setOrder(order: string[]): void {
    const names = this.axes.map((a) => a.name);
    const next = [...order.filter((n) => names.includes(n)), ...names.filter((n) => !order.includes(n))];
    if (JSON.stringify(next) === JSON.stringify(this.order())) return;
    if (this.pc) this.pending = this.brushes();
    this.order_ = next;
    this.pc = null;
    if (this.rows.length) this.rebuild();
  }

  // Shows the given brushes (e.g. from a loaded state) without reporting them back.
  setBrushes(brushes: Brush[]): void {
    this.known = brushes.map((b) => ({ ...b }));
    if (!this.pc) {
      this.pending = brushes.map((b) => ({ ...b })); // shown once the sample has arrived
      return;
    }
    const same = JSON.stringify(this.brushes().map((b) => [b.name, b.min.toPrecision(5), b.max.toPrecision(5)]).sort()) ===
      JSON.stringify(brushes.map((b) => [b.name, b.min.toPrecision(5), b.max.toPrecision(5)]).sort());
    if (same) return;
    if (this.options.multi) {
      // parcoord-es's multi mode cannot take ranges away from an axis: a fresh plot gets them.
      this.pending = brushes.map((b) => ({ ...b }));
      this.order_ = this.pc.getOrderedDimensionKeys();
      this.pc = null;
      this.rebuild();
      return;
    }
    this.suppress++;
    try {
      this.pc.brushReset();
      this.applyBrushes(brushes);
    } finally {
      this.suppress--;
    }
    this.drawBrushLabels();
  }

  private applyBrushes(given: Brush[]): void {
    const known = new Set(this.axes.map((a) => a.name));
    // A range wholly beyond its axis is kept aside (this.outside); one partly beyond is drawn to
    // the axis' end.
    this.outside = [];
    const brushes: Brush[] = [];
    for (const b of given) {
      const dom = this.domain(b.name);
      if (!dom || !known.has(b.name)) continue;
      const lo = Math.max(dom[0], b.min), hi = Math.min(dom[1], b.max);
      if (hi <= lo && !(b.min === b.max && b.min >= dom[0] && b.min <= dom[1])) this.outside.push({ ...b });
      else brushes.push({ name: b.name, min: lo, max: hi });
    }
    const byName = [...rangesByName(brushes)].filter(([name]) => known.has(name));
    if (!byName.length) return;
    if (!this.options.multi) {
      // One range per axis: the last given (a state with several shows the last one here).
      this.pc.brushExtents(Object.fromEntries(byName.map(([name, ranges]) => [name, ranges[ranges.length - 1]])));
      return;
    }
    // parcoord-es's multi-mode setter maps each [a, b] to pixels and expects the first to be the
    // lower one on screen (the larger y), and it confines each brush to its own range; both are
    // put right here: the pair is given in screen order, and the brushes get the whole axis back.
    const dims = this.pc.dimensions() as Record<string, { yscale: { (v: number): number; range(): number[] } }>;
    const ext: Record<string, [number, number][]> = {};
    for (const [name, ranges] of byName) {
      const y = dims[name].yscale;
      ext[name] = ranges.map(([lo, hi]) => (y(lo) >= y(hi) ? [lo, hi] : [hi, lo]));
    }
    this.pc.brushExtents(ext);
    for (const node of this.container.querySelectorAll<SVGGElement>('g.brush')) {
      const name = node.getAttribute('dimension') ?? '';
      const brush = (node as unknown as { __data__?: { brush?: { extent(e: number[][]): unknown } } }).__data__?.brush;
      if (!brush || !dims[name]) continue;
      brush.extent([[-15, 0], [15, dims[name].yscale.range()[0]]]);
      d3.select(node).call(brush as never);
    }
  }

  // parcoord-es's multi mode names each axis' brush elements by the axis' position when they were
  // made and looks them up by its current position; moving an axis changes positions, so the ids
  // are brought up to date before anything reads them.
  private renumberBrushes(): void {
    if (!this.options.multi || !this.pc) return;
    const keys = Object.keys(this.pc.dimensions());
    for (const group of this.container.querySelectorAll<SVGGElement>('g.brush-group')) {
      const pos = keys.indexOf(group.getAttribute('dimension') ?? '');
      if (pos < 0) continue;
      group.id = `brush-group-${pos}`;
      for (const b of group.querySelectorAll<SVGGElement>('g.brush')) {
        const id = (b as unknown as { __data__?: { id?: number } }).__data__?.id;
        if (id !== undefined) b.id = `brush-${pos}-${id}`;
      }
    }
  }

  private rebuild(): void {
    const w = this.container.clientWidth, h = this.container.clientHeight;
    if (w < 50 || h < 50 || this.rows.length === 0) return;
    const brushes = this.pc ? this.brushes() : this.pending;
    if (this.pc) this.order_ = this.pc.getOrderedDimensionKeys();
    this.container.innerHTML = '';
    const names = this.axes.map((a) => a.name);
    const order = this.order_ ? [...this.order_.filter((n) => names.includes(n)), ...names.filter((n) => !this.order_!.includes(n))] : names;
    // Full titles wrapped to the space between axes, centred on their axes (the first and last
    // within the side margins too); the top margin holds the most lines any title needs.
    const side = { left: 48, right: 64 };
    const gap = order.length > 1 ? (w - side.left - side.right) / (order.length - 1) : w - side.left - side.right;
    const measure = textMeasure();
    const titles = new Map(order.map((name, i) => {
      const a = this.axes.find((x) => x.name === name);
      const room = Math.min(gap - 4, i === 0 ? 2 * side.left - 4 : i === order.length - 1 ? 2 * side.right - 4 : Infinity);
      return [name, wrapTitle(a ? axisTitle(a) : name, Math.max(40, room), measure)];
    }));
    const lines = Math.max(1, ...[...titles.values()].map((t) => t.length));
    const margin = { top: 8 + lines * kLineHeight, right: side.right, bottom: 16, left: side.left };
    const plotH = h - margin.top - margin.bottom;
    const dimensions: Record<string, unknown> = {};
    order.forEach((name, index) => {
      const a = this.axes.find((x) => x.name === name);
      if (!a) return;
      const lo = a.min, hi = a.max > a.min ? a.max : a.min + 1;
      const categories = a.categories;
      dimensions[name] = {
        title: axisTitle(a),
        tickFormat: categories ? (v: number) => categories[v] ?? '' : tickFormatFor(lo, hi),
        ...(categories ? { tickValues: Object.keys(categories).map(Number).filter((v) => v >= lo && v <= hi) } : {}),
        type: 'number',
        index,
        // Depth grows downwards (0 km at the top), as in the depth profile and the planet.
        yscale: d3.scaleLinear().domain(kDownwards.has(name) ? [hi, lo] : [lo, hi]).range([plotH + 1, 1]),
        ticks: 5,
      };
    });
    this.suppress++;
    try {
      this.pc = withCpuCanvases(() => ParCoords({ width: w, height: h, margin, alpha: this.options.alpha ?? 0.06,
        alphaOnBrushed: (this.options.alpha ?? 0.06) / 2, lineWidth: 1 })(this.container));
      this.installRenderer();
      this.pc
        .data(this.allRows())
        .dimensions(dimensions)
        .mode('queue')
        .color(this.lineColor)
        .render()
        .createAxes()
        .reorderable()
        .brushMode(this.options.multi ? '1D-axes-multi' : '1D-axes');
      this.pc.on('brush', () => this.emit(true));
      this.pc.on('brushend', () => this.emit(false));
      if (brushes.length) this.applyBrushes(brushes);
    } finally {
      this.suppress--;
    }
    this.shownOrder = JSON.stringify(this.pc.getOrderedDimensionKeys());
    this.drawBrushLabels();
    // Titles carry units, wrapped (above) and centred; the whole title and how to brush is the
    // tooltip.
    d3.select(this.container).selectAll<SVGTextElement, string>('text.label')
      .attr('text-anchor', 'middle')
      .attr('transform', 'translate(0,-5)')
      .each((d, i, nodes) => {
        const text = d3.select(nodes[i]);
        const ls = titles.get(d) ?? [d];
        text.text(null);
        ls.forEach((line, k) => text.append('tspan').attr('x', 0).attr('dy', k === 0 ? -(ls.length - 1) * kLineHeight : kLineHeight).text(line));
        const a = this.axes.find((x) => x.name === d);
        d3.select(nodes[i].parentNode as SVGGElement).append('title')
          .text(`${a ? axisTitle(a) : d}${a?.about ? ` — ${a.about}` : ''}. Drag vertically on the axis to brush, drag the title to reorder; ` +
            'from the keyboard (Tab to the axis): type a range such as 560-760 or <= 0 and Enter, arrow keys move the brush, Shift+arrows widen or narrow it, Escape clears it');
      });
    this.setUpKeyboard();
  }

  // ---- keyboard -------------------------------------------------------------------------------

  // Each axis is a focusable group with an ARIA label (its title, range and brush); the keys
  // brush it: typing (or Enter) opens a field for a range, ↑/↓ move its brush by the snap step (a
  // new one covers the middle tenth of the axis), Shift+↑/↓ widen or narrow it, Escape clears
  // the axis' brushes, ←/→ go to the neighbouring axis.
  private setUpKeyboard(): void {
    for (const g of this.container.querySelectorAll<SVGGElement>('g.dimension')) {
      const name = (g as unknown as { __data__?: string }).__data__;
      if (name === undefined) continue;
      g.setAttribute('tabindex', '0');
      g.setAttribute('role', 'group');
      g.setAttribute('aria-roledescription', 'axis');
      g.addEventListener('keydown', (e) => this.onAxisKey(e, name));
      g.addEventListener('focus', () => { this.focusName = name; });
      g.addEventListener('blur', () => { if (this.focusName === name && !this.container.querySelector('input.pcRange')) this.focusName = null; });
    }
    this.updateAria();
    if (this.focusName) this.axisNode(this.focusName)?.focus();
  }

  private axisNode(name: string): SVGGElement | null {
    for (const g of this.container.querySelectorAll<SVGGElement>('g.dimension'))
      if ((g as unknown as { __data__?: string }).__data__ === name) return g;
    return null;
  }

  // The axes' ARIA labels: title, range, and the ranges brushed (or that none is).
  private updateAria(): void {
    const byName = rangesByName(this.currentBrushes());
    for (const g of this.container.querySelectorAll<SVGGElement>('g.dimension')) {
      const name = (g as unknown as { __data__?: string }).__data__;
      const a = this.axes.find((x) => x.name === name);
      if (!a || name === undefined) continue;
      const format = tickFormatFor(a.min, a.max);
      const ranges = byName.get(name) ?? [];
      const brushed = ranges.length
        ? `brushed ${ranges.map(([lo, hi]) => `${format(lo)} to ${format(hi)}${this.beyondText(a, lo, hi)}`).join(' or ')}`
        : 'not brushed';
      g.setAttribute('aria-label', `${axisTitle(a)}, ${format(a.min)} to ${format(a.max)}, ${brushed}. ` +
        'Type a range and Enter to brush, arrows move the brush, Escape clears it');
    }
  }

  // " (below the axis: selects nothing)" for a range wholly beyond the axis' values, else ''.
  private beyondText(a: AxisInfo, lo: number, hi: number): string {
    if (hi < a.min) return ' (below the axis, which starts at ' + tickFormatFor(a.min, a.max)(a.min) + ': selects nothing)';
    if (lo > a.max) return ' (above the axis, which ends at ' + tickFormatFor(a.min, a.max)(a.max) + ': selects nothing)';
    return '';
  }

  // The brushes with their exact ends (typed or snapped) where they are known for every range.
  private currentBrushes(): Brush[] {
    const shown = this.brushes();
    return this.known.length === shown.length ? this.known : shown;
  }

  private onAxisKey(e: KeyboardEvent, name: string): void {
    const a = this.axes.find((x) => x.name === name);
    if (!a || e.target !== this.axisNode(name)) return;
    const ranges = this.currentBrushes().filter((b) => b.name === name);
    const step = snapStep(a) || (a.max - a.min) / 100 || 1;
    let handled = true;
    if (e.key === 'Escape') {
      if (ranges.length) this.setAxisRange(name, null);
      else handled = false; // nothing on this axis: Escape goes on to clear the other brushes
    } else if (e.key === 'ArrowUp' || e.key === 'ArrowDown') {
      // ↑ moves the brush towards the top of the screen (larger values, smaller depths).
      const towardsTop = e.key === 'ArrowUp';
      const sign = (kDownwards.has(name) ? -1 : 1) * (towardsTop ? 1 : -1);
      const r = ranges[ranges.length - 1];
      if (!r) {
        const mid = snapTo((a.min + a.max) / 2, step), half = Math.max(step, snapTo((a.max - a.min) / 20, step));
        this.setAxisRange(name, [mid - half, mid + half]);
      } else if (e.shiftKey) {
        // Shift+↑ widens (one step at each end), Shift+↓ narrows (never below one step wide).
        const d = towardsTop ? step : -step;
        const lo = snapTo(r.min - d, step), hi = snapTo(r.max + d, step);
        this.setAxisRange(name, hi - lo >= step ? [lo, hi] : [r.min, r.max]);
      } else {
        this.setAxisRange(name, [snapTo(r.min + sign * step, step), snapTo(r.max + sign * step, step)]);
      }
    } else if (e.key === 'ArrowLeft' || e.key === 'ArrowRight') {
      const order = this.order(), i = order.indexOf(name);
      const next = order[i + (e.key === 'ArrowLeft' ? -1 : 1)];
      if (next) this.axisNode(next)?.focus();
    } else if (e.key === 'Enter' || (e.key.length === 1 && /[-−0-9.<>=≤≥]/.test(e.key) && !e.ctrlKey && !e.metaKey && !e.altKey)) {
      this.openRangeField(name, e.key === 'Enter' ? '' : e.key);
    } else {
      handled = false;
    }
    if (handled) {
      e.preventDefault();
      e.stopPropagation();
    }
  }

  // A text field over the axis for a typed range: Enter sets it (or says what is wrong), Escape
  // or leaving it closes it; the axis keeps the focus afterwards.
  private openRangeField(name: string, first: string): void {
    const a = this.axes.find((x) => x.name === name), g = this.axisNode(name);
    if (!a || !g) return;
    this.container.querySelector('input.pcRange')?.remove();
    const input = document.createElement('input');
    input.type = 'text';
    input.className = 'pcRange';
    input.value = first;
    input.placeholder = 'e.g. 560-760, <= 0';
    input.setAttribute('aria-label', `Range of ${axisTitle(a)} to brush, e.g. 560-760, <= 0 or >= 100; Enter sets it, Escape cancels`);
    const box = g.getBoundingClientRect(), own = this.container.getBoundingClientRect();
    input.style.left = `${Math.max(0, Math.min(own.width - 130, box.left + box.width / 2 - own.left - 60))}px`;
    input.style.top = `${Math.max(0, box.top - own.top + box.height / 3)}px`;
    this.container.appendChild(input);
    let closed = false;
    const close = (refocus: boolean) => {
      if (closed) return;
      closed = true;
      input.remove();
      if (refocus) this.axisNode(name)?.focus();
    };
    input.addEventListener('keydown', (e) => {
      e.stopPropagation();
      if (e.key === 'Escape') {
        e.preventDefault();
        close(true);
      } else if (e.key === 'Enter') {
        e.preventDefault();
        const r = parseRange(input.value, a.min, a.max);
        if (typeof r === 'string') {
          input.setCustomValidity(r);
          input.title = r;
          input.classList.add('invalid');
          input.reportValidity();
          return;
        }
        close(false);
        this.setAxisRange(name, r);
      }
    });
    input.addEventListener('input', () => { input.setCustomValidity(''); input.classList.remove('invalid'); });
    input.addEventListener('blur', () => close(false));
    input.focus();
  }

  // Sets the axis' brush to one range (or clears its ranges), shows it and reports it as a
  // released brush; the axis keeps the keyboard focus.
  private setAxisRange(name: string, range: [number, number] | null): void {
    this.focusName = name;
    const next = this.currentBrushes().filter((b) => b.name !== name).map((b) => ({ ...b }));
    if (range) next.push({ name, min: range[0], max: range[1] });
    this.setBrushes(next);
    this.known = next.map((b) => ({ ...b }));
    this.drawBrushLabels();
    this.dragging = false;
    this.timing.brushEvents++;
    this.options.onBrush(next, false);
    if (this.options.afterFrame) this.options.afterFrame(() => this.redrawBrushed());
    else this.redrawBrushed();
    this.axisNode(name)?.focus();
  }

  // Replaces parcoord-es's line drawing (foreground and brushed layers; it stays in charge of
  // axes, brushes, filtering and reordering) with the sliced renderer below.
  private installRenderer(): void {
    const pc = this.pc;
    // The brushed rows by the selection's own rule (state.ts: OR within an axis, AND over axes, as
    // raypc resolves it), not parcoord-es's filter, which found no row on an inverted axis (depth,
    // 0 at the top): a depth brush veiled every line and highlighted none.
    const brushed = () => {
      const ranges = [...rangesByName(this.brushes())];
      const rows = ranges.length ? this.allRows().filter((r) => ranges.every(([name, rs]) => inRanges(r[name], rs))) : [];
      this.drawLayer('brushed', rows, this.dragging || this.coarse);
    };
    this.redrawBrushed = brushed;
    pc.renderBrushed.queue = brushed;
    pc.renderBrushed.default = brushed;
    let orderTimer = 0;
    pc.render.queue = () => {
      // An axis dragged sideways re-renders on every move: the brushes' ids follow at once, the
      // new order is reported once the drag has settled.
      this.renumberBrushes();
      const order = JSON.stringify(pc.getOrderedDimensionKeys());
      if (this.suppress) this.shownOrder = order; // drawn by rebuild or setData, not moved by the user
      else if (order !== this.shownOrder && pc === this.pc) {
        this.shownOrder = order;
        clearTimeout(orderTimer);
        orderTimer = window.setTimeout(() => { if (pc === this.pc) this.options.onOrder?.(this.order()); }, 400);
      }
      brushed();
      pc.renderMarked.queue();
      this.drawLayer('foreground', pc.data() as Row[], this.coarse);
    };
  }

  // A layer shows every line of the data tagged `tag`: once both do, onDrawn hears of it.
  private layerDrawn(layer: string, tag: number): void {
    this.drawnTags[layer] = tag;
    if (this.drawnTags.foreground === tag && this.drawnTags.brushed === tag) this.options.onDrawn?.(tag);
  }

  // Draws the brushed layer again (installRenderer sets it to its own rule).
  private redrawBrushed: () => void = () => {};

  // Clears the layer (parcoord-es's clear: the brushed layer then veils the foreground while something
  // is brushed) and draws the rows' polylines in time-limited slices; a newer call for the layer
  // cancels this one. In coarse mode (playback) the lines are drawn off screen and the layer is
  // cleared and given them in one go once both layers' drawings are complete.
  private drawLayer(layer: 'foreground' | 'brushed', rows: Row[], coarse = false): void {
    const job = ++this.jobs[layer];
    const pc = this.pc;
    const tag = this.dataTag;
    const buffered = this.coarse;
    const clearShown = () => {
      if (layer === 'foreground') {
        pc.clear('foreground');
        pc.clear('highlight');
      } else if (rows.length || this.brushes().length > 0) {
        pc.clear('brushed');
      } else {
        // Nothing brushed: no veil. parcoord-es's clear veils whenever its brush state has a key, and
        // the multi-range mode keeps keys for axes without ranges: the lines were veiled with no brush.
        const c = pc.ctx.brushed as CanvasRenderingContext2D;
        c.save();
        c.setTransform(1, 0, 0, 1, 0, 0);
        c.clearRect(0, 0, c.canvas.width, c.canvas.height);
        c.restore();
      }
    };
    const shown = pc.ctx[layer] as CanvasRenderingContext2D;
    this.ready[layer] = null;
    this.inProgress[layer] = buffered;
    let ctx = shown;
    if (buffered) {
      // The off-screen layer: the visible one's size, transform and line style, cleared.
      let off = this.offscreen[layer];
      if (!off || off.canvas.width !== shown.canvas.width || off.canvas.height !== shown.canvas.height) {
        const c = document.createElement('canvas');
        c.width = shown.canvas.width;
        c.height = shown.canvas.height;
        off = c.getContext('2d', { willReadFrequently: true })!;
        this.offscreen[layer] = off;
      }
      off.setTransform(1, 0, 0, 1, 0, 0);
      off.clearRect(0, 0, off.canvas.width, off.canvas.height);
      off.setTransform(shown.getTransform());
      off.lineWidth = shown.lineWidth;
      off.globalCompositeOperation = shown.globalCompositeOperation;
      ctx = off;
    } else {
      clearShown();
    }
    // The layer complete: shown (buffered: with the other layer, once its drawing is complete too).
    const complete = () => {
      this.timing.drawnAt[layer] = performance.now();
      if (!buffered) {
        this.layerDrawn(layer, tag);
        return;
      }
      const off = ctx;
      this.ready[layer] = () => {
        clearShown();
        shown.save();
        shown.setTransform(1, 0, 0, 1, 0, 0);
        shown.globalAlpha = 1;
        shown.globalCompositeOperation = 'source-over';
        shown.drawImage(off.canvas, 0, 0);
        shown.restore();
        this.layerDrawn(layer, tag);
      };
      this.inProgress[layer] = false;
      if (!this.inProgress.foreground && !this.inProgress.brushed) {
        for (const l of ['foreground', 'brushed']) {
          const flip = this.ready[l];
          this.ready[l] = null;
          flip?.();
        }
      }
    };
    if (!rows.length) {
      this.timing.lines[layer] = 0;
      complete();
      return;
    }
    const dims = pc.dimensions() as Record<string, { yscale: { domain(): number[]; range(): number[] } }>;
    const keys = (pc.getOrderedDimensionKeys() as string[]).filter((k) => dims[k]);
    // An axis being dragged sideways sits at its drag position (parcoord-es keeps it on the node).
    const dragged = new Map<string, number>();
    for (const g of this.container.querySelectorAll('g.dimension')) {
      const n = g as unknown as { __data__?: string; __origin__?: number };
      const [r0, r1] = (pc.xscale.range() as number[]).concat().sort((a, b) => a - b);
      if (n.__data__ !== undefined && typeof n.__origin__ === 'number') dragged.set(n.__data__, Math.min(r1, Math.max(r0, n.__origin__)));
    }
    const xs = keys.map((k) => dragged.get(k) ?? (pc.xscale(k) as number));
    const order = keys.map((_k, i) => i).sort((a, b) => xs[a] - xs[b]);
    const ks = order.map((i) => keys[i]), px = order.map((i) => xs[i]);
    const sa = ks.map((k) => {
      const d = dims[k].yscale.domain(), r = dims[k].yscale.range();
      return (r[1] - r[0]) / (d[1] - d[0] || 1);
    });
    const sb = ks.map((k, i) => dims[k].yscale.range()[0] - dims[k].yscale.domain()[0] * sa[i]);
    const pair = this.pairColors;
    const color = pair ? (r: Row) => (r[kSecondRow] ? pair[1] : pair[0]) : this.lineColor;
    const m = ks.length;
    const stride = coarse ? Math.max(1, Math.ceil(rows.length / kDragLines)) : 1;
    this.timing.lines[layer] = Math.ceil(rows.length / stride);
    this.timing.drawnAt[layer] = 0;
    const alpha = this.options.alpha ?? 0.06;
    let next = 0;
    const slice = () => {
      if (job !== this.jobs[layer] || pc !== this.pc) return;
      const t0 = performance.now();
      ctx.globalAlpha = Math.min(1, alpha * stride);
      let style = '';
      while (next < rows.length) {
        const end = Math.min(rows.length, next + 256 * stride);
        for (; next < end; next += stride) {
          const r = rows[next];
          const c = color(r);
          if (c !== style) { ctx.strokeStyle = c; style = c; }
          ctx.beginPath();
          // A missing value (NaN: no data there) breaks the line: nothing is drawn to or from its axis.
          let pen = false;
          for (let k = 0; k < m; k++) {
            const y = r[ks[k]] * sa[k] + sb[k];
            if (!Number.isFinite(y)) pen = false;
            else if (pen) ctx.lineTo(px[k], y);
            else { ctx.moveTo(px[k], y); pen = true; }
          }
          ctx.stroke();
        }
        // Chromium records a 2D canvas' strokes and rasterises them when the page's next frame is
        // made (CanvasRenderingContext2D::FinalizeFrame), all at once: reading a pixel rasterises
        // them here, so a slice's time is what it costs.
        ctx.getImageData(0, 0, 1, 1);
        if (performance.now() - t0 > kSliceMs) break;
      }
      if (next < rows.length) this.yieldThen(slice);
      else complete();
    };
    this.yieldThen(slice);
  }

  // The next slice runs as a background-priority task where the browser has the Prioritized Task
  // Scheduling API (Chromium): input, rendering and frames from the server go first, so a click is
  // answered while 100 000 lines are drawn. Elsewhere a MessageChannel message (a task, without
  // setTimeout's clamping).
  private yieldThen(f: () => void): void {
    const scheduler = (globalThis as unknown as { scheduler?: { postTask(cb: () => void, o: { priority: string }): Promise<void> } }).scheduler;
    if (scheduler) {
      void scheduler.postTask(f, { priority: 'background' });
      return;
    }
    this.slices.push(f);
    this.channel.port2.postMessage(0);
  }

  // Each brush's min and max as text at its ends, in the axis' tick format, inside the plot (never
  // over the axis' title). An end beyond the axis is drawn at the axis' end and its label says so;
  // a range wholly beyond it is a mark at that end with a label saying that it selects nothing.
  private drawBrushLabels(): void {
    if (!this.pc) return;
    const dims = this.pc.dimensions() as Record<string, { yscale: { (v: number): number; range(): number[] } }>;
    const brushes = rangesByName(this.currentBrushes());
    d3.select(this.container).selectAll<SVGGElement, string>('g.dimension').each((name, i, nodes) => {
      const g = d3.select(nodes[i]);
      g.selectAll('.brushLabel, .brushOutside').remove();
      const ranges = brushes.get(name), dim = dims[name];
      const a = this.axes.find((x) => x.name === name);
      if (!ranges || !dim || !a) return;
      const format = tickFormatFor(a.min, a.max);
      const [yA, yB] = dim.yscale.range();
      const yTop = Math.min(yA, yB), yBottom = Math.max(yA, yB);
      const clampY = (v: number) => Math.min(yBottom, Math.max(yTop, dim.yscale(v)));
      // Baselines: the upper label's text stays below the title (y ≥ yTop + kFontPx - 2), the lower
      // one inside the bottom margin.
      const upperY = (y: number) => Math.max(yTop + kFontPx - 2, y - 4);
      const lowerY = (y: number) => Math.min(yBottom + kFontPx, y + kFontPx + 1);
      const label = (y: number, text: string, beyond: boolean) =>
        g.append('text').attr('class', beyond ? 'brushLabel beyond' : 'brushLabel').attr('x', 9).attr('y', y).text(text);
      // Lines of a label, the first baseline at y.
      const lines = (y: number, texts: string[]) => {
        const t = g.append('text').attr('class', 'brushLabel beyond').attr('y', y);
        texts.forEach((line, k) => t.append('tspan').attr('x', 9).attr('dy', k ? kLineHeight : 0).text(line));
      };
      for (const [lo, hi] of ranges) {
        const beyond = this.beyondText(a, lo, hi);
        if (beyond) {
          // A mark at the end the range lies beyond, and a label inwards from it.
          const y = clampY(hi < a.min ? a.min : a.max), atTop = y - yTop < yBottom - y;
          g.append('rect').attr('class', 'brushOutside').attr('x', -9).attr('width', 18).attr('y', atTop ? y : y - 6).attr('height', 6);
          const texts = [`${format(lo)} to ${format(hi)}`, `${hi < a.min ? 'below' : 'above'} the axis:`, 'selects nothing'];
          lines(atTop ? y + 6 + kFontPx : y - 10 - (texts.length - 1) * kLineHeight, texts);
          continue;
        }
        // Each range's upper end above it and its lower end below it on screen.
        const yLo = clampY(lo), yHi = clampY(hi);
        const [top, bottom] = [Math.min(yLo, yHi), Math.max(yLo, yHi)];
        const [atTop, atBottom] = yHi <= yLo ? [hi, lo] : [lo, hi];
        const past = (v: number) => (v < a.min || v > a.max ? ' (past the axis)' : '');
        label(upperY(top), `${format(atTop)}${past(atTop)}`, past(atTop) !== '');
        label(lowerY(bottom), `${format(atBottom)}${past(atBottom)}`, past(atBottom) !== '');
      }
    });
    this.updateAria();
  }

  // The brushes as the plot has them, with the ends a drag moved on their axis' snap step and the
  // others as last known (a value typed in the Selection panel stays exact while another axis or
  // the other end is dragged). An end counts as unmoved within half a pixel of its known value.
  private snapDragged(raw: Brush[]): Brush[] {
    if (!this.pc) return raw;
    const dims = this.pc.dimensions() as Record<string, { yscale: { domain(): number[]; range(): number[] } }>;
    return raw.map((b) => {
      const a = this.axes.find((x) => x.name === b.name), dim = dims[b.name];
      if (!a || !dim || this.outside.includes(b)) return b;
      const d = dim.yscale.domain(), r = dim.yscale.range();
      const halfPixel = 0.5 * Math.abs((d[1] - d[0]) / ((r[1] - r[0]) || 1));
      const same = this.known.filter((k) => k.name === b.name);
      const k = same.sort((p, q) => (Math.abs(p.min - b.min) + Math.abs(p.max - b.max)) - (Math.abs(q.min - b.min) + Math.abs(q.max - b.max)))[0];
      const step = snapStep(a);
      // A known end beyond the axis is drawn at the axis' end.
      const lo = Math.min(d[0], d[1]), hi = Math.max(d[0], d[1]);
      const end = (v: number, knownV: number | undefined) =>
        knownV !== undefined && Math.abs(v - Math.min(hi, Math.max(lo, knownV))) <= halfPixel ? knownV : snapTo(v, step);
      const min = end(b.min, k?.min), max = end(b.max, k?.max);
      return min <= max ? { name: b.name, min, max } : { name: b.name, min: b.min, max: b.max };
    });
  }

  private emit(interactive: boolean): void {
    if (this.suppress) return;
    const brushes = this.snapDragged(this.brushes());
    this.known = brushes.map((b) => ({ ...b }));
    this.drawBrushLabels();
    const t0 = performance.now();
    this.timing.brushEvents++;
    this.dragging = interactive;
    this.options.onBrush(brushes, interactive);
    this.timing.lastBrushMs = performance.now() - t0;
    if (interactive) return;
    // Every line once the brush is released (after the still frame it asked for is on screen).
    if (this.options.afterFrame) this.options.afterFrame(() => this.redrawBrushed());
    else this.redrawBrushed();
  }
}
