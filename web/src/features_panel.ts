// The Features panel (docs/features.md, "In the UI"): the connected regions of the selection followed
// through the series (POST /api/features, the server's FeatureSeries as `raypc features --tracks`
// computes it), as a sortable table of tracks; a chosen track's timeline (mean depth and volume
// against time, the state's depths marked); the flux across those depths with the avalanche steps;
// the time–depth picture of the selection (POST /api/time-depth, drawn by the server as
// `raypc stats --hovmoller`). Asked for while the panel is open, after each final state whose
// selection or feature settings changed; the next change cancels a request still running.
import * as d3 from 'd3';
import { getJobProgress, postFeatures, postTimeDepth, postTimeDepthCsv, type FeatureSeries, type FeatureTrack, type JobProgress } from './api';
import { download } from './controls';
import { plotFrame } from './stats_plot';
import { cloneState, type RenderState } from './state';
import type { StateStore } from './store';
import type { LegendEntry } from './context_panel';
import { derivedVariable, shellAnomaly, temperatureAnomalyName, temperatureSources } from './names';
import type { Brush } from './state';
import { fmt } from './selection_panel';
import { displayUnits } from './units';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;
// The flux is that of the radial velocity (raypc flux).
const kRadialVelocity = derivedVariable('radialVelocity');

export interface FeaturesPanelHost {
  showError(message: string): void;
  setStep(step: number, interactive: boolean): void;
  commit(interactive: boolean): void;
}

// What the browser tests observe (test_hooks.ts).
export interface FeaturesPanelObserver {
  features(f: FeatureSeries | null): void;
  timeDepth(ok: boolean): void;
}

type SortKey = 'track' | 'firstStep' | 'lifetimeMyr' | 'maxVolumeKm3' | 'meanDepthKm' | 'stallMyr' | 'events';

// A title row above the plot, and below it the tick labels and the axis' title (12 px text).
const kMargin = { top: 22, right: 12, bottom: 36, left: 54 };

const frame = (svg: SVGSVGElement, right = kMargin.right) => plotFrame(svg, { ...kMargin, right });

function fmtVolume(v: number): string {
  return v.toExponential(2);
}

// The measures the server times stalls by (the protocol's FeatureSeries.stallBy).
type StallBy = FeatureSeries['stallBy'];
const kStallByWords: Record<StallBy, string> = {
  'mean-depth': 'mean depth', deepest: 'deepest point (the slab\'s tip)', shallowest: 'shallowest point (the plume\'s head)',
};

// A stall's time as a cell shows it: whole Myr, or one decimal below 10 Myr so that a short stall
// never reads "0".
function fmtMyr(myr: number): string {
  return myr < 10 ? myr.toFixed(1) : myr.toFixed(0);
}

// The measure a selection implies for timing stalls, and why: a selection of cold material (every
// brush on a temperature axis entirely below its reference: 0 for an anomaly, the server's global
// mean for a stored temperature) is of sinking slabs, whose tip reaches a depth first and stalls
// there while their mean depth is still above it; a hot one is of rising plumes, led by their head.
// Anything else (no temperature brush, both or neither side) keeps the mean depth.
export function impliedStallBy(brushes: readonly Brush[], variables: readonly { name: string; mean: number; units: string }[]):
  { stallBy: StallBy; why: string } {
  const sides = new Set<'cold' | 'hot' | 'mixed'>();
  const said: string[] = [];
  for (const b of brushes) {
    const isAnomaly = b.name === temperatureAnomalyName
      || temperatureSources.some((t) => b.name === t + shellAnomaly.suffix || b.name === t + shellAnomaly.percentSuffix);
    const v = variables.find((x) => x.name === b.name);
    if (!v || !(isAnomaly || temperatureSources.includes(b.name))) continue;
    const reference = isAnomaly ? 0 : v.mean;
    const units = v.units ? ` ${displayUnits(v.units)}` : '';
    const below = isAnomaly ? '0' : `its global mean ${fmt(v.mean)}${units}`;
    if (b.max <= reference) { sides.add('cold'); said.push(`${b.name} ≤ ${fmt(b.max)}${units}, below ${below}`); }
    else if (b.min >= reference) { sides.add('hot'); said.push(`${b.name} ≥ ${fmt(b.min)}${units}, above ${below}`); }
    else sides.add('mixed');
  }
  if (sides.size === 1 && sides.has('cold'))
    return { stallBy: 'deepest', why: `the selection is cold (${said.join('; ')}): sinking slabs, timed by their tip` };
  if (sides.size === 1 && sides.has('hot'))
    return { stallBy: 'shallowest', why: `the selection is hot (${said.join('; ')}): rising plumes, timed by their head` };
  return { stallBy: 'mean-depth', why: sides.size ? 'the selection is neither only cold nor only hot' : 'the selection brushes no temperature' };
}

