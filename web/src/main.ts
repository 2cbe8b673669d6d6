// The RayPC browser UI: wires the 3D view (frames + image warping), camera interaction, the
// transfer-function editor, time, parallel coordinates, save/load/share and the status line to
// one render state that is sent whole to the server (docs/protocol.md, docs/state.md).
//
// Cost classes (docs/state.md): camera, transfer function and brushes restart progressive passes;
// step and level reload data. While the user drags, states go out as `interactive` (one pass at
// the interactive level), at most one per display frame and only when the server has answered
// the previous one or 120 ms passed; on release the final state asks for all passes.
import {
  fetchHistogram, fetchInfo, fetchPathlines, fetchPresets, fetchSample, postScreenshot, postSelection, postStats,
  type Histogram, type Info, type PathlineAttributes, type Preset, type Selection, type SelectionOverTime,
} from './api';
import { CameraFrame } from './camera';
import { centredMaps, sampleColorMap } from './colormaps';
import { Connection, type Frame, type FrameHeader } from './connection';
import { ParallelCoordinates, type AxisInfo } from './parcoords';
import { cloneState, encodeStateForUrl, normaliseState, stateFromHash, type Brush, type PathlineState, type RenderState } from './state';
import { drawProfilePlot, drawTimePlot } from './stats_plot';
import { TfEditor } from './tf_editor';
import { View3D } from './view';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;
const kOrbitDegPerPx = 0.35;
const kMinDistanceKm = 500, kMaxDistanceKm = 500000;
// How long the full redraw of the parallel coordinates after a brush release waits at most for the
// still frame it asked for (ParcoordsOptions.afterFrame).
const kAfterFrameMs = 1000;

interface Debug {
  info: Info;
  state(): RenderState;
  setState(s: unknown): void;
  view: View3D['stats'];
  framesReceived: number;
  headers: FrameHeader[];
  lastShownId: number;
  lastSentId: number;
  statesSent: number;
  latencies: { id: number; interactive: boolean; firstFrameMs: number; shownMs: number }[];
  selection: Selection | null;
  errors: string[];
  playing: boolean;
  parcoords: ParallelCoordinates;
  sampleStep: number;
  // Test hooks: what was sent and received when, warps drawn while a newer state was pending,
  // and holding incoming frames back (to look at a warped view deterministically).
  sentLog: { id: number; t: number; step: number; interactive: boolean; brushes: Brush[] }[];
  frameLog: { id: number; step: number; pass: number; t: number }[];
  warpedWhileWaiting: number;
  // Deferred work (the full line redraw after a brush release): the state it waited for, whether
  // that state's frame was on screen when it ran (false: it ran on the timeout or was superseded).
  afterFrames: { id: number; shownId: number; afterShown: boolean }[];
  holdFrames: boolean;
  releaseFrames(): void;
  presets: Preset[];
  applyPreset(name: string): void;
  stats: SelectionOverTime | null;
  statsRequests: number;
  pathlines: { step: number; window: number; lines: number; visibleLines: number } | null;
  plParcoords: ParallelCoordinates;
}

class App {
  state: RenderState;
  private readonly defaults: RenderState;
  private readonly view: View3D;
  private readonly connection: Connection;
  private readonly tf: TfEditor;
  private readonly pc: ParallelCoordinates;
  private autoFitImage = true;
  private drawPending = false;
  private interactivePending = false;
  private lastSendTime = 0;
  private sendTimes = new Map<number, { t: number; interactive: boolean; first?: number }>();
  private finalTimer = 0;
  private playing = false;
  private lastAdvance = 0;
  private advanceTimer = 0;
  private stepHistogram: Histogram | null = null;
  private selection: Selection | null = null;
  private selectionAbort: AbortController | null = null;
  private sampleStep = -1;
  private sampleLoading = false;
  private lastSampleLoad = 0;
  private lastHeader: FrameHeader | null = null;
  private lastDrawKind = 'none';
  private errorTimer = 0;
  private heldFrames: Frame[] = [];
  private presets: Preset[] = [];
  private stats: SelectionOverTime | null = null;
  private statsKey = '';
  private statsAbort: AbortController | null = null;
  private statsTimer = 0;
  private readonly plPc: ParallelCoordinates;
  private plData: PathlineAttributes | null = null;
  private plKey = '';
  private plAbort: AbortController | null = null;
  readonly debug: Debug;

