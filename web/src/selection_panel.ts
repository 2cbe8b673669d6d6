// The Selection panel: the brushed ranges and the exact share of the mantle they select
// (POST /api/selection, or the quick figure of an interactive frame while brushing), and the
// selection over time (POST /api/stats) as two plots.
import { postSelection, postStats, type Selection, type SelectionOverTime } from './api';
import { cloneState } from './state';
import { drawProfilePlot, drawTimePlot } from './stats_plot';
import { download } from './controls';
import { selectionOverTimeColumns } from './names';
import type { StateStore } from './store';
import type { SelectionFigure } from './view_readout';
import { displayUnits } from './units';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;

export interface SelectionPanelHost {
  showError(message: string): void;
  // Replaces the range state.brushes[index] (null: removes it) and sends the state.
  setBrush(index: number, range: [number, number] | null): void;
  playing(): boolean;
  // The selection changed (the status line shows it).
  selectionChanged(): void;
  commit(interactive: boolean): void;
}

// What the browser tests observe (test_hooks.ts).
export interface SelectionPanelObserver {
  selection(s: Selection): void;
  stats(s: SelectionOverTime | null): void;
  statsRequested(): void;
}

export function fmt(v: number): string {
  return Math.abs(v) >= 1e4 || (Math.abs(v) < 1e-2 && v !== 0) ? v.toExponential(3) : String(+v.toPrecision(4));
}

export class SelectionPanel {
  selection: Selection | null = null;
  // The level of the grid `selection` was counted on: 0 exact (POST /api/selection), above 0 an
  // interactive or playback frame's quick figure.
  selectionLevel = 0;
  observer: SelectionPanelObserver | null = null;
  private selectionAbort: AbortController | null = null;
  private stats: SelectionOverTime | null = null;
  private statsKey = '';
  private statsBrushes = ''; // the brushes `stats` are of
  private statsAbort: AbortController | null = null;
  private statsTimer = 0;
  // The user turned "show the selection" off: brushing no longer turns it on by itself.
  private showDeclined = false;

  constructor(private readonly store: StateStore, private readonly host: SelectionPanelHost) {
    $<HTMLInputElement>('showSelection').addEventListener('change', (e) => {
      const on = (e.target as HTMLInputElement).checked;
      this.showDeclined = !on;
      this.store.state.selection.show = on;
      this.syncShow();
      this.host.commit(false);
    });
    $('statsExact').addEventListener('change', () => this.refreshStats());
    $('statsCsv').addEventListener('click', () => {
      const st = this.stats;
      if (!st) return;
      // The columns of `raypc stats -o` (docs/ui.md), plus the level the figures are exact on.
      let csv = `${[...selectionOverTimeColumns, 'level'].join(',')}\n`;
      for (const s of st.steps) csv += `${s.step},${s.timeMyr},${s.volumeKm3.toExponential(6)},${(100 * s.fractionOfMantle).toFixed(6)},${st.level}\n`;
      download(new Blob([csv], { type: 'text/csv' }), `raypc-selection-over-time-step${this.store.state.step}.csv`);
    });
  }

  // Brushing begins (the first brush after none): from the default view, whose opacity curve hides
  // anomalies of a few tens of kelvin, "show the selection" is turned on, so that what is
  // brushed is seen, unless the user turned it off before. Call before the
  // state is sent.
  brushingStarted(): void {
    const s = this.store.state, d = this.store.defaults;
    if (this.showDeclined || s.selection.show) return;
    if (JSON.stringify(s.color) !== JSON.stringify(d.color)) return;
    s.selection.show = true;
    this.syncShow();
  }

  // The toggle and its note from the state.
  syncShow(): void {
    const s = this.store.state;
    $<HTMLInputElement>('showSelection').checked = s.selection.show;
    $('showSelectionNote').textContent = s.selection.show && s.brushes.length
      ? `selected material ≥ ${Math.round(100 * s.selection.minOpacity)} % opaque per ${+s.color.opacityUnitKm.toPrecision(4)} km`
      : '';
  }

  refreshSelection(): void {
    this.selectionAbort?.abort();
    const state = this.store.state;
    if (!state.brushes.length) {
      this.setSelection({ fractionOfMantle: 1, volumeKm3: NaN, step: state.step });
      return;
    }
    const ctl = new AbortController();
    this.selectionAbort = ctl;
    postSelection(state, ctl.signal)
      .then((s) => { if (!ctl.signal.aborted) this.setSelection(s); })
      .catch((e) => { if (!ctl.signal.aborted) this.host.showError((e as Error).message); });
  }