export class FeaturesPanel {
  observer: FeaturesPanelObserver | null = null;
  result: FeatureSeries | null = null;
  selectedTrack: number | null = null;
  private hoverTrack: number | null = null; // the row under the pointer (hover)
  private hoverTimer = 0;
  private key = '';
  private abort: AbortController | null = null;
  private timer = 0;
  private ticker = 0;
  private sort: { key: SortKey; descending: boolean } = { key: 'maxVolumeKm3', descending: true };
  private timeDepthUrl = '';
  // Whether the stall measure is the user's (chosen under "stall by", or named by a loaded state
  // that differs from what its selection implies); else features.stallBy follows the selection.
  private stallChosen = false;

  constructor(private readonly store: StateStore, private readonly host: FeaturesPanelHost) {
    $('featuresDetails').addEventListener('toggle', () => this.refresh());
    $('featuresCancel').addEventListener('click', () => {
      this.abort?.abort();
      this.key = '';
      this.stopTicker('cancelled: change the selection or press Find to ask again');
    });
    $('featuresFind').addEventListener('click', () => { this.key = ''; this.refresh(true); });
    $('featuresTimeDepthOf').addEventListener('change', () => { this.key = ''; this.refresh(true); });
    $<HTMLInputElement>('featuresColorById').addEventListener('change', (e) => {
      this.store.state.features.colorById = (e.target as HTMLInputElement).checked;
      this.host.commit(false);
    });
    $('featuresClearHighlight').addEventListener('click', () => {
      this.selectedTrack = null;
      this.store.state.features.highlight = [];
      this.drawTable();
      this.drawTimeline();
      this.host.commit(false);
    });
    const settings = () => {
      const s = this.store.state.features;
      const minVolume = Number($<HTMLInputElement>('featuresMinVolume').value);
      const band = Number($<HTMLInputElement>('featuresBand').value);
      const depths = $<HTMLInputElement>('featuresDepths').value.split(',').map((t) => t.trim()).filter((t) => t !== '').map(Number);
      if (!(minVolume >= 0)) { this.host.showError(`features: minimum volume ${$<HTMLInputElement>('featuresMinVolume').value} km³ must be a number ≥ 0`); this.sync(); return; }
      if (!(band >= 0)) { this.host.showError(`features: band half-width ${$<HTMLInputElement>('featuresBand').value} km must be a number ≥ 0`); this.sync(); return; }
      // The grid's depths (the server's depth coordinate): a stall or a shell's flux needs them inside.
      const grid = this.store.info.coordinates.find((c) => c.name === 'depth');
      const [lo, hi] = grid ? [grid.min, grid.max] : [0, 6371];
      if (!depths.length || depths.some((d) => !(d >= lo && d <= hi))) { this.host.showError(`features: depths must be numbers from ${+lo.toFixed(1)} to ${+hi.toFixed(1)} km (the grid's), comma-separated`); this.sync(); return; }
      s.minVolumeKm3 = minVolume;
      s.bandHalfWidthKm = band;
      s.depthsKm = depths;
      this.host.commit(false);
    };
    for (const id of ['featuresMinVolume', 'featuresBand', 'featuresDepths']) $(id).addEventListener('change', settings);
    $('featuresStallBy').addEventListener('change', () => {
      this.stallChosen = true;
      this.store.state.features.stallBy = $<HTMLSelectElement>('featuresStallBy').value;
      this.host.commit(false);
    });
    for (const [id, what] of [['featuresTracksCsv', 'tracks'], ['featuresEventsCsv', 'events'], ['featuresStallsCsv', 'stalls'], ['featuresFluxCsv', 'flux']] as const)
      $(id).addEventListener('click', () => this.exportCsv(what));
    $('featuresTimeDepthCsv').addEventListener('click', () => {
      const state = cloneState(this.store.state);
      if (!state.brushes.length) { this.host.showError('features: brush an axis first'); return; }
      const of = $<HTMLSelectElement>('featuresTimeDepthOf').value;
      postTimeDepthCsv(state, of === 'share' ? undefined : state.color.variable)
        .then((csv) => download(new Blob([csv], { type: 'text/csv' }), 'raypc-time-depth.csv'))
        .catch((e) => this.host.showError((e as Error).message));
    });
    // Hovering a row highlights its track's feature of the step in the 3D view (after 150 ms, so
    // that moving across the table asks for no frames); leaving the table returns to the chosen track.
    $('featuresTable').addEventListener('mouseover', (e) => {
      const tr = (e.target as HTMLElement).closest('tr');
      const track = tr?.dataset.track ? Number(tr.dataset.track) : null;
      window.clearTimeout(this.hoverTimer);
      if (track !== this.hoverTrack) this.hoverTimer = window.setTimeout(() => this.hover(track), 150);
    });
    $('featuresTable').addEventListener('mouseleave', () => {
      window.clearTimeout(this.hoverTimer);
      this.hover(null);
    });
    $('featuresTable').addEventListener('click', (e) => {
      const th = (e.target as HTMLElement).closest('th');
      if (th?.dataset.sort) {
        const key = th.dataset.sort as SortKey;
        this.sort = { key, descending: this.sort.key === key ? !this.sort.descending : key !== 'track' && key !== 'firstStep' };
        this.drawTable();
        return;
      }
      const tr = (e.target as HTMLElement).closest('tr');
      if (tr?.dataset.track) this.selectTrack(Number(tr.dataset.track), true);
    });
  }

