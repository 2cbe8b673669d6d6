// The RayPC browser UI: one render state (StateStore) sent whole to the server (RenderLink,
// docs/protocol.md), and the parts that read and change it: camera input, the transfer-function
// panel, presets, the volume's parallel coordinates and its sample, the selection and pathline
// panels, playback, the other controls and the status line.
import { fetchPresets, fetchSample, postSelection, type Info, type Preset, type Sample } from './api';
import { setUpCameraInput } from './camera_input';
import type { FrameHeader, ShellKeyEntry } from './connection';
import { ContextPanel, showLegends, type LegendEntry } from './context_panel';
import { download, maxImageSide, setUpControls, syncControls, writeStateToUrl } from './controls';
import { ParallelCoordinates } from './parcoords';
import { PairView } from './pair';
import { PathlinePanel } from './pathline_panel';
import { PersistencePanel } from './persistence_panel';
import { FeaturesPanel } from './features_panel';
import { Playback } from './playback';
import { RenderLink } from './render_link';
import { setUpScreenshot } from './screenshot';
import { SelectionPanel } from './selection_panel';
import { SlicePanel } from './slice_panel';
import { watchSeriesProgress } from './series_progress';
import { describePreset, sameBrushes } from './presets';
import { normaliseState, type Brush, type RenderState } from './state';
import { StateStore } from './store';
import { TfPanel } from './tf_panel';
import { displayUnits } from './units';
import { readoutText } from './view_readout';
import { placeShellLabels } from './shell_labels';
import { setUpXr, type XrSession } from './xr';
import { showEmptySelection } from './empty_selection';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;

// While playing, a new step's sample is fetched at most this often, ms.
const kPlaybackSampleMs = 250;

// Axes of the volume's plot hidden until ticked under Axes (or brushed).
const kHiddenByDefault = ['x', 'y', 'z', 'radius'];

// The size of a still frame for a view of viewW x viewH device pixels: the view's own, or scaled
// down to `maxSide` on the longer side (the aspect kept).
export function fitImageSize(viewW: number, viewH: number, maxSide: number): { width: number; height: number } {
  const w = Math.max(1, viewW), h = Math.max(1, viewH);
  const scale = Math.min(1, maxSide / Math.max(w, h));
  return { width: Math.max(1, Math.round(w * scale)), height: Math.max(1, Math.round(h * scale)) };
}

export class App {
  readonly store: StateStore;
  readonly link: RenderLink;
  readonly pc: ParallelCoordinates;
  readonly tf: TfPanel;
  readonly selection: SelectionPanel;
  readonly pathlines: PathlinePanel;
  readonly persistence: PersistencePanel;
  readonly features: FeaturesPanel;
  readonly playback: Playback;
  readonly context: ContextPanel;
  readonly slices: SlicePanel;
  presets: Preset[] = [];
  // The second dataset's view of a pair (`raypc serve A B`, pair.ts); null: one dataset.
  pair: PairView | null = null;
  // The WebXR session control once the browser has said whether it offers immersive-vr (null: not).
  readonly xr: Promise<XrSession | null>;
  sampleStep = -1;
  readonly errors: string[] = [];
  private sampleLoading = false;
  private lastSampleLoad = 0;
  private sampleFailedStep = -1;
  private sampleFailedAt = 0;
  // Playback: the step sent ahead (not yet on screen) and its sample if it came before its frame
  // was shown (given to the parallel coordinates when it is).
  private aheadStep = -1;
  private heldSample: { step: number; sample: Sample } | null = null;
  linesStep = -1; // the step whose sample the parallel coordinates show complete (both layers)
  private errorTimer = 0;
  private statusNote = '';
  private viewNoteText = '';
  private lastPreset: Preset | null = null; // the preset applied last, in force while its brushes are
  private linkedStates: Promise<void> = Promise.resolve(); // the linked states being applied, in order
  private shellKey: ShellKeyEntry[] = []; // the reference shells the last frame shown drew
  private shownHeader: FrameHeader | null = null; // the frame on screen (the readout describes it)

