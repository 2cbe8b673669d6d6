// The Pathlines section (state.pathlines) and the Pathlines tab of the bottom panel: a second
// parallel-coordinates plot with one line per pathline of the window (GET /api/pathlines) whose
// brushes set pathlines.filters, and the count of lines shown.
import { fetchPathlines, type PathlineAttributes } from './api';
import type { FrameHeader } from './connection';
import { sampleColorMap } from './colormaps';
import { ParallelCoordinates, type AxisInfo } from './parcoords';
import { type Brush, type PathlineState } from './state';
import type { LegendEntry } from './context_panel';
import { pathlineAttribute, pathlineAttributeNames, pathlineVariablePrefixes } from './names';
import type { StateStore } from './store';
import { displayUnits } from './units';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;

// The seed kinds of docs/format.md (critical points of the seeding field), by their stored value.
const kSeedKind = pathlineAttribute('seedKind');
const kSeedKinds: Record<number, string> = { 0: 'minimum', 1: '1-saddle', 2: '2-saddle', 3: 'maximum', 4: 'multi-saddle' };

export interface PathlinePanelHost {
  commit(interactive: boolean): void;
  showError(message: string): void;
  // The lines' attributes arrived (the legend of an attribute colouring needs their range).
  linesLoaded(): void;
  // The line filters were brushed (the persistence diagram shows its threshold).
  filtersChanged(): void;
  // Shows a tab of the bottom panel (app.ts: the volume's plot, the pathlines', maps and sections).
  showTab(tab: 'volume' | 'pathlines'): void;
}

export interface PathlineCount {
  step: number;
  window: number;
  lines: number;
  visibleLines: number;
}

export class PathlinePanel {
  readonly pc: ParallelCoordinates;
  // What the count line says (the browser tests read it); null before the lines arrived.
  count: PathlineCount | null = null;
  private data: PathlineAttributes | null = null;
  private shown: { lines: number; visible: number } | null = null; // the last shown frame's count
  private key = '';
  private abort: AbortController | null = null;

  constructor(private readonly store: StateStore, private readonly host: PathlinePanelHost) {
    this.pc = new ParallelCoordinates($('plParcoords'), [], {
      onBrush: (brushes, interactive) => this.onLineFilter(brushes, interactive),
      alpha: 0.5, // hundreds of lines, not 100 000
    });
    this.setUpControls();
  }

  private get pathlines(): PathlineState | undefined {
    return this.store.state.pathlines;
  }

  // Loads the line attributes of the window shown when the lines are visible and (step, window) changed.
  refresh(): void {
    const pl = this.pathlines;
    if (!pl || !pl.visible) return;
    const key = `${this.store.state.step}/${pl.window}`;
    if (key === this.key) return;
    this.key = key;
    this.abort?.abort();
    const ctl = new AbortController();
    this.abort = ctl;
    fetchPathlines(this.store.state.step, pl.window, ctl.signal)
      .then((d) => {
        if (ctl.signal.aborted) return;
        this.data = d;
        this.pc.setAxes(this.axes());
        this.pc.setBrushes(pl.filters);
        this.pc.setData({ rows: d.lines, columns: d.columns, values: d.values });
        this.updateColorOptions();
        this.updateLineColors();
        this.updateLineCount();
        $('plEmpty').hidden = true;
        this.host.linesLoaded();
      })
      .catch((e) => { if (!ctl.signal.aborted) { this.key = ''; this.host.showError((e as Error).message); } });
  }

  // The volume's colour variable changed: the plot shows that variable's start and end values.
  variableChanged(): void {
    const d = this.data;
    if (!d) return;
    this.pc.setAxes(this.axes());
    this.pc.setData({ rows: d.lines, columns: d.columns, values: d.values });
  }

  // Axes of the pathline plot: the fixed attributes (seed, times, length, end reason, start and end
  // position), the start and end values of the volume's colour variable, and every filtered column
  // (all 30-odd columns would not fit). Ranges over the window's lines, widened to hold the filters.
  private axes(): AxisInfo[] {
    const d = this.data, pl = this.pathlines;
    if (!d || !pl) return [];
    const v = this.store.state.color.variable;
    const filtered = new Set(pl.filters.map((f) => f.name));
    const shown = (c: string) => pathlineAttributeNames.has(c) || pathlineVariablePrefixes.some((p) => c === p + v) ||
      filtered.has(c);
    return d.columns.flatMap((name, k) => {
      if (!shown(name)) return [];
      let lo = Infinity, hi = -Infinity;
      for (let i = 0; i < d.lines; i++) {
        const x = d.values[i * d.columns.length + k];
        if (Number.isFinite(x)) { lo = Math.min(lo, x); hi = Math.max(hi, x); }
      }
      if (!(lo <= hi)) { lo = 0; hi = 1; }
      for (const f of pl.filters) if (f.name === name) { lo = Math.min(lo, f.min); hi = Math.max(hi, f.max); }
      if (name === kSeedKind) return [{ name, units: '', min: -0.2, max: 4.2, categories: kSeedKinds }];
      return [{ name, units: d.units[k] ?? '', min: lo, max: hi > lo ? hi : lo + 1 }];
    });
  }