  // The settings' fields from the state.
  sync(): void {
    const s = this.store.state.features;
    $<HTMLInputElement>('featuresColorById').checked = s.colorById;
    $<HTMLInputElement>('featuresMinVolume').value = String(s.minVolumeKm3);
    $<HTMLInputElement>('featuresBand').value = String(s.bandHalfWidthKm);
    $<HTMLInputElement>('featuresDepths').value = s.depthsKm.join(', ');
    $<HTMLSelectElement>('featuresStallBy').value = s.stallBy;
    this.showStallMeasure();
  }

  // A state was loaded (a file, a preset, a link, the URL): a document whose features.stallBy is
  // neither the default nor what its selection implies was chosen, and keeps it; otherwise the
  // measure follows the selection. A document that names the default cannot be told from one that
  // names none (a preset written before stallBy existed, a saved state of the first view), so the
  // default counts as not chosen.
  stateLoaded(doc: unknown): void {
    const named = (doc as { features?: { stallBy?: unknown } } | null)?.features?.stallBy;
    this.stallChosen = typeof named === 'string' && named !== this.store.defaults.features.stallBy
      && named !== impliedStallBy(this.store.state.brushes, this.store.info.variables).stallBy;
  }

  // Sets features.stallBy to what the selection implies unless the user chose one (called before the
  // features are asked for, so that the request and a saved state carry the measure used), and says
  // in the panel which measure times the stalls and why; warns when the selection brushes depth.
  private showStallMeasure(): void {
    const s = this.store.state;
    const implied = impliedStallBy(s.brushes, this.store.info.variables);
    if (!this.stallChosen && s.features.stallBy !== implied.stallBy) {
      s.features.stallBy = implied.stallBy;
      $<HTMLSelectElement>('featuresStallBy').value = implied.stallBy;
    }
    const by = s.features.stallBy as StallBy;
    $('featuresStallNote').textContent = this.stallChosen
      ? `stalls timed by the ${kStallByWords[by] ?? by}: your choice${by === implied.stallBy ? '' : ` (the selection implies the ${kStallByWords[implied.stallBy]}: ${implied.why})`}`
      : `stalls timed by the ${kStallByWords[by]}: ${implied.why}; choose another under "stall by"`;
    // A brush on depth cuts every feature at its ends: a track whose tip or head reaches a brushed
    // end stays there, and reads as a stall at any depth of the band near it.
    const depth = s.brushes.filter((b) => b.name === 'depth' || b.name === 'radius');
    const warning = $('featuresDepthWarning');
    warning.hidden = depth.length === 0;
    warning.textContent = depth.length
      ? `⚠ The selection brushes ${depth.map((b) => `${b.name} ${fmt(b.min)}–${fmt(b.max)} km`).join(' and ')}: stalls at depths near the brush's ends are an artefact of the brush (features are cut there). Clear the ${depth[0].name} brush to time real stalls.`
      : '';
  }

  private open(): boolean {
    return $<HTMLDetailsElement>('featuresDetails').open;
  }

  // Asks for the features when the panel is open and the selection, the feature settings or the
  // picture's choice changed (debounced; `now` asks at once).
  refresh(now = false): void {
    const state = this.store.state;
    if (!this.open()) return;
    if (!state.brushes.length) {
      this.abort?.abort();
      this.key = '';
      this.setResult(null);
      $('featuresNote').textContent = 'Brush an axis: its connected regions are followed through the series here.';
      return;
    }
    this.showStallMeasure();
    const of = $<HTMLSelectElement>('featuresTimeDepthOf').value;
    const { highlight: _h, colorById: _c, ...settings } = state.features; // painting asks nothing new
    const key = JSON.stringify([state.brushes, settings, of]);
    if (key === this.key) {
      this.drawTimeline();
      this.drawFlux();
      return;
    }
    clearTimeout(this.timer);
    this.timer = window.setTimeout(() => this.ask(key, of), now ? 0 : 300);
  }