  constructor(readonly info: Info) {
    this.store = new StateStore(info);
    try {
      this.store.loadFromHash(location.hash);
    } catch (e) {
      this.showError(`state in the URL: ${(e as Error).message}`);
    }
    const store = this.store;

    this.link = new RenderLink($<HTMLCanvasElement>('view3d'), store, {
      onFrameArrived: (h) => {
        // Interactive frames carry the selection on the level they rendered: quick feedback while
        // brushing; final states get the exact volume from POST /api/selection (refreshSelection).
        // (A playback frame's figure is taken when the frame is shown: it is of the step ahead.)
        if (h.selection && h.interactive && store.state.brushes.length) this.selection.setSelection({ ...h.selection, step: h.step }, h.level);
        if (this.playback.playing) this.playback.maybeAdvance();
      },
      onFrameHeld: (f) => this.playback.frameHeld(f),
      onFrameShown: (h) => {
        this.shownHeader = h;
        // Playback's step on the time bar once its frame is on screen, not when it is released.
        if (h.playback) {
          this.showStepOnBar(h.step);
          this.showLinesStep(this.linesStep);
        }
        if (h.selection && h.playback && store.state.brushes.length) this.selection.setSelection({ ...h.selection, step: h.step }, h.level);
        this.updateStatus();
        this.pathlines.frameShown(h);
        const key = h.shellKey ?? [];
        if (JSON.stringify(key) !== JSON.stringify(this.shellKey)) {
          this.shellKey = key;
          this.updateLegends();
        }
      },
      onDrawn: (kind) => placeShellLabels($('shellLabels'), this.link.view.frameHeader, kind, this.link.view.pictureRect),
      onError: (m) => this.showError(m),
      onStatus: (t) => this.setStatusNote(t),
      // A program set the linked state (e.g. a notebook's `view.state = s`): applied as "Load
      // state" applies a file, one at a time in the order they came; what the page then commits goes
      // back to the server, which makes it the linked state.
      onLink: (doc, version) => {
        this.linkedStates = this.linkedStates.then(() =>
          this.loadOutsideState(doc, `the linked state (version ${version}, from /api/link)`));
      },
    });
    this.tf = new TfPanel(store, {
      commit: (i) => this.commit(i),
      showError: (m) => this.showError(m),
      setStatusNote: (t) => this.setStatusNote(t),
      colorsChanged: () => this.updateLineColors(),
      variableChanged: () => {
        this.pathlines.variableChanged();
        this.showViewNote('');
      },
    });
    this.pc = new ParallelCoordinates($('parcoords'), this.shownAxes(), {
      onBrush: (brushes, interactive) => this.onBrush(brushes, interactive),
      afterFrame: (draw) => this.link.afterFrameShown(draw),
      multi: true,
      onOrder: (order) => this.setAxes(order),
      onDrawn: (step) => this.showLinesStep(step),
    });
    this.pathlines = new PathlinePanel(store, {
      commit: (i) => this.commit(i),
      showError: (m) => this.showError(m),
      linesLoaded: () => this.updateLegends(),
      filtersChanged: () => this.persistence.draw(),
      showTab: (tab) => this.showTab(tab),
    });
    this.slices = new SlicePanel(store, {
      changed: () => {
        if (store.state.map.showInView) this.link.send(false);
        writeStateToUrl(store);
      },
      showError: (m) => this.showError(m),
    });
    $('pcTabVolume').addEventListener('click', () => this.showTab('volume'));
    $('pcTabPathlines').addEventListener('click', () => this.showTab('pathlines'));
    $('pcTabSlices').addEventListener('click', () => this.showTab('slices'));
    this.persistence = new PersistencePanel(store, {
      commit: (i) => this.commit(i),
      showError: (m) => this.showError(m),
      filtersChanged: (i) => this.pathlines.filtersChanged(i),
      columnMax: (name) => this.pathlines.columnMax(name),
    });
    this.features = new FeaturesPanel(store, {
      showError: (m) => this.showError(m),
      setStep: (step, interactive) => this.setStep(step, interactive),
      commit: (i) => this.commit(i),
    });
    this.link.forStep = (s, step) => this.features.forStep(s, step);
    this.context = new ContextPanel(store, { commit: (i) => this.commit(i), showError: (m) => this.showError(m) });
    this.selection = new SelectionPanel(store, {
      showError: (m) => this.showError(m),
      setBrush: (index, range) => {
        const brushes = store.state.brushes.map((b) => ({ ...b }));
        if (range) brushes[index] = { name: brushes[index].name, min: range[0], max: range[1] };
        else brushes.splice(index, 1);
        this.pc.setBrushes(brushes);
        this.onBrush(brushes, false);
      },
      playing: () => this.playback.playing,
      selectionChanged: () => { this.updateStatus(); showEmptySelection(this.selection.selection); },
      commit: (i) => this.commit(i),
    });
    this.playback = new Playback({
      stepCount: info.steps.length,
      currentStep: () => store.state.step,
      sendStep: (step, budgetMs) => {
        const id = this.link.sendPlayback(step, budgetMs);
        // Its sample is fetched meanwhile, to be drawn when its frame is shown (at most four a
        // second: the page shares the machine with the server rendering the steps).
        this.aheadStep = step;
        if (performance.now() - this.lastSampleLoad >= kPlaybackSampleMs) this.loadSample(step);
        return id;
      },
      hasHeld: (id) => this.link.hasHeld(id),
      showHeld: (step) => {
        this.link.releaseHeld();
        this.stepShown(step);
      },
      lastSentId: () => this.link.lastSentId,
      caughtUp: () => this.link.caughtUp,
      stopHolding: () => this.link.stopHolding(),
      setStep: (step, interactive) => this.setStep(step, interactive),
      // While playing, the parallel coordinates draw a twentieth of the lines of each new step's
      // sample (the full redraw of 100 000 lines per sample held playback to ~5 steps/s).
      playingChanged: (playing) => {
        this.pc.setCoarse(playing);
        this.aheadStep = -1;
        this.heldSample = null;
        this.showLinesStep(this.linesStep);
      },
    });
    setUpControls(store, {
      commit: (i) => this.commit(i),
      loadState: (doc) => this.loadState(doc),
      loadOutsideState: (doc, what) => this.loadOutsideState(doc, what),
      showError: (m) => this.showError(m),
      setStatusNote: (t) => this.setStatusNote(t),
      setStep: (step, interactive) => this.setStep(step, interactive),
      togglePlay: () => this.playback.toggle(),
      stopPlaying: () => { if (this.playback.playing) this.playback.toggle(); },
      cancelRendering: () => this.link.cancel(),
      fitImage: () => this.fitImage(),
      view: this.link.view,
      redrawView: () => this.link.requestDraw(),
      clearBrushes: () => {
        this.pc.setBrushes([]);
        store.state.brushes = [];
        this.selection.updateText();
        this.presetLeft();
        this.commit(false);
      },
    });
    setUpScreenshot({
      // A pair's picture holds both views: twice the width of one (docs/compare.md).
      state: () => (this.pair && !this.pair.closed ? { ...store.state, image: { ...store.state.image, width: 2 * store.state.image.width } } : store.state),
      showError: (m) => this.showError(m),
      setStatusNote: (t) => this.setStatusNote(t),
      download,
      fileStem: () => `raypc-step${store.state.step}`,
      limits: () => this.info.limits,
    });
    this.setUpAxisChoice();
    setUpCameraInput(this.link.view.canvas, store, (i) => this.commit(i));
    this.xr = setUpXr($<HTMLButtonElement>('enterVr'), this.link, store, (m) => this.showError(m));
    // Escape clears the brushes (outside text fields, where it belongs to the field).
    document.addEventListener('keydown', (e) => {
      const t = e.target as HTMLElement;
      if (e.key === 'Escape' && !(t instanceof HTMLInputElement && t.type !== 'checkbox') && store.state.brushes.length && !document.querySelector('dialog[open]')) {
        this.pc.setBrushes([]);
        this.onBrush([], false);
      }
    });
    $('devStats').addEventListener('change', () => this.updateStatus());
    new ResizeObserver(() => this.onResize()).observe($('viewPanel'));
  }