  constructor(readonly info: Info) {
    this.defaults = normaliseState(info.defaultState, info.defaultState);
    this.state = cloneState(this.defaults);
    try {
      const fromUrl = stateFromHash(location.hash);
      if (fromUrl) {
        this.state = normaliseState(fromUrl, this.defaults);
        this.autoFitImage = false;
      }
    } catch (e) {
      this.showError(`state in the URL: ${(e as Error).message}`);
    }

    this.view = new View3D($<HTMLCanvasElement>('view3d'));
    this.tf = new TfEditor($<HTMLCanvasElement>('tf'), {
      onChange: (opacity, interactive) => {
        this.state.color.opacity = opacity;
        this.commit(interactive);
      },
    });
    this.pc = new ParallelCoordinates($('parcoords'), this.axes(), {
      onBrush: (brushes, interactive) => this.onBrush(brushes, interactive),
      afterFrame: (draw) => this.afterFrameShown(draw),
    });
    this.plPc = new ParallelCoordinates($('plParcoords'), [], {
      onBrush: (brushes, interactive) => this.onLineFilter(brushes, interactive),
      alpha: 0.5, // hundreds of lines, not 100 000
    });
    this.connection = new Connection({
      onFrame: (f) => this.onFrame(f),
      onError: (m, id) => this.showError(id !== undefined ? `state ${id}: ${m}` : m),
      onStatus: (t) => this.setStatusNote(t),
    });
    this.debug = {
      info,
      state: () => cloneState(this.state),
      setState: (s) => this.loadState(s),
      view: this.view.stats,
      framesReceived: 0,
      headers: [],
      lastShownId: 0,
      lastSentId: 0,
      statesSent: 0,
      latencies: [],
      selection: null,
      errors: [],
      playing: false,
      parcoords: this.pc,
      sampleStep: -1,
      sentLog: [],
      frameLog: [],
      warpedWhileWaiting: 0,
      afterFrames: [],
      holdFrames: false,
      releaseFrames: () => {
        this.debug.holdFrames = false;
        const held = this.heldFrames;
        this.heldFrames = [];
        for (const f of held) this.onFrame(f);
      },
      presets: [],
      applyPreset: (name) => {
        const p = this.presets.find((x) => x.name === name);
        if (!p) throw new Error(`no preset '${name}'`);
        this.applyPreset(p);
      },
      stats: null,
      statsRequests: 0,
      pathlines: null,
      plParcoords: this.plPc,
    };
    (window as unknown as { __raypc: Debug }).__raypc = this.debug;

    this.setUpControls();
    this.setUpCamera();
    new ResizeObserver(() => this.onResize()).observe($('viewPanel'));
    this.onResize();
    this.syncControls();
    this.loadSample();
    this.loadHistogram();
    this.loadPresets();
    this.commit(false);
  }

  // ---- state -------------------------------------------------------------------------------

  private axes(): AxisInfo[] {
    const { columns, units } = this.info.sample;
    return columns.map((name, i) => {
      const v = this.info.variables.find((x) => x.name === name);
      const c = this.info.coordinates.find((x) => x.name === name);
      const r = v ?? c;
      return { name, units: units[i] ?? r?.units ?? '', min: r?.min ?? 0, max: r?.max ?? 1 };
    });
  }

  private variableInfo(name = this.state.color.variable) {
    return this.info.variables.find((v) => v.name === name) ?? this.info.variables[0];
  }

  // The colour range in force: the state's, or the global range (symmetric for centred maps).
  effectiveRange(): [number, number] {
    if (this.state.color.range) return this.state.color.range;
    const v = this.variableInfo();
    if (centredMaps.has(this.state.color.colorMap)) {
      const m = Math.max(Math.abs(v.min), Math.abs(v.max)) || 1;
      return [-m, m];
    }
    return v.max > v.min ? [v.min, v.max] : [v.min, v.min + 1];
  }

  loadState(s: unknown): void {
    const prev = this.state;
    this.state = normaliseState(s, this.defaults);
    this.autoFitImage = false;
    this.syncControls();
    if (prev.step !== this.state.step) {
      this.loadSample();
      this.loadHistogram();
    } else if (prev.color.variable !== this.state.color.variable) this.loadHistogram();
    this.updateLineColors();
    this.commit(false);
  }

  // ---- presets (GET /api/presets) ------------------------------------------------------------

  private loadPresets(): void {
    fetchPresets()
      .then((presets) => {
        this.presets = presets;
        this.debug.presets = presets;
        const box = $('presets');
        box.innerHTML = '';
        if (!presets.length) box.textContent = 'none (no examples directory)';
        for (const p of presets) {
          const b = document.createElement('button');
          b.textContent = p.title;
          b.title = `${p.name}.json`;
          b.dataset.preset = p.name;
          b.addEventListener('click', () => this.applyPreset(p));
          box.appendChild(b);
        }
      })
      .catch((e) => this.showError((e as Error).message));
  }

  // A preset replaces colours, opacity, brushes, camera, shading and core; the current step (presets
  // are written for one time but the criteria apply to every step, and the dataset may have fewer
  // steps), the image size (it follows the window), the level, and the pathlines when the preset has
  // none (version 1) stay as they are.
  applyPreset(p: Preset): void {
    try {
      const doc = { ...(p.state as Record<string, unknown>) };
      doc.step = this.state.step;
      doc.image = { ...this.state.image };
      doc.level = this.state.level;
      if (this.state.pathlines && !('pathlines' in doc)) {
        doc.pathlines = cloneState(this.state).pathlines;
        doc.version = this.state.version;
      }
      const fit = this.autoFitImage;
      this.loadState(doc);
      this.autoFitImage = fit;
      for (const b of document.querySelectorAll<HTMLButtonElement>('#presets button'))
        b.classList.toggle('active', b.dataset.preset === p.name);
      this.setStatusNote(`preset ${p.title}`);
    } catch (e) {
      this.showError(`preset ${p.name}: ${(e as Error).message}`);
    }
  }

  // Sends the state. Interactive states are coalesced to one per display frame.
  commit(interactive: boolean): void {
    this.requestDraw();
    if (interactive) {
      this.interactivePending = true;
      this.pumpInteractive();
      return;
    }
    this.interactivePending = false;
    this.send(false);
    history.replaceState(null, '', `${location.pathname}${location.search}#state=${encodeStateForUrl(this.state)}`);
    this.afterFrameShown(() => {
      this.refreshSelection();
      this.refreshStats();
    });
    this.refreshPathlines();
  }

  private pumpInteractive(): void {
    if (!this.interactivePending) return;
    const now = performance.now();
    if (this.connection.caughtUp || now - this.lastSendTime > 120) {
      this.interactivePending = false;
      this.send(true);
    } else {
      requestAnimationFrame(() => this.pumpInteractive());
    }
  }