  private ask(key: string, of: string): void {
    this.abort?.abort();
    const ctl = new AbortController();
    this.abort = ctl;
    this.key = key;
    const state = cloneState(this.store.state);
    const steps = this.store.info.steps.length;
    const start = performance.now();
    $('featuresCancel').hidden = false;
    // The server says how many steps are done (GET /api/job-progress, asked every 400 ms, one at a time).
    const job = `features-${Date.now().toString(36)}-${Math.random().toString(36).slice(2, 10)}`;
    let progress: JobProgress | null = null, asking = false, lastAsked = 0;
    const tick = () => {
      const seconds = ((performance.now() - start) / 1000).toFixed(1);
      $('featuresNote').textContent = progress?.state === 'running' || progress?.state === 'done'
        ? `finding the features: step ${progress.done} of ${progress.total} done at level ${state.features.level}… ${seconds} s`
        : progress?.state === 'unknown' && performance.now() - start > 1000
          ? `waiting for another statistics request to finish… ${seconds} s`
          : `finding the features of ${steps} steps at level ${state.features.level}… ${seconds} s`;
      if (!asking && performance.now() - lastAsked >= 400) {
        asking = true;
        lastAsked = performance.now();
        getJobProgress(job, ctl.signal)
          .then((p) => { if (!ctl.signal.aborted) progress = p; })
          .catch(() => {}) // the answer itself reports failures
          .finally(() => { asking = false; });
      }
    };
    tick();
    clearInterval(this.ticker);
    this.ticker = window.setInterval(tick, 200);
    postFeatures(state, job, ctl.signal)
      .then((f) => {
        if (ctl.signal.aborted) return;
        this.stopTicker('');
        this.setResult(f, performance.now() - start);
      })
      .catch((e) => {
        if (ctl.signal.aborted) return;
        this.key = '';
        this.stopTicker(`not found: ${(e as Error).message}`);
        this.host.showError((e as Error).message);
      });
    const width = Math.max(320, Math.round(($('featuresPanel').clientWidth || 300) * devicePixelRatio));
    const meanVar = of === 'share' ? undefined : state.color.variable;
    postTimeDepth(state, of, meanVar, width, Math.round(width * 0.9), ctl.signal)
      .then((png) => {
        if (ctl.signal.aborted) return;
        if (this.timeDepthUrl) URL.revokeObjectURL(this.timeDepthUrl);
        this.timeDepthUrl = URL.createObjectURL(png);
        $<HTMLImageElement>('featuresTimeDepth').src = this.timeDepthUrl;
        this.observer?.timeDepth(true);
      })
      .catch((e) => {
        if (ctl.signal.aborted) return;
        this.observer?.timeDepth(false);
        this.host.showError((e as Error).message);
      });
  }

  private stopTicker(note: string): void {
    clearInterval(this.ticker);
    $('featuresCancel').hidden = true;
    if (note) $('featuresNote').textContent = note;
  }

  private setResult(f: FeatureSeries | null, ms = 0): void {
    this.result = f;
    this.observer?.features(f);
    // A new answer numbers features and tracks anew: the highlight follows the chosen track if it is
    // still there, else goes.
    if (this.selectedTrack !== null && !(f && f.tracks.some((t) => t.track === this.selectedTrack))) this.selectedTrack = null;
    this.hoverTrack = null;
    const before = JSON.stringify(this.store.state.features.highlight);
    if (this.selectedTrack === null) this.store.state.features.highlight = [];
    else this.stepChanged();
    if (JSON.stringify(this.store.state.features.highlight) !== before) this.host.commit(false);
    if (f) {
      const counts = new Map<string, number>();
      for (const e of f.events) counts.set(e.kind, (counts.get(e.kind) ?? 0) + 1);
      const events = ['birth', 'death', 'merge', 'split'].map((k) => `${counts.get(k) ?? 0} ${k}${(counts.get(k) ?? 0) === 1 ? '' : k === 'birth' ? 's' : 's'}`).join(', ');
      const n = f.steps.reduce((a, s) => a + s.features, 0);
      $('featuresNote').textContent = `${f.level === 0 ? 'exact (level 0 grid)' : `approximate (level ${f.level} grid)`}: ${n} features in ${f.steps.length} steps, ${f.tracks.length} tracks; ${events}${ms ? ` · ${(ms / 1000).toFixed(1)} s` : ''}`;
    }
    this.drawTable();
    this.drawTimeline();
    this.drawFlux();
  }

  private stallMyr(t: FeatureTrack): number {
    return this.stallsShown(t).reduce((a, s) => Math.max(a, s.durationMyr), -1);
  }

