// Transfer-function editor: the piecewise-linear opacity (state.color.opacity, positions
// normalised over the colour range, logarithmically with a log scale) drawn over the variable's
// histogram, and the colour bar with its colour control points (state.color.points).
// Opacity: drag a point to move it, click on empty space to add one, double-click a point to remove it.
// Colours (on the bar): click to add a point (it takes the colour there), drag to move, click to
// select it (its colour is then picked in the panel), double-click to remove it.
import type { ColorStop } from './colormaps';

export interface HistogramData {
  min: number;
  max: number;
  histogram: number[]; // volume fractions of equal bins over [min, max]
}

export interface TfEditorOptions {
  onChange(opacity: [number, number][], interactive: boolean): void;
  // The colour points changed (`points` is the whole new list) or one was selected (-1: none).
  onColorPoints(points: ColorStop[], interactive: boolean): void;
  onSelectColorPoint(index: number): void;
}

// What the editor shows besides the opacity points: the colour at a position of the bar, the
// position of a value (for the histograms), the colour points being edited (empty: a named map).
export interface TfView {
  colorAt(u: number): [number, number, number];
  positionOf(value: number): number;
  valueAt(u: number): number;
  colorPoints: ColorStop[];
}

const kBarHeight = 14;
// Where a named map becomes editable colour points.
const kEditPositions = [0, 1 / 6, 2 / 6, 3 / 6, 4 / 6, 5 / 6, 1];
const kPointRadius = 5;

export class TfEditor {
  private points: [number, number][] = [[0, 0], [1, 0.5]];
  private range: [number, number] = [0, 1];
  private tfView: TfView = { colorAt: () => [0.5, 0.5, 0.5], positionOf: (v) => v, valueAt: (u) => u, colorPoints: [] };
  private units = '';
  private colorPoints: ColorStop[] = [];
  private draggingColor = -1;
  selectedColor = -1;
  private histograms: { data: HistogramData; style: 'bars' | 'line' }[] = [];
  private dragging = -1;
  private readonly ctx: CanvasRenderingContext2D;

  constructor(readonly canvas: HTMLCanvasElement, private readonly options: TfEditorOptions) {
    this.ctx = canvas.getContext('2d')!;
    canvas.addEventListener('pointerdown', (e) => this.onDown(e));
    canvas.addEventListener('pointermove', (e) => this.onMove(e));
    canvas.addEventListener('pointerup', (e) => this.onUp(e));
    canvas.addEventListener('pointercancel', (e) => this.onUp(e));
    canvas.addEventListener('dblclick', (e) => this.onDoubleClick(e));
    new ResizeObserver(() => this.draw()).observe(canvas);
  }

  set(points: [number, number][], range: [number, number], view: TfView, units: string,
      histograms: { data: HistogramData; style: 'bars' | 'line' }[]): void {
    if (this.dragging < 0) this.points = points.map((p) => [p[0], p[1]] as [number, number]);
    this.range = range;
    this.tfView = view;
    if (this.draggingColor < 0) this.colorPoints = view.colorPoints.map((p) => [...p] as ColorStop);
    if (this.selectedColor >= this.colorPoints.length) this.selectedColor = -1;
    this.units = units;
    this.histograms = histograms;
    this.draw();
  }

  private plotArea() {
    const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
    return { x0: 8, x1: w - 8, y0: 6, y1: h - kBarHeight - 22 };
  }

  private toScreen(p: [number, number]): [number, number] {
    const a = this.plotArea();
    return [a.x0 + p[0] * (a.x1 - a.x0), a.y1 - p[1] * (a.y1 - a.y0)];
  }

  private fromEvent(e: PointerEvent | MouseEvent): [number, number] {
    const r = this.canvas.getBoundingClientRect();
    const a = this.plotArea();
    const x = (e.clientX - r.left - a.x0) / (a.x1 - a.x0);
    const y = (a.y1 - (e.clientY - r.top)) / (a.y1 - a.y0);
    return [Math.min(1, Math.max(0, x)), Math.min(1, Math.max(0, y))];
  }

  private hit(e: PointerEvent | MouseEvent): number {
    const r = this.canvas.getBoundingClientRect();
    const mx = e.clientX - r.left, my = e.clientY - r.top;
    let best = -1, bestD = (kPointRadius + 4) ** 2;
    this.points.forEach((p, i) => {
      const [sx, sy] = this.toScreen(p);
      const d = (sx - mx) ** 2 + (sy - my) ** 2;
      if (d < bestD) { bestD = d; best = i; }
    });
    return best;
  }

  private barY(): number {
    return this.plotArea().y1 + 4;
  }

