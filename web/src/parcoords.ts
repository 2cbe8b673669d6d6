// Parallel coordinates of the dataset's volume-weighted sample (GET /api/sample), drawn by
// parcoord-es: one axis per column (coordinates, then variables, derived ones included), with
// units in the titles, fixed global ranges (so axes do not jump between steps), reorderable axes
// and 1-D brushes, several per axis where asked (parcoord-es "1D-axes-multi": OR-ed, docs/state.md).
// Brushes are reported as state.brushes ranges in each column's units, one entry per range.
import ParCoords from 'parcoord-es';
import * as d3 from 'd3';
import { inRanges, rangesByName, type Brush } from './state';
import type { Sample } from './api';
import { pathlineVariablePrefixes, shortTitles } from './names';
import { displayUnits } from './units';

export interface AxisInfo {
  name: string;
  units: string;
  min: number;
  max: number;
  // Names of integer values (a categorical axis such as the seed kind): ticks at those values.
  categories?: Record<number, string>;
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
// step's sample costs a twentieth of a full redraw; leaving it draws every line.
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

// Short axis titles for the long dataset names (src/grid/names.json; the full name is the axis'
// tooltip).
export function axisTitle(a: AxisInfo): string {
  const units = displayUnits(a.units);
  // Pathline attributes: "start temperature anomaly" -> "start T anomaly".
  const prefix = pathlineVariablePrefixes.find((p) => a.name.startsWith(p) && shortTitles.has(a.name.slice(p.length)));
  const name = shortTitles.get(a.name) ?? (prefix === undefined ? a.name : prefix + shortTitles.get(a.name.slice(prefix.length)));
  return units ? `${name} [${units}]` : name;
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
  // The brushes last reported or set, in data units (typed values exact): an end of a brush that
  // a drag did not move keeps its value here, one it moved snaps (snapDragged).
  private known: Brush[] = [];

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

  // A sample of every column, or (a new step) of some of the columns the lines have: those change.
  setData(sample: Sample): void {
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
      this.pc.render();
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

  // The current brushes in data units, in axis order (an axis' ranges in the order drawn).
  brushes(): Brush[] {
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

  private applyBrushes(brushes: Brush[]): void {
    const known = new Set(this.axes.map((a) => a.name));
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
    // Wide enough side margins that the first and last (centred) titles are not cut off.
    const margin = { top: 34, right: 64, bottom: 14, left: 48 };
    const plotH = h - margin.top - margin.bottom;
    const names = this.axes.map((a) => a.name);
    const order = this.order_ ? [...this.order_.filter((n) => names.includes(n)), ...names.filter((n) => !this.order_!.includes(n))] : names;
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
    // Titles carry units; stagger every other one so neighbours do not overlap; the first and last
    // titles are anchored inwards so that a long one is not cut off at the panel's edge; full name
    // as tooltip.
    const shown = (this.pc.getOrderedDimensionKeys() as string[]);
    d3.select(this.container).selectAll<SVGTextElement, string>('text.label')
      .style('font-size', '11px')
      .attr('text-anchor', (d) => (d === shown[0] ? 'start' : d === shown[shown.length - 1] ? 'end' : 'middle'))
      .attr('transform', (_d, i) => `translate(0,${i % 2 ? -5 : -18})`)
      .each((d, i, nodes) => {
        const a = this.axes.find((x) => x.name === d);
        d3.select(nodes[i].parentNode as SVGGElement).append('title')
          .text(a ? `${a.name} [${displayUnits(a.units)}]: drag vertically on the axis to brush, drag the title to reorder` : d);
      });
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

  // Draws the brushed layer again (installRenderer sets it to its own rule).
  private redrawBrushed: () => void = () => {};

  // Clears the layer (parcoord-es's clear: the brushed layer then veils the foreground while something
  // is brushed) and draws the rows' polylines in time-limited slices; a newer call for the layer
  // cancels this one.
  private drawLayer(layer: 'foreground' | 'brushed', rows: Row[], coarse = false): void {
    const job = ++this.jobs[layer];
    const pc = this.pc;
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
    if (!rows.length) {
      this.timing.lines[layer] = 0;
      this.timing.drawnAt[layer] = performance.now();
      return;
    }
    const ctx = pc.ctx[layer] as CanvasRenderingContext2D;
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
      else this.timing.drawnAt[layer] = performance.now();
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

  // Each brush's min and max as text at its ends, in the axis' tick format.
  private drawBrushLabels(): void {
    if (!this.pc) return;
    const dims = this.pc.dimensions() as Record<string, { yscale: (v: number) => number }>;
    // The values reported (snapped or typed) where they are known for every range shown.
    const shown = this.brushes();
    const brushes = rangesByName(this.known.length === shown.length ? this.known : shown);
    d3.select(this.container).selectAll<SVGGElement, string>('g.dimension').each((name, i, nodes) => {
      const g = d3.select(nodes[i]);
      g.selectAll('text.brushLabel').remove();
      const ranges = brushes.get(name), dim = dims[name];
      if (!ranges || !dim) return;
      const a = this.axes.find((x) => x.name === name);
      for (const [lo, hi] of ranges) {
        const format = tickFormatFor(a?.min ?? lo, a?.max ?? hi);
        // Each range's upper end above it and its lower end below it on screen.
        const top = Math.min(dim.yscale(lo), dim.yscale(hi)), bottom = Math.max(dim.yscale(lo), dim.yscale(hi));
        const [atTop, atBottom] = dim.yscale(hi) <= dim.yscale(lo) ? [hi, lo] : [lo, hi];
        g.append('text').attr('class', 'brushLabel').attr('x', 9).attr('y', top - 4).text(format(atTop));
        g.append('text').attr('class', 'brushLabel').attr('x', 9).attr('y', bottom + 12).text(format(atBottom));
      }
    });
  }

  // The brushes as the plot has them, with the ends a drag moved on their axis' snap step and the
  // others as last known (a value typed in the Selection panel stays exact while another axis or
  // the other end is dragged). An end counts as unmoved within half a pixel of its known value.
  private snapDragged(raw: Brush[]): Brush[] {
    if (!this.pc) return raw;
    const dims = this.pc.dimensions() as Record<string, { yscale: { domain(): number[]; range(): number[] } }>;
    return raw.map((b) => {
      const a = this.axes.find((x) => x.name === b.name), dim = dims[b.name];
      if (!a || !dim) return b;
      const d = dim.yscale.domain(), r = dim.yscale.range();
      const halfPixel = 0.5 * Math.abs((d[1] - d[0]) / ((r[1] - r[0]) || 1));
      const same = this.known.filter((k) => k.name === b.name);
      const k = same.sort((p, q) => (Math.abs(p.min - b.min) + Math.abs(p.max - b.max)) - (Math.abs(q.min - b.min) + Math.abs(q.max - b.max)))[0];
      const step = snapStep(a);
      const end = (v: number, knownV: number | undefined) =>
        knownV !== undefined && Math.abs(v - knownV) <= halfPixel ? knownV : snapTo(v, step);
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