  setSelection(s: Selection, level = 0): void {
    // A frame's quick figure (a coarse level; playback's) gives way to the statistics over time's
    // figure of its step where those are finer (exact when asked exact): the panel then agrees with
    // the exact range beside it.
    const st = this.stats;
    const p = level > 0 && st && st.level < level && s.step !== undefined && this.statsBrushes === JSON.stringify(this.store.state.brushes)
      ? st.steps.find((x) => x.step === s.step) : undefined;
    if (p && st) {
      s = { ...s, fractionOfMantle: p.fractionOfMantle, volumeKm3: p.volumeKm3 };
      level = st.level;
    }
    this.selection = s;
    this.selectionLevel = level;
    this.observer?.selection(s);
    this.updateText();
    this.host.selectionChanged();
  }

  // The selection's figures known for the readout on the view: the last one set, and the
  // statistics over time's figure of `step` (exact when they were asked exact).
  figures(step: number): SelectionFigure[] {
    const out: SelectionFigure[] = [];
    const s = this.selection;
    if (s && s.step !== undefined) out.push({ step: s.step, fractionOfMantle: s.fractionOfMantle, volumeKm3: s.volumeKm3, level: this.selectionLevel });
    const st = this.stats, key = JSON.stringify(this.store.state.brushes);
    const p = st && this.statsBrushes === key ? st.steps.find((x) => x.step === step) : undefined;
    if (st && p) out.push({ step, fractionOfMantle: p.fractionOfMantle, volumeKm3: p.volumeKm3, level: st.level });
    return out;
  }

  updateText(): void {
    this.syncShow();
    const el = $('selection');
    const state = this.store.state;
    if (!state.brushes.length) {
      el.textContent = 'no brushes: the whole mantle';
      return;
    }
    const axes = this.store.axes();
    // The same brushes as shown: update the figures in place, so that a field being typed in keeps
    // its element (and its text) while another field's change is applied.
    const rows = [...el.querySelectorAll<HTMLElement>('.brushRow')];
    if (rows.length === state.brushes.length && rows.every((r, i) => r.dataset.brush === state.brushes[i].name)) {
      const head = el.querySelector('#selectionValue');
      if (head) head.textContent = this.selectionText();
      rows.forEach((r, i) => {
        const b = state.brushes[i];
        for (const [cls, v] of [['brushMin', b.min], ['brushMax', b.max]] as const) {
          const input = r.querySelector<HTMLInputElement>(`input.${cls}`);
          if (input && input !== document.activeElement) input.value = String(+v.toPrecision(6));
        }
      });
      return;
    }
    el.innerHTML = '';
    const head = document.createElement('div');
    head.textContent = this.selectionText();
    head.id = 'selectionValue';
    el.appendChild(head);
    // One row per range (an axis with several has a row for each, OR-ed): its name, exact min and
    // max to type, and × to clear it.
    state.brushes.forEach((b, index) => {
      const a = axes.find((x) => x.name === b.name);
      const row = document.createElement('div');
      row.className = 'brushRow';
      row.dataset.brush = b.name;
      const name = document.createElement('span');
      name.className = 'brushName';
      name.textContent = `${b.name}${a?.units ? ` [${displayUnits(a.units)}]` : ''}`;
      name.title = name.textContent;
      const input = (value: number, which: string) => {
        const i = document.createElement('input');
        i.type = 'number';
        i.step = 'any';
        i.value = String(+value.toPrecision(6));
        i.className = `brush${which}`;
        i.setAttribute('aria-label', `${b.name} ${which.toLowerCase()}`);
        return i;
      };
      const lo = input(b.min, 'Min'), hi = input(b.max, 'Max');
      const typed = () => {
        const min = Number(lo.value), max = Number(hi.value);
        if (!(Number.isFinite(min) && Number.isFinite(max) && min <= max)) {
          this.host.showError(`brush ${b.name}: min ${lo.value} must not be greater than max ${hi.value}`);
          this.updateText();
          return;
        }
        this.host.setBrush(index, [min, max]);
      };
      lo.addEventListener('change', typed);
      hi.addEventListener('change', typed);
      const clear = document.createElement('button');
      clear.textContent = '×';
      const several = state.brushes.filter((x) => x.name === b.name).length > 1;
      clear.title = several ? `Clear this range on ${b.name}` : `Clear the brush on ${b.name}`;
      clear.className = 'brushClear';
      clear.addEventListener('click', () => this.host.setBrush(index, null));
      if (several && state.brushes.findIndex((x) => x.name === b.name) !== index) {
        name.textContent = `or ${name.textContent}`;
        row.classList.add('brushOr');
      }
      row.append(name, lo, hi, clear);
      el.appendChild(row);
    });
  }