  // The colour point under the pointer on the bar (within a few pixels), or -1.
  private hitColor(e: PointerEvent | MouseEvent): number {
    const r = this.canvas.getBoundingClientRect();
    const a = this.plotArea();
    const mx = e.clientX - r.left;
    let best = -1, bestD = 6;
    this.colorPoints.forEach((p, i) => {
      const d = Math.abs(a.x0 + p[0] * (a.x1 - a.x0) - mx);
      if (d <= bestD) { bestD = d; best = i; }
    });
    return best;
  }

  private onBar(e: PointerEvent | MouseEvent): boolean {
    const r = this.canvas.getBoundingClientRect();
    const y = e.clientY - r.top, barY = this.barY();
    return y >= barY - 2 && y <= barY + kBarHeight + 6;
  }

  private emitColors(interactive: boolean): void {
    this.options.onColorPoints(this.colorPoints.map((p) => [...p] as ColorStop), interactive);
  }

  private onDown(e: PointerEvent): void {
    if (e.button !== 0) return;
    if (this.onBar(e)) {
      let i = this.hitColor(e);
      if (i < 0) {
        // A new point takes the colour shown there; a named map first becomes points.
        const [u] = this.fromEvent(e);
        if (!this.colorPoints.length) this.colorPoints = kEditPositions.map((x) => [x, ...this.tfView.colorAt(x)] as ColorStop);
        const c = this.tfView.colorAt(u);
        i = this.colorPoints.findIndex((q) => q[0] > u);
        if (i < 0) i = this.colorPoints.length;
        this.colorPoints.splice(i, 0, [u, ...c]);
        this.emitColors(false);
      }
      this.selectedColor = i;
      this.draggingColor = i;
      this.options.onSelectColorPoint(i);
      this.canvas.setPointerCapture(e.pointerId);
      this.draw();
      return;
    }
    let i = this.hit(e);
    if (i < 0) {
      const p = this.fromEvent(e);
      i = this.points.findIndex((q) => q[0] > p[0]);
      if (i < 0) i = this.points.length;
      this.points.splice(i, 0, p);
    }
    this.dragging = i;
    this.canvas.setPointerCapture(e.pointerId);
    this.draw();
    this.options.onChange(this.points.map((p) => [...p] as [number, number]), true);
  }

  private onMove(e: PointerEvent): void {
    if (this.draggingColor >= 0) {
      const i = this.draggingColor;
      const [u] = this.fromEvent(e);
      const lo = i > 0 ? this.colorPoints[i - 1][0] : 0, hi = i + 1 < this.colorPoints.length ? this.colorPoints[i + 1][0] : 1;
      this.colorPoints[i] = [Math.min(hi, Math.max(lo, u)), this.colorPoints[i][1], this.colorPoints[i][2], this.colorPoints[i][3]];
      this.draw();
      this.emitColors(true);
      return;
    }
    if (this.dragging < 0) return;
    const i = this.dragging;
    const [x, y] = this.fromEvent(e);
    const lo = i > 0 ? this.points[i - 1][0] : 0, hi = i + 1 < this.points.length ? this.points[i + 1][0] : 1;
    this.points[i] = [Math.min(hi, Math.max(lo, x)), y];
    this.draw();
    this.options.onChange(this.points.map((p) => [...p] as [number, number]), true);
  }

  private onUp(e: PointerEvent): void {
    if (this.draggingColor >= 0) {
      this.draggingColor = -1;
      if (this.canvas.hasPointerCapture(e.pointerId)) this.canvas.releasePointerCapture(e.pointerId);
      this.emitColors(false);
      return;
    }
    if (this.dragging < 0) return;
    this.dragging = -1;
    if (this.canvas.hasPointerCapture(e.pointerId)) this.canvas.releasePointerCapture(e.pointerId);
    this.options.onChange(this.points.map((p) => [...p] as [number, number]), false);
  }

  private onDoubleClick(e: MouseEvent): void {
    if (this.onBar(e)) {
      const k = this.hitColor(e);
      if (k >= 0 && this.colorPoints.length > 2) {
        this.colorPoints.splice(k, 1);
        this.selectedColor = -1;
        this.options.onSelectColorPoint(-1);
        this.draw();
        this.emitColors(false);
      }
      return;
    }
    const i = this.hit(e);
    if (i < 0 || this.points.length <= 2) return;
    this.points.splice(i, 1);
    this.draw();
    this.options.onChange(this.points.map((p) => [...p] as [number, number]), false);
  }