  // Starts the work that needs the test hooks (if any) in place: the first state, the sample, ….
  start(): void {
    if (this.info.pair) {
      this.pair = new PairView({
        info: this.info, store: this.store, link: this.link, pc: this.pc,
        commit: (i) => this.commit(i),
        showError: (m) => this.showError(m),
        layoutChanged: () => this.onResize(),
        firstSelection: () => this.selection.selection?.fractionOfMantle ?? null,
      });
    }
    this.onResize();
    this.syncControls();
    this.loadSample();
    this.tf.loadHistogram();
    this.loadPresets();
    this.commit(false);
    watchSeriesProgress($('seriesProgress'));
  }

  // ---- state -------------------------------------------------------------------------------

  loadState(s: unknown): void {
    const prev = this.store.replace(s);
    this.pair?.stateLoaded();
    this.features.stateLoaded(s);
    this.showViewNote(''); // a preset shows its own after loading
    const state = this.store.state;
    this.syncControls();
    if (prev.step !== state.step) {
      this.loadSample();
      this.tf.loadHistogram();
    } else if (prev.color.variable !== state.color.variable) this.tf.loadHistogram();
    this.updateLineColors();
    this.commit(false);
  }

  // A state from outside the page (a file, a link): checked by the server against this dataset first
  // (POST /api/selection resolves it with the rules it renders with: names, ranges, step), so that a
  // state it refuses changes nothing and no figure of it is shown. A step beyond the dataset's last
  // is clamped to it, with a note, as presets are.
  async loadOutsideState(doc: unknown, what: string): Promise<void> {
    let candidate: RenderState;
    try {
      candidate = normaliseState(doc, this.store.defaults);
    } catch (e) {
      this.showError(`${what}: ${(e as Error).message}`);
      return;
    }
    const last = this.info.steps.length - 1;
    const asked = candidate.step;
    candidate.step = Math.min(asked, last);
    try {
      await postSelection(candidate);
    } catch (e) {
      this.showError(`${what} not applied: ${(e as Error).message}`);
      return;
    }
    // A document that names no image size (an example state, a hand-written one) keeps the view's:
    // the picture goes on following the view, as after a preset.
    const namesImage = typeof doc === 'object' && doc !== null && 'image' in doc;
    if (!namesImage) candidate.image = { ...this.store.state.image };
    this.loadState(candidate);
    if (!namesImage) {
      this.store.autoFitImage = true;
      if (this.fitImage()) this.commit(false);
    }
    this.presetLeft(); // a document with the last preset's brushes puts it back in force
    this.setStatusNote(asked > last
      ? `loaded ${what}: written for step ${asked}, this dataset ends at step ${last}, shown`
      : `loaded ${what}`);
  }