  private onLineFilter(filters: Brush[], interactive: boolean): void {
    const pl = this.pathlines;
    if (!pl) return;
    pl.filters = filters.map((f) => ({ name: f.name, min: f.min, max: f.max }));
    this.updateLineCount();
    this.host.commit(interactive); // restart class: no new lines, no tube rebuild
    if (!interactive) this.host.filtersChanged();
  }

  // state.pathlines.filters changed elsewhere (the persistence diagram's threshold): the count
  // follows at once, the plot's brushes (and an axis widened to hold them) once the drag ends.
  filtersChanged(interactive: boolean): void {
    const pl = this.pathlines, d = this.data;
    if (!pl) return;
    this.updateLineCount();
    if (interactive || !d) return;
    this.pc.setAxes(this.axes());
    this.pc.setBrushes(pl.filters);
    this.pc.setData({ rows: d.lines, columns: d.columns, values: d.values });
    this.updateLineColors();
  }

  // The largest value of a line attribute among the loaded lines, or null.
  columnMax(name: string): number | null {
    const d = this.data;
    const k = d ? d.columns.indexOf(name) : -1;
    if (!d || k < 0) return null;
    let hi = -Infinity;
    for (let i = 0; i < d.lines; i++) { const v = d.values[i * d.columns.length + k]; if (Number.isFinite(v)) hi = Math.max(hi, v); }
    return hi > -Infinity ? hi : null;
  }

  // A frame was shown: its header says how many lines the server drew (docs/protocol.md), by the
  // one rule of line filters and brushes (render/pathline_scene.h); the count line shows that.
  frameShown(header: FrameHeader): void {
    const shown = header.pathlines ?? null;
    if (shown?.lines === this.shown?.lines && shown?.visible === this.shown?.visible) return;
    this.shown = shown;
    this.updateLineCount();
  }

  updateLineCount(): void {
    const pl = this.pathlines, d = this.data;
    if (!pl || !d) {
      $('plCount').textContent = pl?.visible ? 'loading lines…' : '';
      this.count = null;
      return;
    }
    if (pl.visible && !this.shown) {
      $('plCount').textContent = 'counting lines…';
      this.count = null;
      return;
    }
    const visible = pl.visible && this.shown ? this.shown.visible : 0;
    this.count = { step: d.step, window: d.window, lines: d.lines, visibleLines: visible };
    $('plCount').textContent = pl.visible ? `${visible.toLocaleString()} of ${d.lines.toLocaleString()} lines shown` : 'hidden';
  }

  private updateColorOptions(): void {
    const sel = $<HTMLSelectElement>('plColorBy');
    const d = this.data;
    const want = ['age', ...(d ? d.columns : [])];
    if ([...sel.options].map((o) => o.value).join('|') !== want.join('|')) {
      sel.innerHTML = '';
      for (const c of want) sel.add(new Option(c, c));
    }
    sel.value = this.pathlines?.colorBy ?? 'age';
  }