  private send(interactive: boolean): void {
    const id = this.connection.send(cloneState(this.state), interactive);
    this.lastSendTime = performance.now();
    this.sendTimes.set(id, { t: this.lastSendTime, interactive });
    if (this.sendTimes.size > 200) this.sendTimes.delete(this.sendTimes.keys().next().value as number);
    this.debug.lastSentId = id;
    this.debug.statesSent++;
    this.debug.sentLog.push({ id, t: this.lastSendTime, step: this.state.step, interactive, brushes: this.state.brushes.map((b) => ({ ...b })) });
    if (this.debug.sentLog.length > 500) this.debug.sentLog.shift();
  }

  // ---- frames ------------------------------------------------------------------------------

  private onFrame(frame: Frame): void {
    if (this.debug.holdFrames) {
      this.heldFrames.push(frame);
      return;
    }
    const h = frame.header;
    this.debug.framesReceived++;
    this.debug.frameLog.push({ id: h.id, step: h.step, pass: h.pass, t: frame.receivedAt });
    if (this.debug.frameLog.length > 500) this.debug.frameLog.shift();
    this.debug.headers.push(h);
    if (this.debug.headers.length > 100) this.debug.headers.shift();
    const sent = this.sendTimes.get(h.id);
    if (sent && sent.first === undefined) sent.first = frame.receivedAt - sent.t;
    if (h.id < this.debug.lastShownId) return; // a pass of an older state that was still in flight
    this.lastHeader = h;
    // Interactive frames carry the selection on the level they rendered: quick feedback while
    // brushing; final states get the exact volume from POST /api/selection (refreshSelection).
    if (h.selection && h.interactive && this.state.brushes.length) this.setSelection({ ...h.selection, step: h.step });
    void this.view.setFrame(frame).then(() => {
      if (h.id >= this.debug.lastShownId) this.debug.lastShownId = h.id;
      if (sent && h.pass === 1) {
        this.debug.latencies.push({ id: h.id, interactive: sent.interactive, firstFrameMs: sent.first ?? NaN, shownMs: performance.now() - sent.t });
        if (this.debug.latencies.length > 200) this.debug.latencies.shift();
      }
      this.drawNow(); // at once, not in the next animation frame (which may queue behind other work)
      this.updateStatus();
      if (this.afterFrame && h.id >= this.afterFrame.id) this.runAfterFrame();
    });
    if (this.playing) this.maybeAdvance();
  }

  requestDraw(): void {
    if (this.drawPending) return;
    this.drawPending = true;
    requestAnimationFrame(() => {
      if (this.drawPending) this.drawNow();
    });
  }

  private drawNow(): void {
    this.drawPending = false;
    const bg = (this.state.background as [number, number, number] | undefined) ?? [0, 0, 0];
    this.lastDrawKind = this.view.draw(this.state.camera, this.state.image.width, this.state.image.height, bg);
    if (this.lastDrawKind === 'warped' && this.debug.lastShownId < this.debug.lastSentId) this.debug.warpedWhileWaiting++;
  }

  // ---- camera ------------------------------------------------------------------------------