  // Sends the state; a final (not interactive) one also goes into the page URL, and once its frame
  // is shown the exact selection and the statistics are asked for.
  commit(interactive: boolean): void {
    this.link.send(interactive);
    this.updateLegends();
    this.updateViewNote();
    this.slices.stateChanged();
    if (interactive) return;
    writeStateToUrl(this.store);
    this.link.afterFrameShown(() => {
      this.selection.refreshSelection();
      this.selection.refreshStats();
      this.features.refresh();
    });
    this.pathlines.refresh();
    this.persistence.refresh();
  }

  // The bottom panel's tab: the volume's parallel coordinates, the pathlines', or the map and the
  // section (docs/maps.md).
  showTab(tab: 'volume' | 'pathlines' | 'slices'): void {
    $('parcoords').hidden = tab !== 'volume';
    this.pathlines.setVisible(tab === 'pathlines');
    this.slices.setVisible(tab === 'slices');
    $('pcTabVolume').classList.toggle('active', tab === 'volume');
    $('pcTabPathlines').classList.toggle('active', tab === 'pathlines');
    $('pcTabSlices').classList.toggle('active', tab === 'slices');
    for (const [id, t] of [['pcTabVolume', 'volume'], ['pcTabPathlines', 'pathlines'], ['pcTabSlices', 'slices']])
      $(id).setAttribute('aria-selected', String(tab === t));
  }

  // The colour legends on the view (state.legend): the volume's variable, and the pathlines'
  // colouring while they are shown.
  updateLegends(): void {
    const s = this.store.state;
    const entries: LegendEntry[] = [];
    if (s.legend) {
      const painted = this.features.paintLegend();
      if (painted) entries.push(painted);
      else {
        const v = this.store.variableInfo();
        const units = displayUnits(v.units);
        const colorOf = this.store.colorOf();
        entries.push({ title: units ? `${v.name} [${units}]` : v.name, colorAt: (u) => colorOf(this.store.valueAt(u)), valueAt: (u) => this.store.valueAt(u) });
      }
      const pl = this.pathlines.legend();
      if (pl) entries.push(pl);
    }
    // The shells' key with the legends, as the last frame shown drew the shells (its header).
    showLegends(entries, s.legend ? this.shellKey : []);
  }