  // The stalls worth a line: a track that only crossed a depth within one step (0 Myr) did not stall.
  private stallsShown(t: FeatureTrack): FeatureTrack['stalls'] {
    return t.stalls.filter((s) => s.durationMyr > 0);
  }

  private eventCount(track: number): number {
    return this.result ? this.result.events.filter((e) => e.track === track).length : 0;
  }

  private drawTable(): void {
    const table = $('featuresTable');
    table.innerHTML = '';
    const f = this.result;
    if (!f) return;
    const value = (t: FeatureTrack): number => {
      switch (this.sort.key) {
        case 'stallMyr': return this.stallMyr(t);
        case 'events': return this.eventCount(t.track);
        default: return t[this.sort.key];
      }
    };
    const tracks = [...f.tracks].sort((a, b) => (this.sort.descending ? value(b) - value(a) : value(a) - value(b)) || a.track - b.track);
    const head = document.createElement('tr');
    const columns: [SortKey, string, string][] = [
      // The stalls next to the track's id: the answer a task reads stays in sight in a narrow panel.
      ['track', 'track', 'track id'],
      ['stallMyr', 'stalls', 'time at each depth (its stall-by depth within the band), and how it left (↓ down, ↑ up, † ended)'],
      ['firstStep', 'steps', 'first and last step'],
      ['lifetimeMyr', 'Myr', 'lifetime, Myr'],
      ['maxVolumeKm3', 'max km³', 'largest volume, km³'],
      ['meanDepthKm', 'depth km', 'mean over its steps of its mean depth, km'],
      ['events', 'events', 'how many births, deaths, merges and splits this track has (the list: hover the number)'],
    ];
    for (const [key, text, title] of columns) {
      const th = document.createElement('th');
      th.dataset.sort = key;
      th.title = `${title}; click to sort`;
      th.textContent = text + (this.sort.key === key ? (this.sort.descending ? ' ▾' : ' ▴') : '');
      head.appendChild(th);
    }
    table.appendChild(head);
    const arrow: Record<string, string> = { down: ' ↓', up: ' ↑', ended: ' †', '': '' };
    for (const t of tracks) {
      const tr = document.createElement('tr');
      tr.dataset.track = String(t.track);
      if (t.track === this.selectedTrack) tr.classList.add('selected');
      const events = f.events.filter((e) => e.track === t.track).map((e) => `${e.kind} @${e.step}`);
      const cells = [
        String(t.track),
        '', // the stalls, one line each (below)
        t.firstStep === t.lastStep ? String(t.firstStep) : `${t.firstStep}–${t.lastStep}`,
        t.lifetimeMyr.toFixed(1),
        fmtVolume(t.maxVolumeKm3),
        t.meanDepthKm.toFixed(0),
        // Their count, the list in the tooltip: the whole list made the rows tall and the table wider
        // than the side panel, pushing the stalls out of sight.
        events.length ? String(events.length) : '',
      ];
      for (const c of cells) {
        const td = document.createElement('td');
        td.textContent = c;
        tr.appendChild(td);
      }
      if (events.length)
        (tr.lastElementChild as HTMLElement).title = events.join(', ');
      const stallCell = tr.children[1] as HTMLElement;
      stallCell.classList.add('stalls');
      for (const st of this.stallsShown(t)) {
        const span = document.createElement('span');
        span.className = 'stall';
        span.textContent = `${st.depthKm} km: ${fmtMyr(st.durationMyr)} Myr${arrow[st.left] ?? ''}`;
        stallCell.appendChild(span);
      }
      // The colour the 3D view paints the track's feature of the current step in (features.colorById).
      const now = t.points.find((p) => p.step === this.store.state.step);
      const swatch = tr.firstElementChild as HTMLElement;
      if (now) {
        const [r, g, b] = this.store.info.featurePalette[(now.feature - 1) % 10 + 1].map((c) => Math.round(255 * c));
        swatch.style.borderLeft = `6px solid rgb(${r},${g},${b})`;
        swatch.title = `track ${t.track} (its feature ${now.feature} of step ${now.step}): this colour in the 3D view when coloured by feature`;
      }
      tr.title = `track ${t.track}: hover to highlight its feature of this step in the 3D view, click to show it from its first step`;
      table.appendChild(tr);
    }
  }

  // The track under the pointer (null: none) is highlighted in the 3D view, or else the chosen one.
  private hover(track: number | null): void {
    if (track === this.hoverTrack) return;
    this.hoverTrack = track;
    const s = this.store.state;
    if ((this.hoverTrack ?? this.selectedTrack) === null) s.features = { ...s.features, highlight: [] };
    else s.features = this.forStep(s, s.step).features;
    this.host.commit(false);
  }