  private setUpCamera(): void {
    const canvas = this.view.canvas;
    const pointers = new Map<number, { x: number; y: number }>();
    let pan = false;
    const cameraChanged = () => this.commit(true);
    const panBy = (dxPx: number, dyPx: number) => {
      const cam = this.state.camera;
      const frame = new CameraFrame(cam, this.state.image.width, this.state.image.height);
      const kmPerPx = (2 * cam.distanceKm * frame.tanHalfFovY) / Math.max(1, canvas.clientHeight);
      const t = cam.targetKm;
      for (let k = 0; k < 3; k++) t[k] = t[k] - frame.right[k] * dxPx * kmPerPx + frame.up[k] * dyPx * kmPerPx;
    };
    const zoomBy = (factor: number) => {
      const cam = this.state.camera;
      cam.distanceKm = Math.min(kMaxDistanceKm, Math.max(kMinDistanceKm, cam.distanceKm * factor));
    };
    const spread = () => {
      const p = [...pointers.values()];
      return Math.hypot(p[0].x - p[1].x, p[0].y - p[1].y);
    };
    const centroid = () => {
      const p = [...pointers.values()];
      return { x: p.reduce((s, q) => s + q.x, 0) / p.length, y: p.reduce((s, q) => s + q.y, 0) / p.length };
    };
    canvas.addEventListener('contextmenu', (e) => e.preventDefault());
    canvas.addEventListener('pointerdown', (e) => {
      canvas.focus();
      canvas.setPointerCapture(e.pointerId);
      pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
      pan = e.button === 2 || e.button === 1 || e.shiftKey || e.ctrlKey;
    });
    canvas.addEventListener('pointermove', (e) => {
      const prev = pointers.get(e.pointerId);
      if (!prev) return;
      if (pointers.size === 1) {
        const dx = e.clientX - prev.x, dy = e.clientY - prev.y;
        if (pan) panBy(dx, dy);
        else {
          const cam = this.state.camera;
          cam.azimuthDeg = (((cam.azimuthDeg - dx * kOrbitDegPerPx) % 360) + 360) % 360;
          cam.elevationDeg = Math.min(89.5, Math.max(-89.5, cam.elevationDeg + dy * kOrbitDegPerPx));
        }
        pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
      } else if (pointers.size === 2) {
        const s0 = spread(), c0 = centroid();
        pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
        const s1 = spread(), c1 = centroid();
        if (s1 > 0 && s0 > 0) zoomBy(s0 / s1);
        panBy(c1.x - c0.x, c1.y - c0.y);
      } else return;
      cameraChanged();
    });
    const up = (e: PointerEvent) => {
      if (!pointers.delete(e.pointerId)) return;
      if (pointers.size === 0) this.commit(false);
    };
    canvas.addEventListener('pointerup', up);
    canvas.addEventListener('pointercancel', up);
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      zoomBy(Math.exp(e.deltaY * (e.deltaMode === 1 ? 0.05 : 0.0015)));
      cameraChanged();
      clearTimeout(this.finalTimer);
      this.finalTimer = window.setTimeout(() => this.commit(false), 250);
    }, { passive: false });
  }

  private onResize(): void {
    const canvas = this.view.canvas;
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(canvas.clientWidth * dpr)), h = Math.max(1, Math.round(canvas.clientHeight * dpr));
    if (canvas.width !== w || canvas.height !== h) {
      canvas.width = w;
      canvas.height = h;
    }
    if (this.autoFitImage) {
      const changed = this.fitImage();
      if (changed) this.commit(false);
    }
    this.requestDraw();
  }

  // Image size from the resolution (longer side) and the view's aspect.
  private fitImage(): boolean {
    const res = Number($<HTMLSelectElement>('resolution').value) || 512;
    const cw = this.view.canvas.clientWidth || 1, ch = this.view.canvas.clientHeight || 1;
    const w = cw >= ch ? res : Math.max(16, Math.round((res * cw) / ch));
    const h = cw >= ch ? Math.max(16, Math.round((res * ch) / cw)) : res;
    if (w === this.state.image.width && h === this.state.image.height) return false;
    this.state.image = { width: w, height: h };
    return true;
  }

  // Work that waits until the frame of the state sent last is on screen (or kAfterFrameMs passed),
  // so that it does not compete with that frame for the CPU (the browser and the server share it):
  // the full line redraw after a brush release, the exact selection and the statistics over time.
  private afterFrame: { id: number; run: (() => void)[]; timer: number } | null = null;

  private afterFrameShown(run: () => void): void {
    const id = this.debug.lastSentId;
    if (this.afterFrame && this.afterFrame.id !== id) this.runAfterFrame(); // older work runs now
    if (!this.afterFrame) this.afterFrame = { id, run: [], timer: window.setTimeout(() => this.runAfterFrame(), kAfterFrameMs) };
    this.afterFrame.run.push(run);
  }

  private runAfterFrame(): void {
    const pending = this.afterFrame;
    if (!pending) return;
    this.afterFrame = null;
    clearTimeout(pending.timer);
    const shownId = this.debug.lastShownId;
    this.debug.afterFrames.push({ id: pending.id, shownId, afterShown: shownId >= pending.id });
    if (this.debug.afterFrames.length > 50) this.debug.afterFrames.shift();
    for (const run of pending.run) run();
  }

  // ---- brushes, selection, sample ---------------------------------------------------------

  private onBrush(brushes: Brush[], interactive: boolean): void {
    this.state.brushes = brushes;
    this.commit(interactive);
    this.updateSelectionText();
    this.updateLineCount();
  }

  // ---- selection over time (POST /api/stats) --------------------------------------------------

  // Asks for the statistics when the brushes, the step or the level asked for changed (debounced;
  // not while playing, when only the current-step mark moves).
  private refreshStats(): void {
    const exact = $<HTMLInputElement>('statsExact').checked;
    if (!this.state.brushes.length) {
      this.statsAbort?.abort();
      this.stats = null;
      this.debug.stats = null;
      this.statsKey = '';
      $('statsNote').textContent = 'Brush an axis to see the selected volume over time.';
      for (const id of ['statsTime', 'statsProfile']) $(id).innerHTML = '';
      return;
    }
    const key = JSON.stringify([this.state.brushes, this.state.step, exact]);
    if (this.stats) drawTimePlot($('statsTime') as unknown as SVGSVGElement, this.stats, this.state.step);
    if (key === this.statsKey || this.playing) return;
    clearTimeout(this.statsTimer);
    this.statsTimer = window.setTimeout(() => {
      this.statsAbort?.abort();
      const ctl = new AbortController();
      this.statsAbort = ctl;
      this.statsKey = key;
      this.debug.statsRequests++;
      $('statsNote').textContent = 'computing…';
      postStats(cloneState(this.state), exact ? 0 : undefined, ctl.signal)
        .then((st) => {
          if (ctl.signal.aborted) return;
          this.stats = st;
          this.debug.stats = st;
          const cur = st.steps.find((x) => x.step === this.state.step);
          $('statsNote').textContent = `level ${st.level}${st.level === 0 ? ' (exact)' : ''} · now ${cur ? (cur.fractionOfMantle * 100).toFixed(2) : '?'} % · ` +
            `range ${(Math.min(...st.steps.map((x) => x.fractionOfMantle)) * 100).toFixed(2)}–${(Math.max(...st.steps.map((x) => x.fractionOfMantle)) * 100).toFixed(2)} %`;
          drawTimePlot($('statsTime') as unknown as SVGSVGElement, st, this.state.step);
          drawProfilePlot($('statsProfile') as unknown as SVGSVGElement, st);
        })
        .catch((e) => { if (!ctl.signal.aborted) { this.statsKey = ''; this.showError((e as Error).message); } });
    }, 250);
  }

  // ---- pathlines (GET /api/pathlines, state.pathlines) ----------------------------------------

  private get pathlines(): PathlineState | undefined {
    return this.state.pathlines;
  }

  // Loads the line attributes of the window shown when the lines are visible and (step, window) changed.
  private refreshPathlines(): void {
    const pl = this.pathlines;
    if (!pl || !pl.visible) return;
    const key = `${this.state.step}/${pl.window}`;
    if (key === this.plKey) return;
    this.plKey = key;
    this.plAbort?.abort();
    const ctl = new AbortController();
    this.plAbort = ctl;
    const step = this.state.step, window = pl.window;
    fetchPathlines(step, window, ctl.signal)
      .then((d) => {
        if (ctl.signal.aborted) return;
        this.plData = d;
        const axes = this.pathlineAxes();
        this.plPc.setAxes(axes);
        this.plPc.setBrushes(pl.filters);
        this.plPc.setData({ rows: d.lines, columns: d.columns, values: d.values });
        this.updatePlColorOptions();
        this.updatePlLineColors();
        this.updateLineCount();
      })
      .catch((e) => { if (!ctl.signal.aborted) { this.plKey = ''; this.showError((e as Error).message); } });
  }

  // Axes of the pathline plot: the fixed attributes (seed, times, length, end reason, start and end
  // position), the start and end values of the volume's colour variable, and every filtered column
  // (all 30-odd columns would not fit). Ranges over the window's lines, widened to hold the filters.
  private pathlineAxes(): AxisInfo[] {
    const d = this.plData, pl = this.pathlines;
    if (!d || !pl) return [];
    const v = this.state.color.variable;
    const filtered = new Set(pl.filters.map((f) => f.name));
    const shown = (c: string) => !/^(start|end) /.test(c) || /^(start|end) (lat|lon|radius)$/.test(c) ||
      c === `start ${v}` || c === `end ${v}` || filtered.has(c);
    return d.columns.flatMap((name, k) => {
      if (!shown(name)) return [];
      let lo = Infinity, hi = -Infinity;
      for (let i = 0; i < d.lines; i++) {
        const x = d.values[i * d.columns.length + k];
        if (Number.isFinite(x)) { lo = Math.min(lo, x); hi = Math.max(hi, x); }
      }
      if (!(lo <= hi)) { lo = 0; hi = 1; }
      for (const f of pl.filters) if (f.name === name) { lo = Math.min(lo, f.min); hi = Math.max(hi, f.max); }
      return [{ name, units: d.units[k] ?? '', min: lo, max: hi > lo ? hi : lo + 1 }];
    });
  }

  private onLineFilter(filters: Brush[], interactive: boolean): void {
    const pl = this.pathlines;
    if (!pl) return;
    pl.filters = filters.map((f) => ({ name: f.name, min: f.min, max: f.max }));
    this.updateLineCount();
    this.commit(interactive); // restart class: no new lines, no tube rebuild
  }

  // How many lines of the window pass the line filters and, with filterByBrushes, start inside the
  // volume brushes (variables by their "start <name>" column; coordinates from the start position).
  private countVisibleLines(): number {
    const d = this.plData, pl = this.pathlines;
    if (!d || !pl) return 0;
    const nc = d.columns.length, col = (n: string) => d.columns.indexOf(n);
    const tests: ((row: number) => boolean)[] = [];
    for (const f of pl.filters) {
      const k = col(f.name);
      if (k >= 0) tests.push((i) => { const v = d.values[i * nc + k]; return v >= f.min && v <= f.max; });
    }
    if (pl.filterByBrushes) {
      const kLat = col('start lat'), kLon = col('start lon'), kR = col('start radius');
      for (const b of this.state.brushes) {
        const inside = (v: number) => v >= b.min && v <= b.max;
        const k = col(`start ${b.name}`);
        if (k >= 0) { tests.push((i) => inside(d.values[i * nc + k])); continue; }
        const pos = (i: number) => {
          const lat = (d.values[i * nc + kLat] * Math.PI) / 180, lon = (d.values[i * nc + kLon] * Math.PI) / 180, r = d.values[i * nc + kR];
          return { lat, lon, r };
        };
        const coordinate: Record<string, (i: number) => number> = {
          lat: (i) => d.values[i * nc + kLat],
          lon: (i) => d.values[i * nc + kLon],
          radius: (i) => d.values[i * nc + kR],
          depth: (i) => 6371 - d.values[i * nc + kR],
          x: (i) => { const p = pos(i); return p.r * Math.cos(p.lat) * Math.cos(p.lon); },
          y: (i) => { const p = pos(i); return p.r * Math.cos(p.lat) * Math.sin(p.lon); },
          z: (i) => { const p = pos(i); return p.r * Math.sin(p.lat); },
        };
        const get = coordinate[b.name];
        if (get && kLat >= 0 && kLon >= 0 && kR >= 0) tests.push((i) => inside(get(i)));
      }
    }
    let n = 0;
    for (let i = 0; i < d.lines; i++) if (tests.every((t) => t(i))) n++;
    return n;
  }

  private updateLineCount(): void {
    const pl = this.pathlines, d = this.plData;
    if (!pl || !d) {
      $('plCount').textContent = pl?.visible ? 'loading lines…' : '';
      this.debug.pathlines = null;
      return;
    }
    const visible = pl.visible ? this.countVisibleLines() : 0;
    this.debug.pathlines = { step: d.step, window: d.window, lines: d.lines, visibleLines: visible };
    $('plCount').textContent = pl.visible ? `${visible.toLocaleString()} of ${d.lines.toLocaleString()} lines shown` : 'hidden';
  }

  private updatePlColorOptions(): void {
    const sel = $<HTMLSelectElement>('plColorBy');
    const d = this.plData;
    const want = ['age', ...(d ? d.columns : [])];
    if ([...sel.options].map((o) => o.value).join('|') !== want.join('|')) {
      sel.innerHTML = '';
      for (const c of want) sel.add(new Option(c, c));
    }
    sel.value = this.pathlines?.colorBy ?? 'age';
  }

  // Lines of the pathline plot coloured like the tubes: by injection time for age, else the attribute.
  private updatePlLineColors(): void {
    const d = this.plData, pl = this.pathlines;
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
    this.plPc.setColor((row) => palette[Math.min(63, Math.max(0, Math.round(((row[name] - lo) / (hi - lo || 1)) * 63))) || 0]);
  }

  private showPcTab(pathlines: boolean): void {
    $('parcoords').hidden = pathlines;
    $('plParcoords').hidden = !pathlines;
    $('pcTabVolume').classList.toggle('active', !pathlines);
    $('pcTabPathlines').classList.toggle('active', pathlines);
  }

  private setUpPathlineControls(): void {
    if (!this.state.pathlines) {
      $('plUnavailable').hidden = false;
      $('plControls').hidden = true;
      $('pcTabPathlines').hidden = true;
      return;
    }
    const change = (f: (pl: PathlineState) => void, reload = false) => () => {
      const pl = this.pathlines;
      if (!pl) return;
      f(pl);
      if (reload) this.plKey = '';
      this.updateLineCount();
      this.commit(false);
    };
    $('plVisible').addEventListener('change', change((pl) => {
      pl.visible = $<HTMLInputElement>('plVisible').checked;
      if (pl.visible) this.showPcTab(true);
    }));
    $('plRadius').addEventListener('change', change((pl) => {
      const v = Number($<HTMLInputElement>('plRadius').value);
      if (v > 0) pl.radiusKm = v;
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
      this.updatePlLineColors();
    }));
    $('plClearFilters').addEventListener('click', change((pl) => {
      pl.filters = [];
      this.plPc.setBrushes([]);
    }));
    $('pcTabVolume').addEventListener('click', () => this.showPcTab(false));
    $('pcTabPathlines').addEventListener('click', () => this.showPcTab(true));
  }

  private syncPathlineControls(): void {
    const pl = this.pathlines;
    if (!pl) return;
    $<HTMLInputElement>('plVisible').checked = pl.visible;
    $<HTMLInputElement>('plRadius').value = String(pl.radiusKm);
    $<HTMLInputElement>('plWindow').value = String(pl.window);
    $<HTMLInputElement>('plAO').checked = pl.ambientOcclusion;
    $<HTMLInputElement>('plFilterByBrushes').checked = pl.filterByBrushes;
    this.updatePlColorOptions();
    if (this.plData) this.plPc.setBrushes(pl.filters);
    this.updateLineCount();
  }

  private refreshSelection(): void {
    this.selectionAbort?.abort();
    if (!this.state.brushes.length) {
      this.setSelection({ fractionOfMantle: 1, volumeKm3: NaN, step: this.state.step });
      return;
    }
    const ctl = new AbortController();
    this.selectionAbort = ctl;
    postSelection(this.state, ctl.signal)
      .then((s) => { if (!ctl.signal.aborted) this.setSelection(s); })
      .catch((e) => { if (!ctl.signal.aborted) this.showError((e as Error).message); });
  }

  private setSelection(s: Selection): void {
    this.selection = s;
    this.debug.selection = s;
    this.updateSelectionText();
    this.updateStatus();
  }

  private updateSelectionText(): void {
    const el = $('selection');
    if (!this.state.brushes.length) {
      el.textContent = 'no brushes: the whole mantle';
      return;
    }
    const s = this.selection;
    const ranges = this.state.brushes.map((b) => {
      const a = this.axes().find((x) => x.name === b.name);
      return `${b.name} ${fmt(b.min)} … ${fmt(b.max)}${a?.units ? ' ' + a.units : ''}`;
    });
    el.innerHTML = '';
    const head = document.createElement('div');
    head.textContent = s && Number.isFinite(s.fractionOfMantle)
      ? `${(s.fractionOfMantle * 100).toFixed(2)} % of the mantle${Number.isFinite(s.volumeKm3) ? `, ${s.volumeKm3.toExponential(3)} km³` : ''}`
      : 'computing…';
    head.id = 'selectionValue';
    el.appendChild(head);
    for (const r of ranges) {
      const d = document.createElement('div');
      d.textContent = r;
      d.style.color = '#99a';
      el.appendChild(d);
    }
  }

  private loadSample(): void {
    if (this.sampleLoading) return;
    const step = this.state.step;
    if (step === this.sampleStep) return;
    this.sampleLoading = true;
    this.lastSampleLoad = performance.now();
    fetchSample(step, this.info.sample.columns)
      .then((sample) => {
        this.pc.setData(sample);
        this.sampleStep = step;
        this.debug.sampleStep = step;
        this.updateLineColors();
      })
      .catch((e) => this.showError((e as Error).message))
      .finally(() => {
        this.sampleLoading = false;
        if (this.state.step !== this.sampleStep && !this.playing) this.loadSample();
      });
  }

  private updateLineColors(): void {
    const name = this.state.color.variable, map = this.state.color.colorMap;
    const [lo, hi] = this.effectiveRange();
    const palette = Array.from({ length: 64 }, (_, i) => {
      const [r, g, b] = sampleColorMap(map, i / 63);
      return `rgb(${Math.round(r * 255)},${Math.round(g * 255)},${Math.round(b * 255)})`;
    });
    this.pc.setColor((row) => palette[Math.min(63, Math.max(0, Math.round(((row[name] - lo) / (hi - lo)) * 63))) || 0]);
  }

  // ---- transfer function --------------------------------------------------------------------

  private loadHistogram(): void {
    const step = this.state.step, name = this.state.color.variable;
    fetchHistogram(step, name)
      .then((h) => {
        if (this.state.step === step && this.state.color.variable === name) {
          this.stepHistogram = h;
          this.updateTf();
        }
      })
      .catch((e) => this.showError((e as Error).message));
  }

  private updateTf(): void {
    const v = this.variableInfo();
    const hist = [];
    if (this.stepHistogram && this.stepHistogram.name === v.name) hist.push({ data: this.stepHistogram, style: 'bars' as const });
    hist.push({ data: v, style: 'line' as const });
    this.tf.set(this.state.color.opacity, this.effectiveRange(), this.state.color.colorMap, v.units, hist);
    const [lo, hi] = this.effectiveRange();
    $<HTMLInputElement>('rangeMin').value = String(+lo.toPrecision(6));
    $<HTMLInputElement>('rangeMax').value = String(+hi.toPrecision(6));
  }

  // ---- time --------------------------------------------------------------------------------

  private setStep(step: number, interactive: boolean): void {
    this.state.step = step;
    this.updateStepLabel();
    this.commit(interactive);
    if (!interactive) {
      this.loadHistogram();
      this.loadSample();
    } else if (performance.now() - this.lastSampleLoad > 1000) this.loadSample();
  }

  private togglePlay(): void {
    this.playing = !this.playing;
    this.debug.playing = this.playing;
    $('play').textContent = this.playing ? '❚❚' : '▶';
    if (this.playing) {
      this.lastAdvance = 0;
      this.maybeAdvance();
    } else {
      clearTimeout(this.advanceTimer);
      this.setStep(this.state.step, false);
    }
  }

  // Advances one step once the frame for the current step has arrived and the speed allows.
  private maybeAdvance(): void {
    if (!this.playing || !this.connection.caughtUp) return;
    const fps = Number($<HTMLSelectElement>('fps').value) || 2;
    const wait = 1000 / fps - (performance.now() - this.lastAdvance);
    clearTimeout(this.advanceTimer);
    if (wait > 0) {
      this.advanceTimer = window.setTimeout(() => this.maybeAdvance(), wait);
      return;
    }
    this.lastAdvance = performance.now();
    const n = this.info.steps.length;
    this.setStep((this.state.step + 1) % n, true);
    $<HTMLInputElement>('step').value = String(this.state.step);
  }

  private updateStepLabel(): void {
    const s = this.info.steps[this.state.step];
    $('stepLabel').textContent = s ? `step ${s.index + 1} / ${this.info.steps.length} · ${s.timeMyr.toFixed(1)} Myr` : '';
  }

  // ---- controls ----------------------------------------------------------------------------

  private setUpControls(): void {
    const info = this.info;
    this.setUpPathlineControls();
    $('statsExact').addEventListener('change', () => this.refreshStats());
    $('dataset').textContent = `${info.steps.length} steps · ${info.variables.length} variables · sample of ${info.sample.rows.toLocaleString()} points`;
    const varSel = $<HTMLSelectElement>('variable');
    for (const v of info.variables) varSel.add(new Option(`${v.name} [${v.units}]`, v.name));
    varSel.addEventListener('change', () => {
      this.state.color.variable = varSel.value;
      this.state.color.range = null;
      this.stepHistogram = null;
      this.updateTf();
      this.loadHistogram();
      this.updateLineColors();
      if (this.plData) {
        this.plPc.setAxes(this.pathlineAxes());
        this.plPc.setData({ rows: this.plData.lines, columns: this.plData.columns, values: this.plData.values });
      }
      this.commit(false);
    });
    const mapSel = $<HTMLSelectElement>('colorMap');
    for (const m of info.colorMaps) mapSel.add(new Option(m, m));
    mapSel.addEventListener('change', () => {
      this.state.color.colorMap = mapSel.value;
      this.updateTf();
      this.updateLineColors();
      this.commit(false);
    });
    const rangeChanged = () => {
      const lo = Number($<HTMLInputElement>('rangeMin').value), hi = Number($<HTMLInputElement>('rangeMax').value);
      if (!(Number.isFinite(lo) && Number.isFinite(hi) && lo < hi)) {
        this.showError(`colour range: min ${lo} must be less than max ${hi}`);
        this.updateTf();
        return;
      }
      this.state.color.range = [lo, hi];
      this.updateTf();
      this.updateLineColors();
      this.commit(false);
    };
    $('rangeMin').addEventListener('change', rangeChanged);
    $('rangeMax').addEventListener('change', rangeChanged);
    $('rangeReset').addEventListener('click', () => {
      this.state.color.range = null;
      this.updateTf();
      this.updateLineColors();
      this.commit(false);
    });
    $('opacityUnit').addEventListener('change', () => {
      const v = Number($<HTMLInputElement>('opacityUnit').value);
      if (v > 0) {
        this.state.color.opacityUnitKm = v;
        this.commit(false);
      }
    });
    $('resolution').addEventListener('change', () => {
      this.autoFitImage = true;
      if (this.fitImage()) this.commit(false);
    });
    $('passes').addEventListener('change', () => {
      const v = Math.round(Number($<HTMLInputElement>('passes').value));
      if (v >= 1) {
        this.state.passes = v;
        this.commit(false);
      }
    });
    $('level').addEventListener('change', () => {
      const v = $<HTMLSelectElement>('level').value;
      this.state.level = v === 'auto' ? 'auto' : Number(v);
      this.commit(false);
    });
    $('lighting').addEventListener('change', () => {
      this.state.shading = { ...this.state.shading, enabled: $<HTMLInputElement>('lighting').checked };
      this.commit(false);
    });
    $('core').addEventListener('change', () => {
      this.state.core = { ...this.state.core, visible: $<HTMLInputElement>('core').checked };
      this.commit(false);
    });
    $('cancel').addEventListener('click', () => {
      if (this.playing) this.togglePlay();
      this.connection.cancel();
      this.setStatusNote('cancelled');
    });
    $('resetView').addEventListener('click', () => {
      this.state.camera = cloneState(this.defaults).camera;
      this.commit(false);
    });
    $('clearBrushes').addEventListener('click', () => {
      this.pc.setBrushes([]);
      this.state.brushes = [];
      this.updateSelectionText();
      this.commit(false);
    });
    const stepIn = $<HTMLInputElement>('step');
    stepIn.max = String(info.steps.length - 1);
    stepIn.addEventListener('input', () => this.setStep(Number(stepIn.value), true));
    stepIn.addEventListener('change', () => this.setStep(Number(stepIn.value), false));
    $('play').addEventListener('click', () => this.togglePlay());
    document.addEventListener('keydown', (e) => {
      const t = e.target as HTMLElement;
      if (e.key === ' ' && !(t instanceof HTMLInputElement || t instanceof HTMLSelectElement || t instanceof HTMLButtonElement)) {
        e.preventDefault();
        this.togglePlay();
      }
    });

    $('save').addEventListener('click', () => {
      download(new Blob([JSON.stringify(this.state, null, 2) + '\n'], { type: 'application/json' }), `raypc-state-step${this.state.step}.json`);
    });
    $<HTMLInputElement>('load').addEventListener('change', async (e) => {
      const input = e.target as HTMLInputElement;
      const file = input.files?.[0];
      input.value = '';
      if (!file) return;
      try {
        this.loadState(JSON.parse(await file.text()));
        this.setStatusNote(`loaded ${file.name}`);
      } catch (err) {
        this.showError(`${file.name}: ${(err as Error).message}`);
      }
    });
    $('share').addEventListener('click', async () => {
      const url = `${location.origin}${location.pathname}${location.search}#state=${encodeStateForUrl(this.state)}`;
      try {
        await navigator.clipboard.writeText(url);
        this.setStatusNote('link copied');
      } catch {
        window.prompt('Link to this view:', url);
      }
    });
    $('screenshot').addEventListener('click', async () => {
      const button = $<HTMLButtonElement>('screenshot');
      button.disabled = true;
      this.setStatusNote('rendering screenshot…');
      try {
        download(await postScreenshot(cloneState(this.state)), `raypc-step${this.state.step}.png`);
        this.setStatusNote('screenshot saved');
      } catch (err) {
        this.showError((err as Error).message);
      } finally {
        button.disabled = false;
      }
    });
    window.addEventListener('hashchange', () => {
      try {
        const s = stateFromHash(location.hash);
        if (s && JSON.stringify(s) !== JSON.stringify(this.state)) this.loadState(s);
      } catch (e) {
        this.showError(`state in the URL: ${(e as Error).message}`);
      }
    });
  }

  // Puts the state into every control (after load, undo, URL).
  private syncControls(): void {
    const s = this.state;
    $<HTMLSelectElement>('variable').value = s.color.variable;
    $<HTMLSelectElement>('colorMap').value = s.color.colorMap;
    $<HTMLInputElement>('opacityUnit').value = String(s.color.opacityUnitKm);
    $<HTMLInputElement>('passes').value = String(s.passes);
    $<HTMLSelectElement>('level').value = String(s.level);
    $<HTMLInputElement>('lighting').checked = Boolean((s.shading as { enabled?: boolean } | undefined)?.enabled);
    $<HTMLInputElement>('core').checked = (s.core as { visible?: boolean } | undefined)?.visible !== false;
    $<HTMLInputElement>('step').value = String(s.step);
    this.updateStepLabel();
    this.updateTf();
    this.pc.setBrushes(s.brushes);
    this.updateSelectionText();
    this.syncPathlineControls();
  }

  // ---- status ------------------------------------------------------------------------------

  private statusNote = '';
  private setStatusNote(t: string): void {
    this.statusNote = t;
    this.updateStatus();
  }

  private updateStatus(): void {
    const h = this.lastHeader;
    const parts: string[] = [];
    if (h) {
      const st = h.stats ?? {};
      parts.push(`frame ${h.id}`, `step ${h.step + 1}`, `level ${h.level}`, `pass ${h.pass}/${h.passes}${h.converged ? ' ✓' : ''}`);
      if (st.passMs !== undefined) parts.push(`${st.passMs.toFixed(1)} ms/pass`);
      if (st.samplesPerSecond !== undefined) parts.push(`${(st.samplesPerSecond / 1e6).toFixed(1)} M samples/s`);
      if (st.bricksTotal) parts.push(`${(((st.bricksSkipped ?? 0) / st.bricksTotal) * 100).toFixed(0)} % bricks skipped`);
      parts.push(`${h.width}×${h.height}`);
    }
    const sel = this.selection;
    if (this.state.brushes.length && sel) parts.push(`selected ${(sel.fractionOfMantle * 100).toFixed(2)} %`);
    const lat = this.debug.latencies[this.debug.latencies.length - 1];
    if (lat) parts.push(`latency ${lat.shownMs.toFixed(0)} ms`);
    if (this.statusNote) parts.push(this.statusNote);
    $('status').textContent = parts.join(' · ');
  }

  showError(message: string): void {
    this.debug?.errors.push(message);
    const el = $('error');
    el.textContent = message;
    el.hidden = false;
    clearTimeout(this.errorTimer);
    this.errorTimer = window.setTimeout(() => { el.hidden = true; }, 6000);
  }
}

function fmt(v: number): string {
  return Math.abs(v) >= 1e4 || (Math.abs(v) < 1e-2 && v !== 0) ? v.toExponential(3) : String(+v.toPrecision(4));
}

function download(blob: Blob, name: string): void {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}

fetchInfo()
  .then((info) => new App(info))
  .catch((e) => {
    $('status').textContent = `cannot start: ${(e as Error).message}`;
  });