  // Puts the state into every control (after load, undo, URL).
  private syncControls(): void {
    this.context.sync();
    this.tf.sync();
    syncControls(this.store);
    this.updateStepLabel();
    this.showStateAxes(); // before the brushes: a brushed axis is shown
    this.pc.setBrushes(this.store.state.brushes);
    this.selection.updateText();
    this.pathlines.sync();
    this.slices.sync();
    this.features.sync();
    this.persistence.draw();
  }

  // ---- presets (GET /api/presets) ------------------------------------------------------------

  private loadPresets(): void {
    fetchPresets()
      .then((presets) => {
        this.presets = presets;
        const box = $('presets');
        box.innerHTML = '';
        if (!presets.length) box.textContent = 'none (no examples directory)';
        for (const p of presets) {
          const b = document.createElement('button');
          b.textContent = p.title;
          b.title = `${p.title} (${p.name}.json)`;
          b.dataset.preset = p.name;
          if (p.unavailable) {
            // The server tried it on this dataset (a model without the contest's variables, say).
            b.disabled = true;
            b.classList.add('unavailable');
            b.title = `${p.title} (${p.name}.json): ${p.unavailable}`;
          }
          b.addEventListener('click', () => this.applyPreset(p));
          box.appendChild(b);
        }
        const unavailable = presets.filter((p) => p.unavailable).length;
        if (unavailable)
          $('presetNote').textContent = `${unavailable} of ${presets.length} presets are not for this dataset (greyed; hover one for why)`;
      })
      .catch((e) => this.showError((e as Error).message));
  }

  // A preset sets everything it names and resets the rest to the defaults (pathlines off unless it
  // names them, the level, reference geometry, …), its step included (the figures of docs/tasks.md
  // are of that step; a dataset with fewer steps shows its last one, and the note says so). Only the
  // image size stays: it follows the view.
  applyPreset(p: Preset): void {
    try {
      const state = this.store.state;
      const previousVariable = state.color.variable;
      const doc = { ...(p.state as Record<string, unknown>) };
      const last = this.info.steps.length - 1;
      const asked = typeof doc.step === 'number' ? doc.step : 0;
      doc.step = Math.min(asked, last);
      doc.image = { ...state.image };
      const fit = this.store.autoFitImage;
      this.loadState(doc);
      this.store.autoFitImage = fit;
      this.lastPreset = p;
      this.showPresetInForce(p);
      this.setStatusNote(`preset ${p.title}`);
      // The colouring on the view itself: a preset may switch the colour variable (task 1 colours
      // by radial velocity), which the picture alone does not tell.
      const v = this.store.variableInfo();
      const units = displayUnits(v.units);
      const switched = previousVariable !== v.name ? ' now' : '';
      this.showViewNote(`colour${switched}: ${v.name}${units ? ` [${units}]` : ''} (preset ${p.title})`);
    } catch (e) {
      this.showError(`preset ${p.name}: ${(e as Error).message}`);
    }
  }

  // The preset's button highlighted and its one-line description under the buttons.
  private showPresetInForce(p: Preset): void {
    for (const b of document.querySelectorAll<HTMLButtonElement>('#presets button'))
      b.classList.toggle('active', b.dataset.preset === p.name);
    const last = this.info.steps.length - 1;
    const asked = typeof (p.state as { step?: unknown }).step === 'number' ? (p.state as { step: number }).step : 0;
    const note = describePreset(this.store.state, this.store.axes());
    $('presetNote').textContent = `${p.title}: ${note}${asked > last ? ` (written for step ${asked}; this dataset ends at step ${last})` : ''}`;
  }

  // ---- view size ---------------------------------------------------------------------------

  private onResize(): void {
    const view = this.link.view;
    const dpr = window.devicePixelRatio || 1;
    view.resize(Math.max(1, Math.round(view.canvas.clientWidth * dpr)), Math.max(1, Math.round(view.canvas.clientHeight * dpr)));
    if (this.store.autoFitImage) {
      const changed = this.fitImage();
      if (changed) this.commit(false);
    }
    this.link.requestDraw();
  }

