// The Selection panel: the brushed ranges and the exact share of the mantle they select
// (POST /api/selection, or the quick figure of an interactive frame while brushing), and the
// selection over time (POST /api/stats) as two plots.
import { postSelection, postStats, type Selection, type SelectionOverTime } from './api';
import { cloneState } from './state';
import { drawProfilePlot, drawTimePlot } from './stats_plot';
import type { StateStore } from './store';
import { displayUnits } from './units';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;

export interface SelectionPanelHost {
  showError(message: string): void;
  playing(): boolean;
  // The selection changed (the status line shows it).
  selectionChanged(): void;
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
  observer: SelectionPanelObserver | null = null;
  private selectionAbort: AbortController | null = null;
  private stats: SelectionOverTime | null = null;
  private statsKey = '';
  private statsAbort: AbortController | null = null;
  private statsTimer = 0;

  constructor(private readonly store: StateStore, private readonly host: SelectionPanelHost) {
    $('statsExact').addEventListener('change', () => this.refreshStats());
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

  setSelection(s: Selection): void {
    this.selection = s;
    this.observer?.selection(s);
    this.updateText();
    this.host.selectionChanged();
  }

  updateText(): void {
    const el = $('selection');
    const state = this.store.state;
    if (!state.brushes.length) {
      el.textContent = 'no brushes: the whole mantle';
      return;
    }
    const s = this.selection;
    const axes = this.store.axes();
    const ranges = state.brushes.map((b) => {
      const a = axes.find((x) => x.name === b.name);
      return `${b.name} ${fmt(b.min)} … ${fmt(b.max)}${a?.units ? ' ' + displayUnits(a.units) : ''}`;
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

  // Asks for the statistics when the brushes, the step or the level asked for changed (debounced;
  // not while playing, when only the current-step mark moves).
  refreshStats(): void {
    const exact = $<HTMLInputElement>('statsExact').checked;
    const state = this.store.state;
    if (!state.brushes.length) {
      this.statsAbort?.abort();
      this.stats = null;
      this.observer?.stats(null);
      this.statsKey = '';
      $('statsNote').textContent = 'Brush an axis to see the selected volume over time.';
      for (const id of ['statsTime', 'statsProfile']) $(id).innerHTML = '';
      return;
    }
    const key = JSON.stringify([state.brushes, state.step, exact]);
    if (this.stats) drawTimePlot($('statsTime') as unknown as SVGSVGElement, this.stats, state.step);
    if (key === this.statsKey || this.host.playing()) return;
    clearTimeout(this.statsTimer);
    this.statsTimer = window.setTimeout(() => {
      this.statsAbort?.abort();
      const ctl = new AbortController();
      this.statsAbort = ctl;
      this.statsKey = key;
      this.observer?.statsRequested();
      $('statsNote').textContent = 'computing…';
      postStats(cloneState(this.store.state), exact ? 0 : undefined, ctl.signal)
        .then((st) => {
          if (ctl.signal.aborted) return;
          this.stats = st;
          this.observer?.stats(st);
          const step = this.store.state.step;
          const cur = st.steps.find((x) => x.step === step);
          $('statsNote').textContent = `level ${st.level}${st.level === 0 ? ' (exact)' : ''} · now ${cur ? (cur.fractionOfMantle * 100).toFixed(2) : '?'} % · ` +
            `range ${(Math.min(...st.steps.map((x) => x.fractionOfMantle)) * 100).toFixed(2)}–${(Math.max(...st.steps.map((x) => x.fractionOfMantle)) * 100).toFixed(2)} %`;
          drawTimePlot($('statsTime') as unknown as SVGSVGElement, st, step);
          drawProfilePlot($('statsProfile') as unknown as SVGSVGElement, st);
        })
        .catch((e) => { if (!ctl.signal.aborted) { this.statsKey = ''; this.host.showError((e as Error).message); } });
    }, 250);
  }
}