  // Chooses a track: its row is marked, its timeline drawn and (`move`) the time slider goes to its
  // first step.
  selectTrack(track: number, move: boolean): void {
    const t = this.result?.tracks.find((x) => x.track === track);
    if (!t) return;
    this.selectedTrack = track;
    for (const tr of $('featuresTable').querySelectorAll<HTMLElement>('tr[data-track]'))
      tr.classList.toggle('selected', Number(tr.dataset.track) === track);
    this.drawTimeline();
    if (move && this.store.state.step !== t.firstStep) this.host.setStep(t.firstStep, false); // highlights (stepChanged)
    else {
      this.stepChanged();
      this.host.commit(false);
    }
  }

  // The legend of the 3D view while it paints features (render/feature_paint.h: the same palette),
  // else null.
  paintLegend(): LegendEntry | null {
    const s = this.store.state, f = s.features;
    if (!s.brushes.length || (!f.colorById && !f.highlight.length)) return null;
    const slot = (k: number) => this.store.info.featurePalette[k] as [number, number, number];
    // The table's id space: the highlight is sent as the step's feature ids (what the renderer
    // paints), but the reader chose a track, so the legend names the track; a highlight from a loaded
    // state with no track behind it names its features of the step.
    const track = this.hoverTrack ?? this.selectedTrack;
    const what = track !== null && f.highlight.length
      ? `track ${track}`
      : `feature${f.highlight.length > 1 ? 's' : ''} ${f.highlight.join(', ')} of step ${s.step}`;
    if (f.colorById)
      return { title: `features by id (colours repeat every 10; the table's colour marks give each track's)${f.highlight.length ? `; highlighted: ${what}` : ''}; dark grey: the rest of the selection`,
        colorAt: (u) => slot(1 + Math.min(9, Math.floor(u * 10))), valueAt: (u) => 1 + Math.round(u * 9),
        ticks: Array.from({ length: 10 }, (_, k) => ({ at: (k + 0.5) / 10, text: String(k + 1) })) };
    return { title: `highlighted ${what} (amber); dark grey: the rest of the selection`,
      colorAt: (u) => slot(u < 0.5 ? 0 : 11), valueAt: (u) => (u < 0.5 ? 0 : f.highlight[0]),
      ticks: [{ at: 0.25, text: 'rest' }, { at: 0.75, text: 'highlighted' }] };
  }

  // The hovered or else the chosen track's feature at `step` highlighted in `s` (the store's state
  // unless given): none where the track has no feature. Call before a state of a new step is sent.
  forStep(s: RenderState, step: number): RenderState {
    const t = this.result?.tracks.find((x) => x.track === (this.hoverTrack ?? this.selectedTrack));
    if (!t) return s;
    const p = t.points.find((x) => x.step === step);
    return { ...s, features: { ...s.features, highlight: p ? [p.feature] : [] } };
  }

  // The store's step changed: the chosen track's feature of that step is highlighted; the timeline's
  // mark and the table's colour marks (the features' ids of that step) follow.
  stepChanged(): void {
    const s = this.store.state;
    if ((this.hoverTrack ?? this.selectedTrack) !== null && this.result) s.features = this.forStep(s, s.step).features;
    if (this.result) this.drawTable();
    this.drawTimeline();
  }