  // Still frames at the view's size in device pixels (CSS size × devicePixelRatio, as the canvas),
  // scaled down to the Max size setting on the longer side. Interactive frames keep their time
  // budget on the server (coarser level, then 1/2 or 1/4 of the pixels per axis; docs/protocol.md)
  // and are warped in between. Side by side at full width, each eye takes half the view.
  private fitImage(): boolean {
    const view = this.link.view;
    const eyesAcross = this.store.state.stereo.mode === 'side-by-side' ? 2 : 1;
    const { width, height } = fitImageSize(Math.max(1, Math.floor(view.fullWidth / eyesAcross)), view.fullHeight, maxImageSide());
    const w = width, h = height;
    const image = this.store.state.image;
    if (w === image.width && h === image.height) return false;
    this.store.state.image = { width: w, height: h };
    return true;
  }

  // ---- axes, brushes and the sample ----------------------------------------------------------

  // The axes of the volume's plot in display order: state.axes (ticked under Axes, in the order
  // they were dragged to), by default every axis but x, y, z and radius (depth, lat and lon say
  // where more plainly) in the dataset's order; and any axis a brush is on, after them.
  private axisNames(): string[] {
    const all = this.store.axes().map((a) => a.name);
    const chosen = this.store.state.axes ?? all.filter((n) => !kHiddenByDefault.includes(n));
    const brushed = this.store.state.brushes.map((b) => b.name);
    return [...new Set([...chosen, ...brushed])].filter((n) => all.includes(n));
  }

  private shownAxes() {
    const axes = this.store.axes();
    return this.axisNames().map((n) => axes.find((a) => a.name === n)!);
  }

  // Shows the state's axes in its order (after a load, or a change under Axes).
  private showStateAxes(): void {
    this.pc.showAxes(this.shownAxes());
    this.pc.setOrder(this.axisNames());
    for (const input of document.querySelectorAll<HTMLInputElement>('#axisChoice input'))
      input.checked = this.axisNames().includes(input.dataset.axis ?? '');
  }

  // Axes shown and their order change nothing in the picture: the state keeps them (saved files,
  // the URL) without sending it.
  private setAxes(names: string[]): void {
    this.store.state.axes = names;
    writeStateToUrl(this.store);
  }

  private setUpAxisChoice(): void {
    const box = $('axisChoice');
    for (const a of this.store.axes()) {
      const label = document.createElement('label');
      const input = document.createElement('input');
      input.type = 'checkbox';
      input.dataset.axis = a.name;
      input.checked = this.axisNames().includes(a.name);
      input.addEventListener('change', () => {
        const shown = this.pc.order().filter((n) => n !== a.name);
        this.setAxes(input.checked ? [...shown, a.name] : shown);
        this.showStateAxes();
      });
      label.append(input, ` ${a.name}`);
      box.appendChild(label);
    }
  }

  // ---- brushes and the sample ----------------------------------------------------------------

  // The brushes no longer are a preset's: its button is no longer highlighted, and its note (which
  // lists its brushes) says that the selection was changed.
  // Brushes that are the preset's own (a saved state of it loaded again, the parallel coordinates
  // setting them back) leave it in force, or put it back in force: only a different selection is a
  // change.
  private presetLeft(): void {
    const last = this.lastPreset;
    if (last && sameBrushes((last.state as { brushes?: Brush[] }).brushes ?? [], this.store.state.brushes)) {
      this.showPresetInForce(last);
      return;
    }
    const active = document.querySelector<HTMLButtonElement>('#presets button.active');
    if (!active) return;
    active.classList.remove('active');
    $('presetNote').textContent = `${active.textContent}: brushes changed since (no preset in force)`;
    // The status line's "preset TITLE" named the selection in force; it is no longer.
    if (this.statusNote === `preset ${active.textContent}`) this.setStatusNote('');
    this.showViewNote('');
  }

  // The note over the 3D view (#viewNote): what a preset coloured the volume by; '' hides it.
  // While the view is coloured by feature (features.colorById) the colour variable is not what the
  // view shows, so the note is hidden until the view is coloured by the variable again.
  private showViewNote(text: string): void {
    this.viewNoteText = text;
    this.updateViewNote();
  }