  draw(): void {
    const c = this.canvas, ctx = this.ctx;
    const dpr = window.devicePixelRatio || 1;
    const w = c.clientWidth, h = c.clientHeight;
    if (w === 0 || h === 0) return;
    if (c.width !== Math.round(w * dpr) || c.height !== Math.round(h * dpr)) {
      c.width = Math.round(w * dpr);
      c.height = Math.round(h * dpr);
    }
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, w, h);
    const a = this.plotArea();
    const [lo, hi] = this.range;
    ctx.fillStyle = '#15181d';
    ctx.fillRect(a.x0, a.y0, a.x1 - a.x0, a.y1 - a.y0);

    // Histograms: bin masses as density over the displayed range, square-root scaled so thin tails show.
    for (const { data, style } of this.histograms) {
      const n = data.histogram.length;
      const binW = (data.max - data.min) / n;
      if (!(binW > 0)) continue;
      const peak = Math.max(...data.histogram.map(Math.sqrt), 1e-12);
      ctx.beginPath();
      for (let b = 0; b < n; b++) {
        const v0 = data.min + b * binW, v1 = v0 + binW;
        const x0 = a.x0 + this.tfView.positionOf(v0) * (a.x1 - a.x0), x1 = a.x0 + this.tfView.positionOf(v1) * (a.x1 - a.x0);
        if (v1 < lo || v0 > hi) continue;
        if (x1 < a.x0 || x0 > a.x1) continue;
        const y = a.y1 - (Math.sqrt(data.histogram[b]) / peak) * (a.y1 - a.y0) * 0.95;
        if (style === 'bars') ctx.rect(Math.max(a.x0, x0), y, Math.max(0.5, Math.min(a.x1, x1) - Math.max(a.x0, x0)), a.y1 - y);
        else {
          ctx.lineTo(Math.max(a.x0, x0), y);
          ctx.lineTo(Math.min(a.x1, x1), y);
        }
      }
      if (style === 'bars') { ctx.fillStyle = 'rgba(150,160,175,0.45)'; ctx.fill(); }
      else { ctx.strokeStyle = 'rgba(230,200,120,0.8)'; ctx.lineWidth = 1; ctx.stroke(); }
    }

    // Colour bar, with the opacity shown as a darker band above it.
    const barY = a.y1 + 4;
    for (let x = a.x0; x < a.x1; x++) {
      const [r, g, b] = this.tfView.colorAt((x - a.x0) / (a.x1 - a.x0));
      ctx.fillStyle = `rgb(${r * 255},${g * 255},${b * 255})`;
      ctx.fillRect(x, barY, 1, kBarHeight);
    }
    // Colour points: a tick through the bar and a handle below it (the selected one yellow).
    this.colorPoints.forEach((p, i) => {
      const x = a.x0 + p[0] * (a.x1 - a.x0);
      ctx.fillStyle = `rgb(${p[1] * 255},${p[2] * 255},${p[3] * 255})`;
      ctx.strokeStyle = i === this.selectedColor ? '#ff0' : '#fff';
      ctx.lineWidth = 1.5;
      ctx.beginPath();
      ctx.rect(x - 3, barY - 1, 6, kBarHeight + 2);
      ctx.fill();
      ctx.stroke();
    });
    ctx.fillStyle = '#ccd';
    ctx.font = '11px system-ui, sans-serif';
    ctx.textBaseline = 'top';
    const fmt = (v: number) => (Math.abs(v) >= 1e4 || (Math.abs(v) < 1e-2 && v !== 0) ? v.toExponential(2) : v.toPrecision(4));
    ctx.textAlign = 'left';
    ctx.fillText(fmt(lo), a.x0, barY + kBarHeight + 3);
    ctx.textAlign = 'center';
    ctx.fillText(fmt(this.tfView.valueAt(0.5)), (a.x0 + a.x1) / 2, barY + kBarHeight + 3);
    ctx.textAlign = 'right';
    ctx.fillText(`${fmt(hi)} ${this.units}`, a.x1, barY + kBarHeight + 3);

    // Opacity curve and its control points.
    ctx.beginPath();
    this.points.forEach((p, i) => {
      const [sx, sy] = this.toScreen(p);
      if (i === 0) ctx.moveTo(a.x0, sy);
      ctx.lineTo(sx, sy);
      if (i === this.points.length - 1) ctx.lineTo(a.x1, sy);
    });
    ctx.strokeStyle = '#fff';
    ctx.lineWidth = 1.5;
    ctx.stroke();
    this.points.forEach((p, i) => {
      const [sx, sy] = this.toScreen(p);
      const [r, g, b] = this.tfView.colorAt(p[0]);
      ctx.beginPath();
      ctx.arc(sx, sy, kPointRadius, 0, 2 * Math.PI);
      ctx.fillStyle = `rgb(${r * 255},${g * 255},${b * 255})`;
      ctx.fill();
      ctx.strokeStyle = i === this.dragging ? '#ff0' : '#fff';
      ctx.stroke();
    });
  }
}