  // The chosen track's mean depth (depth down, the state's depths dashed, the stall bands shaded)
  // and its volume against time, the current step marked.
  private drawTimeline(): void {
    const svg = $('featuresTimeline') as unknown as SVGSVGElement;
    const f = this.result;
    const t = f?.tracks.find((x) => x.track === this.selectedTrack);
    $('featuresTimelineNote').textContent = t ? `track ${t.track}: steps ${t.firstStep}–${t.lastStep}` : 'Click a track in the table for its timeline.';
    if (!f || !t) {
      d3.select(svg).selectAll('*').remove();
      return;
    }
    const { g, iw, ih } = frame(svg, 58); // the volume's axis on the right (labels like 1.2e+8)
    const times = f.steps.map((s) => s.timeMyr);
    const xs = d3.scaleLinear().domain(d3.extent(times) as [number, number]).range([0, iw]);
    if (times.length < 2) xs.domain([times[0] - 1, times[0] + 1]);
    const depths = [...t.points.flatMap((p) => [p.topDepthKm, p.bottomDepthKm]), ...f.depthsKm];
    const ys = d3.scaleLinear().domain([d3.min(depths) ?? 0, d3.max(depths) ?? 2886]).nice().range([0, ih]);
    const vs = d3.scaleLinear().domain([0, d3.max(t.points, (p) => p.volumeKm3) ?? 1]).nice().range([ih, 0]);
    const x = (v: number) => xs(v) as number, y = (v: number) => ys(v) as number;
    g.append('g').attr('class', 'axis').attr('transform', `translate(0,${ih})`).call(d3.axisBottom(xs).ticks(5).tickFormat(d3.format('~g')));
    g.append('g').attr('class', 'axis').call(d3.axisLeft(ys).ticks(5).tickFormat(d3.format('~g')));
    g.append('g').attr('class', 'axis').attr('transform', `translate(${iw},0)`).call(d3.axisRight(vs).ticks(3).tickFormat(d3.format('.1e')));
    g.append('text').attr('x', iw).attr('y', ih + 32).attr('text-anchor', 'end').text('time [Myr]');
    g.append('text').attr('x', -kMargin.left + 2).attr('y', -kMargin.top + 3).attr('dominant-baseline', 'hanging').text('depth [km]');
    for (const d of f.depthsKm) {
      if (d < ys.domain()[0] || d > ys.domain()[1]) continue;
      g.append('rect').attr('x', 0).attr('width', iw).attr('y', y(d - f.bandHalfWidthKm)).attr('height', Math.max(1, y(d + f.bandHalfWidthKm) - y(d - f.bandHalfWidthKm)))
        .attr('fill', 'rgba(255,255,255,0.06)');
      g.append('line').attr('x1', 0).attr('x2', iw).attr('y1', y(d)).attr('y2', y(d)).attr('stroke', '#aaa').attr('stroke-dasharray', '4,3');
      g.append('text').attr('x', iw - 2).attr('y', y(d) - 2).attr('text-anchor', 'end').attr('class', 'mark').text(`${d} km`);
    }
    // The depth extent as a band, the mean depth as a line; the volume on the right axis.
    g.append('path').datum(t.points).attr('fill', 'rgba(138,180,248,0.2)')
      .attr('d', d3.area<(typeof t.points)[number]>().x((p) => x(p.timeMyr)).y0((p) => y(p.topDepthKm)).y1((p) => y(p.bottomDepthKm)));
    g.append('path').datum(t.points).attr('class', 'trackDepth').attr('fill', 'none').attr('stroke', '#8ab4f8').attr('stroke-width', 1.8)
      .attr('d', d3.line<(typeof t.points)[number]>().x((p) => x(p.timeMyr)).y((p) => y(p.meanDepthKm)));
    g.append('path').datum(t.points).attr('fill', 'none').attr('stroke', '#f4a259').attr('stroke-width', 1.2).attr('stroke-dasharray', '5,2')
      .attr('d', d3.line<(typeof t.points)[number]>().x((p) => x(p.timeMyr)).y((p) => vs(p.volumeKm3) as number));
    g.selectAll('circle.point').data(t.points).enter().append('circle').attr('class', 'point')
      .attr('cx', (p) => x(p.timeMyr)).attr('cy', (p) => y(p.meanDepthKm)).attr('r', 2.2).attr('fill', '#8ab4f8')
      .append('title').text((p) => `step ${p.step}, ${p.timeMyr.toFixed(1)} Myr: track ${t.track} (feature ${p.feature} of the step), mean depth ${p.meanDepthKm.toFixed(0)} km (${p.topDepthKm.toFixed(0)}–${p.bottomDepthKm.toFixed(0)}), ${p.volumeKm3.toExponential(2)} km³${p.radialVelocityCmPerYr === null ? '' : `, v_r ${p.radialVelocityCmPerYr.toFixed(2)} cm/yr`}`);
    const cur = f.steps.find((s) => s.step === this.store.state.step);
    if (cur) g.append('line').attr('x1', x(cur.timeMyr)).attr('x2', x(cur.timeMyr)).attr('y1', 0).attr('y2', ih).attr('stroke', '#ffcc4d').attr('stroke-dasharray', '3,2');
    g.append('text').attr('x', iw + 56).attr('y', -kMargin.top + 3).attr('dominant-baseline', 'hanging').attr('text-anchor', 'end')
      .style('fill', '#f4a259').text('volume [km³]');
  }