  private updateViewNote(): void {
    const note = $('viewNote');
    note.textContent = this.viewNoteText;
    note.hidden = this.viewNoteText === '' || (this.store.state.features.colorById && this.store.state.brushes.length > 0);
  }

  private onBrush(brushes: Brush[], interactive: boolean): void {
    const started = !this.store.state.brushes.length && brushes.length > 0;
    this.store.state.brushes = brushes;
    showEmptySelection(null); // until the new selection's answer says otherwise
    if (started) this.selection.brushingStarted();
    this.presetLeft();
    if (!interactive) this.pc.showAxes(this.shownAxes()); // an axis hidden once its brush is gone
    this.commit(interactive);
    this.selection.updateText();
    this.pathlines.updateLineCount();
  }

  // Loads the sample of `step` (the store's unless given) into the parallel coordinates, one load at
  // a time. While playing, the sample of the step sent ahead (sendStep) is fetched while its frame
  // is rendered and drawn once that frame is shown (stepShown); one that comes after its frame was
  // shown is drawn at once. Steps come faster than samples at high speeds: a step is skipped while a
  // sample loads, the lines on screen stay those of the last sample drawn, and the label over them
  // names its step (showLinesStep), a step that was on screen.
  private loadSample(step = this.store.state.step): void {
    if (this.sampleLoading) return;
    if (step === this.sampleStep) return;
    // A step whose sample failed is asked for again only when the step changes (or after a pause):
    // never in a loop.
    if (step === this.sampleFailedStep && performance.now() - this.sampleFailedAt < 5000) return;
    this.sampleLoading = true;
    this.lastSampleLoad = performance.now();
    // The first sample whole; later steps only their variables (the rows' coordinates stay).
    const request = this.sampleStep < 0
      ? fetchSample(step, this.info.sample.columns, 'all')
      : fetchSample(step, this.info.variables.map((v) => v.name), 'variables');
    request
      .then((sample) => {
        if (this.playback.playing && step === this.aheadStep && this.sampleStep >= 0) this.heldSample = { step, sample };
        else this.drawSample(step, sample);
      })
      .catch((e) => {
        this.sampleFailedStep = step;
        this.sampleFailedAt = performance.now();
        this.showError((e as Error).message);
      })
      .finally(() => {
        this.sampleLoading = false;
        if (this.store.state.step !== this.sampleStep && !this.playback.playing) this.loadSample();
      });
  }

  private drawSample(step: number, sample: Sample): void {
    const first = this.sampleStep < 0;
    this.pc.setData(sample, step);  // drawn with the colour function in force
    // A new step's lines keep that function; setting it again would draw them all twice.
    if (first) this.updateLineColors();
    this.sampleStep = step;
  }

  // The label over the parallel coordinates: the step whose sample the lines on screen show (while
  // playing, often not the step of the 3D view: it says so).
  private showLinesStep(step: number): void {
    if (step >= 0) this.linesStep = step;
    step = this.linesStep;
    const el = $('pcStep');
    const s = this.info.steps[step];
    if (!s) {
      el.textContent = '';
      return;
    }
    const viewStep = this.shownHeader?.step ?? this.store.state.step;
    el.textContent = `lines: step ${s.index} · ${s.timeMyr.toFixed(1)} Myr${step !== viewStep ? ` (view: step ${viewStep})` : ''}`;
    el.classList.toggle('behind', step !== viewStep);
    el.dataset.step = String(step);
  }

  // The lines of the sample coloured as the volume.
  private updateLineColors(): void {
    const name = this.store.state.color.variable;
    const colorOf = this.store.colorOf();
    const palette = Array.from({ length: 64 }, (_, i) => {
      const [r, g, b] = colorOf(this.store.valueAt(i / 63));
      return `rgb(${Math.round(r * 255)},${Math.round(g * 255)},${Math.round(b * 255)})`;
    });
    this.pc.setColor((row) => palette[Math.min(63, Math.max(0, Math.round(this.store.positionOf(row[name]) * 63))) || 0]);
  }

  // ---- time --------------------------------------------------------------------------------