  // Lines of the pathline plot coloured like the tubes: by injection time for age, else the attribute.
  private updateLineColors(): void {
    const d = this.data, pl = this.pathlines;
    if (!d || !pl) return;
    const name = pl.colorBy === 'age' ? 'injection time' : pl.colorBy;
    const k = d.columns.indexOf(name);
    if (k < 0) return;
    let lo = Infinity, hi = -Infinity;
    for (let i = 0; i < d.lines; i++) { const v = d.values[i * d.columns.length + k]; if (Number.isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); } }
    const map = pl.colorMap ?? (pl.colorBy === 'age' ? 'blue-white-red' : 'viridis');
    const palette = Array.from({ length: 64 }, (_, i) => {
      const [r, g, b] = sampleColorMap(map, pl.colorBy === 'age' ? 1 - i / 63 : i / 63); // old lines are red, as the tubes' age
      return `rgb(${Math.round(r * 255)},${Math.round(g * 255)},${Math.round(b * 255)})`;
    });
    this.pc.setColor((row) => palette[Math.min(63, Math.max(0, Math.round(((row[name] - lo) / (hi - lo || 1)) * 63))) || 0]);
  }

  // The legend of the tubes' colouring while they are shown: age (Myr since injection, blue at the
  // seed) over [0, window x step length] unless the state names a range, else the attribute over its
  // range among the loaded lines (as the renderer's PathlineScene::styleFor).
  legend(): LegendEntry | null {
    const pl = this.pathlines;
    if (!pl || !pl.visible) return null;
    const map = pl.colorMap ?? (pl.colorBy === 'age' ? 'blue-white-red' : 'viridis');
    if (pl.colorBy === 'age') {
      const steps = this.store.info.steps;
      const stepMyr = steps.length > 1 ? (steps[steps.length - 1].timeMyr - steps[0].timeMyr) / (steps.length - 1) : 0;
      const [lo, hi] = (pl.range as [number, number] | null) ?? [0, pl.window * stepMyr || 1];
      return { title: 'pathline age [Myr]', colorAt: (u) => sampleColorMap(map, u), valueAt: (u) => lo + u * (hi - lo) };
    }
    const d = this.data;
    const k = d ? d.columns.indexOf(pl.colorBy) : -1;
    let range = pl.range as [number, number] | null;
    if (!range && d && k >= 0) {
      let lo = Infinity, hi = -Infinity;
      for (let i = 0; i < d.lines; i++) { const v = d.values[i * d.columns.length + k]; if (Number.isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); } }
      range = lo <= hi ? [lo, hi] : null;
    }
    if (!range) return null;
    const units = d && k >= 0 ? displayUnits(d.units[k] ?? '') : '';
    const [lo, hi] = range;
    return { title: `pathlines: ${pl.colorBy}${units ? ` [${units}]` : ''}`, colorAt: (u) => sampleColorMap(map, u), valueAt: (u) => lo + u * (hi - lo) };
  }

  // The pathlines' plot shown or hidden (app.ts's showTab).
  setVisible(pathlines: boolean): void {
    $('plParcoords').hidden = !pathlines;
    // Until lines are shown the tab says how to get them instead of staying blank.
    $('plEmpty').hidden = !pathlines || Boolean(this.pathlines?.visible && this.data);
  }

  private setUpControls(): void {
    // A dataset without pathlines (a tomography model has no flow): the server says why.
    const absent = this.store.info.noPathlines;
    if (!this.pathlines || absent) {
      if (absent) $('plUnavailable').textContent = `No pathlines: ${absent}.`;
      $('plUnavailable').hidden = false;
      $('plControls').hidden = true;
      $('pcTabPathlines').hidden = true;
      return;
    }
    const change = (f: (pl: PathlineState) => void, reload = false) => () => {
      const pl = this.pathlines;
      if (!pl) return;
      f(pl);
      if (reload) this.key = '';
      this.updateLineCount();
      this.host.commit(false);
    };
    $('plVisible').addEventListener('change', change((pl) => {
      pl.visible = $<HTMLInputElement>('plVisible').checked;
      if (pl.visible) this.host.showTab('pathlines');
    }));
    $('plRadius').addEventListener('change', change((pl) => {
      const v = Number($<HTMLInputElement>('plRadius').value);
      if (v > 0) pl.radiusKm = v;
    }));
    $('plMinWidth').addEventListener('change', change((pl) => {
      const v = Number($<HTMLInputElement>('plMinWidth').value);
      if (v >= 0 && v <= 100) pl.minWidthPx = v;
    }));
    $('plWindow').addEventListener('change', change((pl) => {
      const v = Math.round(Number($<HTMLInputElement>('plWindow').value));
      if (v >= 1) pl.window = v;
    }));
    $('plAO').addEventListener('change', change((pl) => { pl.ambientOcclusion = $<HTMLInputElement>('plAO').checked; }));
    $('plFilterByBrushes').addEventListener('change', change((pl) => { pl.filterByBrushes = $<HTMLInputElement>('plFilterByBrushes').checked; }));
    $('plColorBy').addEventListener('change', change((pl) => {
      pl.colorBy = $<HTMLSelectElement>('plColorBy').value;
      pl.range = null;
      pl.colorMap = pl.colorBy === 'age' ? 'blue-white-red' : 'viridis';
      this.updateLineColors();
    }));
    $('plClearFilters').addEventListener('click', change((pl) => {
      pl.filters = [];
      this.pc.setBrushes([]);
      this.host.filtersChanged();
    }));
  }

  // Puts state.pathlines into the controls (after load, preset, URL).
  sync(): void {
    const pl = this.pathlines;
    if (!pl) return;
    $<HTMLInputElement>('plVisible').checked = pl.visible;
    $<HTMLInputElement>('plRadius').value = String(pl.radiusKm);
    $<HTMLInputElement>('plMinWidth').value = String(pl.minWidthPx);
    $<HTMLInputElement>('plWindow').value = String(pl.window);
    $<HTMLInputElement>('plAO').checked = pl.ambientOcclusion;
    $<HTMLInputElement>('plFilterByBrushes').checked = pl.filterByBrushes;
    this.updateColorOptions();
    if (this.data) this.pc.setBrushes(pl.filters);
    this.updateLineCount();
  }
}