  // The downward flux across each depth of the state (whole shell, and within the selection dashed)
  // against time; avalanche steps marked. The flux within the selection (a few slabs' share of the
  // whole shell's) has its own scale, the right axis: on the whole shell's it was flat near zero.
  // The depths' legend is under the plot (in the note), never over its lines.
  private drawFlux(): void {
    const svg = $('featuresFlux') as unknown as SVGSVGElement;
    const flux = this.result?.flux;
    if (!flux || !flux.steps.length) {
      d3.select(svg).selectAll('*').remove();
      $('featuresFluxNote').textContent = this.result ? `no flux: the dataset has no ${kRadialVelocity}` : '';
      return;
    }
    const { g, iw, ih } = frame(svg, 50); // the selection's axis on the right
    const xs = d3.scaleLinear().domain(d3.extent(flux.steps, (s) => s.timeMyr) as [number, number]).range([0, iw]);
    const all = flux.steps.flatMap((s) => s.downKm3PerYr.map((v) => -v));
    const ys = d3.scaleLinear().domain([0, (d3.max(all) ?? 1) * 1.05 || 1]).nice().range([ih, 0]);
    const selected = flux.steps.flatMap((s) => s.selectedDownKm3PerYr.map((v) => -v));
    const ss = d3.scaleLinear().domain([Math.min(0, d3.min(selected) ?? 0), (d3.max(selected) ?? 1) * 1.05 || 1]).nice().range([ih, 0]);
    const x = (v: number) => xs(v) as number, y = (v: number) => ys(v) as number, ySel = (v: number) => ss(v) as number;
    g.append('g').attr('class', 'axis').attr('transform', `translate(0,${ih})`).call(d3.axisBottom(xs).ticks(5).tickFormat(d3.format('~g')));
    g.append('g').attr('class', 'axis').call(d3.axisLeft(ys).ticks(4).tickFormat(d3.format('~g')));
    g.append('g').attr('class', 'axis selectedAxis').attr('transform', `translate(${iw},0)`).call(d3.axisRight(ss).ticks(4).tickFormat(d3.format('~g')));
    g.append('text').attr('x', iw).attr('y', ih + 32).attr('text-anchor', 'end').text('time [Myr]');
    g.append('text').attr('x', -kMargin.left + 2).attr('y', -kMargin.top + 3).attr('dominant-baseline', 'hanging').text('downward flux [km³/yr]: shell');
    g.append('text').attr('x', iw + 48).attr('y', -kMargin.top + 3).attr('dominant-baseline', 'hanging').attr('text-anchor', 'end').text('selection ┆');
    const colors = d3.schemeTableau10;
    flux.depthsKm.forEach((depth, d) => {
      const c = colors[d % colors.length];
      const pts = flux.steps.map((s) => ({ t: s.timeMyr, v: -s.downKm3PerYr[d], sel: -s.selectedDownKm3PerYr[d], step: s.step }));
      g.append('path').datum(pts).attr('fill', 'none').attr('stroke', c).attr('stroke-width', 1.5)
        .attr('d', d3.line<{ t: number; v: number }>().x((p) => x(p.t)).y((p) => y(p.v)));
      g.append('path').datum(pts).attr('class', 'selectedFlux').attr('fill', 'none').attr('stroke', c).attr('stroke-width', 1.2).attr('stroke-dasharray', '3,2')
        .attr('d', d3.line<{ t: number; sel: number }>().x((p) => x(p.t)).y((p) => ySel(p.sel)));
      for (const a of flux.avalanches.filter((a) => a.depthKm === depth)) {
        const p = pts.find((q) => q.step === a.step);
        if (p) g.append('circle').attr('class', 'avalanche').attr('cx', x(p.t)).attr('cy', y(p.v)).attr('r', 4.5)
          .attr('fill', 'none').attr('stroke', '#ff5252').attr('stroke-width', 2)
          .append('title').text(`avalanche across ${depth} km at step ${a.step}: ${p.v.toFixed(1)} km³/yr down`);
      }
    });
    const n = flux.avalanches.length;
    const note = $('featuresFluxNote');
    note.replaceChildren(...flux.depthsKm.map((depth, d) => {
      const key = document.createElement('span');
      key.className = 'fluxKey';
      key.style.color = colors[d % colors.length];
      key.textContent = `■ ${depth} km `;
      return key;
    }), `solid: the whole shell (left axis), dashed: within the selection (right axis); ${n ? `${n} avalanche step${n === 1 ? '' : 's'} (red: downward flux above the mean + ${flux.sigmas} σ)` : `no avalanche (no step's downward flux above the mean + ${flux.sigmas} σ)`}`);
  }

  // The CSV files of `raypc features --tracks/--events/--stalls` and `raypc flux`, as the server wrote them.
  private exportCsv(what: 'tracks' | 'events' | 'stalls' | 'flux'): void {
    const f = this.result;
    if (!f) { this.host.showError('features: nothing to export yet'); return; }
    // The server's tables, written by the command line's code (analysis/feature_csv.h).
    const csv = f.csv[what];
    if (csv === null) { this.host.showError(`features: no flux (the dataset has no ${kRadialVelocity})`); return; }
    download(new Blob([csv], { type: 'text/csv' }), `raypc-features-${what}.csv`);
  }
}