  // Playback showed a frame of `step` (now the store's): the statistics' "now", mark and profile follow.
  stepShown(_step: number): void {
    if (this.stats && this.statsBrushes === JSON.stringify(this.store.state.brushes)) this.showStats(this.stats);
  }

  private selectionText(): string {
    const s = this.selection;
    // While playing (or when the figure is of another step than the store's) it names its step.
    const of = s?.step !== undefined && (this.host.playing() || s.step !== this.store.state.step) ? `step ${s.step}: ` : '';
    return s && Number.isFinite(s.fractionOfMantle)
      ? `${of}${this.selectionLevel > 0 ? `≈ (level ${this.selectionLevel}) ` : ''}${(s.fractionOfMantle * 100).toFixed(2)} % of the mantle${Number.isFinite(s.volumeKm3) ? `, ${s.volumeKm3.toExponential(3)} km³` : ''}`
      : 'computing…';
  }

  // Asks for the statistics when the brushes or the level asked for changed (debounced; not while
  // playing). The answer holds every step's figures and depth profile (`profiles=all`), so a step
  // change only redraws from it: the step is not part of the request's key.
  refreshStats(): void {
    const exact = $<HTMLInputElement>('statsExact').checked;
    const state = this.store.state;
    if (!state.brushes.length) {
      this.statsAbort?.abort();
      this.stats = null;
      this.statsBrushes = '';
      this.observer?.stats(null);
      this.statsKey = '';
      $('statsNote').textContent = 'Brush an axis to see the selected volume over time.';
      for (const id of ['statsTime', 'statsProfile']) $(id).innerHTML = '';
      return;
    }
    const key = JSON.stringify([state.brushes, exact]);
    if (this.stats && key === this.statsKey) this.showStats(this.stats);
    if (key === this.statsKey || this.host.playing()) return;
    clearTimeout(this.statsTimer);
    this.statsTimer = window.setTimeout(() => {
      this.statsAbort?.abort();
      const ctl = new AbortController();
      this.statsAbort = ctl;
      this.statsKey = key;
      const brushesKey = JSON.stringify(this.store.state.brushes);
      this.observer?.statsRequested();
      $('statsNote').textContent = 'computing…';
      postStats(cloneState(this.store.state), exact ? 0 : undefined, ctl.signal, true)
        .then((st) => {
          if (ctl.signal.aborted) return;
          this.stats = st;
          this.statsBrushes = brushesKey;
          this.showStats(st);
          this.host.selectionChanged(); // the readout on the view takes the exact figure of its step
        })
        .catch((e) => { if (!ctl.signal.aborted) { this.statsKey = ''; this.host.showError((e as Error).message); } });
    }, 250);
  }

  // The statistics at the store's step, from the answer over all steps: its profile (the answer's
  // `profiles`), the note's "now" figure and the time plot's mark.
  private showStats(all: SelectionOverTime): void {
    const step = this.store.state.step;
    const p = all.profiles?.find((x) => x.step === step);
    const st: SelectionOverTime = p
      ? { ...all, profile: { ...all.profile, step, volumeKm3: p.volumeKm3, shellVolumeKm3: p.shellVolumeKm3 } }
      : all;
    this.observer?.stats(st);
    const cur = st.steps.find((x) => x.step === step);
    // Exact figures (level 0) agree with the selection above and `raypc stats`; the quick ones
    // of a coarser grid are labelled as approximate.
    const pct = (x: number) => (x * 100).toFixed(2);
    const lo = Math.min(...st.steps.map((x) => x.fractionOfMantle)), hi = Math.max(...st.steps.map((x) => x.fractionOfMantle));
    $('statsNote').textContent = st.level === 0
      ? `exact: now ${cur ? pct(cur.fractionOfMantle) : '?'} % · over time ${pct(lo)}–${pct(hi)} %`
      : `approximate (level ${st.level} grid): now ≈ ${cur ? pct(cur.fractionOfMantle) : '?'} % · over time ≈ ${pct(lo)}–${pct(hi)} %`;
    drawTimePlot($('statsTime') as unknown as SVGSVGElement, st, step);
    drawProfilePlot($('statsProfile') as unknown as SVGSVGElement, st);
  }
}
