// What the browser tests (tests/browser) read and drive, as `window.__raypc`. Installed only when
// the page is opened with `window.__raypcTestHooks = true` set before it loads (the tests' init
// script); otherwise nothing here runs and nothing is recorded.
import type { FeatureSeries, Selection, SelectionOverTime } from './api';
import type { FeaturesPanel } from './features_panel';
import type { PairView } from './pair';
import type { App } from './app';
import type { Frame, FrameHeader } from './connection';
import { snapStep, type AxisInfo, type ParallelCoordinates } from './parcoords';
import type { SlicePanel } from './slice_panel';
import type { PathlineCount } from './pathline_panel';
import type { Latency, SentEntry } from './render_link';
import { cloneState, type Brush, type RenderState } from './state';
import type { Info, PersistenceDiagram, Preset } from './api';
import type { ViewStats } from './view';
import type { XrSession } from './xr';

export interface TestHooks {
  info: Info;
  state(): RenderState;
  setState(s: unknown): void;
  view: ViewStats;
  framesReceived: number;
  headers: FrameHeader[];
  readonly lastShownId: number;
  readonly lastSentId: number;
  statesSent: number;
  latencies: Latency[];
  selection: Selection | null;
  readonly errors: string[];
  readonly playing: boolean;
  parcoords: ParallelCoordinates;
  readonly sampleStep: number;
  // The step whose sample the parallel coordinates' lines show complete (both layers), -1 before any.
  readonly linesStep: number;
  // What was sent and received when, warps drawn while a newer state was pending, and holding
  // incoming frames back (to look at a warped view deterministically).
  sentLog: SentEntry[];
  frameLog: { id: number; step: number; pass: number; t: number }[];
  // Frames on screen, when (performance.now()) and what the server rendered them as.
  // buffer: the 3D view's drawing buffer when the frame was shown (View3D's fitBuffer), full: the view's size.
  // passes: the state's; converged: the server's last frame of it; cached: rendered ahead (or kept).
  shownLog: { id: number; step: number; pass: number; passes: number; converged: boolean; cached: boolean; level: number;
    width: number; height: number; playback: boolean; interactive: boolean;
    buffer: [number, number]; full: [number, number]; t: number }[];
  warpedWhileWaiting: number;
  // Deferred work (the full line redraw after a brush release): the state it waited for, whether
  // that state's frame was on screen when it ran (false: it ran on the timeout or was superseded).
  afterFrames: { id: number; shownId: number; afterShown: boolean }[];
  holdFrames: boolean;
  releaseFrames(): void;
  readonly presets: Preset[];
  applyPreset(name: string): void;
  stats: SelectionOverTime | null;
  statsRequests: number;
  readonly pathlines: PathlineCount | null;
  plParcoords: ParallelCoordinates;
  readonly persistence: PersistenceDiagram | null;
  // The WebXR session (null when the browser offers no immersive-vr), once known.
  xr(): Promise<XrSession | null>;
  // The step dragged brush ends snap to on an axis (parcoords.ts).
  snapStep(a: AxisInfo): number;
  // The map and section panel (its pictures' headers and counts, the point under a pixel).
  slices: SlicePanel;
  // The Features panel: its last answer (null: none or no brushes), answers and time–depth pictures
  // received (true) or failed (false).
  features: FeaturesPanel;
  featureAnswers: (FeatureSeries | null)[];
  timeDepthPictures: boolean[];
  // A pair's second view (`raypc serve A B`; its frames in `headers`), null with one dataset or once closed.
  readonly pair: PairView | null;
}

export function testHooksWanted(): boolean {
  return (window as unknown as { __raypcTestHooks?: boolean }).__raypcTestHooks === true;
}

function push<T>(list: T[], item: T, limit: number): void {
  list.push(item);
  if (list.length > limit) list.shift();
}

export function installTestHooks(app: App): TestHooks {
  let held: Frame[] = [];
  const hooks: TestHooks = {
    info: app.info,
    state: () => cloneState(app.store.state),
    setState: (s) => app.loadState(s),
    view: app.link.view.stats,
    framesReceived: 0,
    headers: [],
    get lastShownId() { return app.link.lastShownId; },
    get lastSentId() { return app.link.lastSentId; },
    statesSent: 0,
    latencies: [],
    selection: null,
    get errors() { return app.errors; },
    get playing() { return app.playback.playing; },
    parcoords: app.pc,
    get sampleStep() { return app.sampleStep; },
    get linesStep() { return app.linesStep; },
    sentLog: [],
    frameLog: [],
    shownLog: [],
    warpedWhileWaiting: 0,
    afterFrames: [],
    holdFrames: false,
    releaseFrames: () => {
      hooks.holdFrames = false;
      const frames = held;
      held = [];
      for (const f of frames) app.link.receive(f);
    },
    get presets() { return app.presets; },
    applyPreset: (name) => {
      const p = app.presets.find((x) => x.name === name);
      if (!p) throw new Error(`no preset '${name}'`);
      app.applyPreset(p);
    },
    stats: null,
    statsRequests: 0,
    get pathlines() { return app.pathlines.count; },
    plParcoords: app.pathlines.pc,
    get persistence() { return app.persistence.diagram; },
    xr: () => app.xr,
    snapStep,
    slices: app.slices,
    features: app.features,
    featureAnswers: [],
    timeDepthPictures: [],
    get pair() { return app.pair && !app.pair.closed ? app.pair : null; },
  };
  app.link.observer = {
    sent: (e) => {
      hooks.statesSent++;
      push(hooks.sentLog, e, 500);
    },
    received: (f) => {
      if (hooks.holdFrames) {
        held.push(f);
        return false;
      }
      const h = f.header;
      hooks.framesReceived++;
      push(hooks.frameLog, { id: h.id, step: h.step, pass: h.pass, t: f.receivedAt }, 500);
      push(hooks.headers, h, 100);
      return true;
    },
    shown: (h, latency) => {
      if (latency) push(hooks.latencies, latency, 200);
      push(hooks.shownLog, { id: h.id, step: h.step, pass: h.pass, passes: h.passes, converged: !!h.converged, cached: !!h.cached,
        level: h.level, width: h.width, height: h.height,
        playback: !!h.playback, interactive: !!h.interactive, buffer: [app.link.view.canvas.width, app.link.view.canvas.height],
        full: [app.link.view.fullWidth, app.link.view.fullHeight], t: performance.now() }, 500);
    },
    drawn: (kind, waiting) => { if (kind === 'warped' && waiting) hooks.warpedWhileWaiting++; },
    afterFrame: (record) => push(hooks.afterFrames, record, 50),
  };
  app.selection.observer = {
    selection: (s) => { hooks.selection = s; },
    stats: (s) => { hooks.stats = s; },
    statsRequested: () => { hooks.statsRequests++; },
  };
  app.features.observer = {
    features: (f) => push(hooks.featureAnswers, f, 20),
    timeDepth: (ok) => push(hooks.timeDepthPictures, ok, 20),
  };
  (window as unknown as { __raypc: TestHooks }).__raypc = hooks;
  return hooks;
}