  private setStep(step: number, interactive: boolean): void {
    this.store.state.step = step;
    this.features.stepChanged();
    this.updateStepLabel();
    this.commit(interactive);
    if (!interactive) {
      this.tf.loadHistogram();
      this.loadSample();
    } else if (performance.now() - this.lastSampleLoad > 1000) this.loadSample();
  }

  // Playback showed a frame of `step` (its state was sent a period earlier): the step is the
  // store's now; the parallel coordinates follow at most once a second.
  private stepShown(step: number): void {
    this.store.state.step = step;
    this.features.stepChanged();
    this.selection.stepShown(step);
    const held = this.heldSample;
    this.heldSample = null;
    if (held && held.step === step) this.drawSample(step, held.sample);
    else this.showLinesStep(this.linesStep);
  }

  // The time bar (slider and label) at `step`: the store's, or during playback the frame shown's.
  private showStepOnBar(step: number): void {
    $<HTMLInputElement>('step').value = String(step);
    this.updateStepLabel(step);
  }

  private updateStepLabel(step = this.store.state.step): void {
    const s = this.info.steps[step];
    // Steps are numbered from 0 everywhere: the state's step, file names, `raypc render --time`.
    $('stepLabel').textContent = s ? `step ${s.index} of 0–${this.info.steps.length - 1} · ${s.timeMyr.toFixed(1)} Myr` : '';
  }

  // ---- status ------------------------------------------------------------------------------

  setStatusNote(t: string): void {
    this.statusNote = t;
    this.updateStatus();
  }

  private updateStatus(): void {
    const h = this.link?.lastHeader;
    const parts: string[] = [];
    // The frame's step and level always; what it cost behind "Frame statistics".
    const dev = $<HTMLInputElement>('devStats').checked;
    if (h) {
      const st = h.stats ?? {};
      if (dev) parts.push(`frame ${h.id}`);
      parts.push(`step ${h.step}`, `level ${h.level}`);
      if (dev) {
        parts.push(h.preview ? 'preview' : `pass ${h.pass}/${h.passes}${h.converged ? ' ✓' : ''}`);
        if (st.passMs !== undefined) parts.push(`${st.passMs.toFixed(1)} ms/pass`);
        if (st.samplesPerSecond !== undefined) parts.push(`${(st.samplesPerSecond / 1e6).toFixed(1)} M samples/s`);
        if (st.bricksTotal) parts.push(`${(((st.bricksSkipped ?? 0) / st.bricksTotal) * 100).toFixed(0)} % bricks skipped`);
        parts.push(`${h.width}×${h.height}`);
      }
      if ((h.ranks ?? 1) > 1) parts.push(`${h.ranks} ranks`);
    }
    const sel = this.selection?.selection;
    if (this.store.state.brushes.length && sel) parts.push(`selected ${this.selection.selectionLevel > 0 ? '≈ ' : ''}${(sel.fractionOfMantle * 100).toFixed(2)} %`);
    const lat = this.link?.lastLatency;
    if (lat && dev) parts.push(`latency ${lat.shownMs.toFixed(0)} ms`);
    if (this.statusNote) parts.push(this.statusNote);
    $('status').textContent = parts.join(' · ');
    this.pair?.updateLabels();
    this.updateReadout();
  }

  // The readout and the coarse-frame badge on the view (view_readout.ts): of the frame shown.
  private updateReadout(): void {
    const h = this.shownHeader;
    const s = this.store.state;
    const { readout, badge } = readoutText({
      frame: h,
      steps: this.info.steps,
      brushed: s.brushes.length > 0,
      imageWidth: s.image.width,
      imageHeight: s.image.height,
      figures: h && this.selection ? this.selection.figures(h.step) : [],
    });
    const r = $('viewReadout'), b = $('coarseBadge');
    r.textContent = readout;
    r.hidden = readout === '';
    b.textContent = badge;
    b.hidden = badge === '';
  }

  showError(message: string): void {
    this.errors.push(message);
    if (this.errors.length > 100) this.errors.shift();
    const el = $('error');
    el.textContent = message;
    el.hidden = false;
    clearTimeout(this.errorTimer);
    this.errorTimer = window.setTimeout(() => { el.hidden = true; }, 6000);
  }
}
