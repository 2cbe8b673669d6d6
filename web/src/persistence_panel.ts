// The persistence diagram of the step shown (GET /api/persistence, docs/persistence.md) under
// Pathlines: persistence against birth (log scale), the threshold the stored seeds were chosen with
// (below it nothing was stored), and a threshold handle to drag: it sets the pathline filter on the
// lines' "seed persistence" column (state.pathlines.filters, the same filters the pathline plot
// brushes), so only lines whose seed persistence is at least T are shown, and it highlights the
// pairs kept.
import * as d3 from 'd3';
import { fetchPersistence, type PersistenceDiagram, type PersistencePair } from './api';
import { pathlineAttribute } from './names';
import type { StateStore } from './store';
import { displayUnits } from './units';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;

// The pathline attribute the threshold filters (docs/format.md).
export const kSeedPersistence = pathlineAttribute('seedPersistence');
const kMargin = { top: 16, right: 10, bottom: 30, left: 44 };
const kKindColors: Record<string, string> = { 'minimum-saddle': '#6fa8ff', 'saddle-maximum': '#ff7a5c', global: '#f0f0f0' };

export interface PersistencePanelHost {
  commit(interactive: boolean): void;
  showError(message: string): void;
  // The line filters changed here: the pathline plot and its count follow.
  filtersChanged(interactive: boolean): void;
  // The largest value of a line attribute among the loaded lines (null before they arrived).
  columnMax(name: string): number | null;
}

export class PersistencePanel {
  // The diagram shown (the browser tests read it); null before it arrived.
  diagram: PersistenceDiagram | null = null;
  private key = '';
  private abort: AbortController | null = null;
  private dragging = false;

  constructor(private readonly store: StateStore, private readonly host: PersistencePanelHost) {
    const details = $<HTMLDetailsElement>('persistenceDetails');
    if (!store.state.pathlines) {
      details.hidden = true;
      return;
    }
    details.addEventListener('toggle', () => this.refresh());
  }

  // The threshold in force: the lower end of the state's seed-persistence filter (the largest, if
  // the name repeats), or null without one.
  threshold(): number | null {
    const fs = (this.store.state.pathlines?.filters ?? []).filter((f) => f.name === kSeedPersistence);
    return fs.length ? Math.min(...fs.map((f) => f.min)) : null;
  }

  // Loads the diagram of the step shown when it changed, the section is open and the pathlines (whose
  // seeds it shows) are shown: stepping through time without them asks for no diagrams.
  refresh(): void {
    if (!this.store.state.pathlines || !$<HTMLDetailsElement>('persistenceDetails').open) return;
    if (!this.store.state.pathlines.visible) {
      if (this.key !== String(this.store.state.step))
        $('persistenceNote').textContent = 'the diagram of the seeds is loaded while the pathlines are shown';
      return;
    }
    const key = String(this.store.state.step);
    if (key === this.key) {
      this.draw();
      return;
    }
    this.key = key;
    this.abort?.abort();
    const ctl = new AbortController();
    this.abort = ctl;
    $('persistenceNote').textContent = `loading the diagram of step ${key}…`;
    fetchPersistence(this.store.state.step, 500, ctl.signal)
      .then((d) => {
        if (ctl.signal.aborted) return;
        this.diagram = d;
        this.draw();
      })
      .catch((e) => { if (!ctl.signal.aborted) { this.key = ''; this.host.showError((e as Error).message); } });
  }

  // Sets the seed-persistence filter to [t, the largest value], or removes it for t = null (every
  // stored line).
  setThreshold(t: number | null, interactive: boolean): void {
    const pl = this.store.state.pathlines;
    if (!pl) return;
    const others = pl.filters.filter((f) => f.name !== kSeedPersistence);
    if (t !== null) others.push({ name: kSeedPersistence, min: t, max: this.upperBound(t) });
    pl.filters = others;
    this.host.filtersChanged(interactive);
    this.host.commit(interactive);
    this.draw();
  }

  // The upper end of the filter: no pair of any step can be more persistent than the variable's
  // global range over all steps (GET /api/info), so the lines of the steps played later pass too.
  private upperBound(t: number): number {
    const v = this.store.info.variables.find((x) => x.name === this.diagram?.variable);
    const global = v ? v.max - v.min : 0;
    return Math.max(t, global, this.diagram?.range ?? t, this.host.columnMax(kSeedPersistence) ?? t);
  }

  // Redraws the diagram (after the state's filters changed elsewhere too).
  draw(): void {
    const d = this.diagram;
    const svg = $<SVGSVGElement & HTMLElement>('persistencePlot');
    const root = d3.select(svg);
    root.selectAll('*').remove();
    if (!d) return;
    const parentW = (svg.parentElement?.clientWidth ?? 0) - 4;
    if (parentW > 100) svg.setAttribute('width', String(parentW));
    const w = Number(svg.getAttribute('width')), h = Number(svg.getAttribute('height'));
    const iw = w - kMargin.left - kMargin.right, ih = h - kMargin.top - kMargin.bottom;
    const g = root.append('g').attr('transform', `translate(${kMargin.left},${kMargin.top})`);
    const units = displayUnits(d.units);
    const stored = d.stored;
    const pairs = d.pairs.filter((p) => p.persistence > 0);
    const range = Math.max(d.range, 1e-30);
    // Log scale down to the smallest pair shown (at least 1e-4 of the range: ties have 0).
    const lo = Math.max(range * 1e-4, Math.min(...pairs.map((p) => p.persistence), stored?.threshold || range) * 0.8);
    const ys = d3.scaleLog().domain([lo, range * 1.5]).range([ih, 0]).clamp(true);
    const bExt = d3.extent(d.pairs, (p) => p.birth) as [number, number];
    const xs = d3.scaleLinear().domain(bExt[0] === undefined || bExt[0] === bExt[1] ? [0, 1] : bExt).range([0, iw]).nice();
    const x = (v: number) => xs(v) as number, y = (v: number) => ys(v) as number;

    // Below the stored threshold nothing was seeded: shaded, with what to do about it.
    if (stored) {
      const ty = y(Math.max(lo, stored.threshold));
      g.append('rect').attr('class', 'notStored').attr('x', 0).attr('y', ty).attr('width', iw).attr('height', Math.max(0, ih - ty))
        .attr('fill', 'rgba(120,120,140,0.18)');
      g.append('text').attr('class', 'notStoredText').attr('x', iw - 2).attr('y', Math.min(ih - 3, ty + 11)).attr('text-anchor', 'end')
        .text('not stored: rerun preprocess with a lower --cp-persistence')
        .append('title').text(`raypc preprocess seeded this step's lines at the extrema of the pairs above ${fmt(stored.threshold)} ${units}`);
      g.append('line').attr('class', 'storedThreshold').attr('x1', 0).attr('x2', iw).attr('y1', ty).attr('y2', ty)
        .attr('stroke', '#99a').attr('stroke-dasharray', '4,3');
    }
    g.append('g').attr('class', 'axis').attr('transform', `translate(0,${ih})`).call(d3.axisBottom(xs).ticks(5).tickFormat(d3.format('~g')));
    g.append('g').attr('class', 'axis').call(d3.axisLeft(ys).ticks(4, '~g'));
    g.append('text').attr('x', iw).attr('y', ih + 28).attr('text-anchor', 'end').text(`birth${units ? ` [${units}]` : ''}`);
    g.append('text').attr('x', -kMargin.left + 2).attr('y', -5).text(`persistence${units ? ` [${units}]` : ''} (log)`);

    // The pairs: bright when a line of theirs passes the threshold (and was stored), dim otherwise.
    const t = this.threshold();
    const kept = (p: PersistencePair) => Boolean(stored) && p.persistence > stored!.threshold && (t === null || p.persistence >= t);
    g.append('g').attr('class', 'pairs').selectAll('circle').data(pairs).enter().append('circle')
      .attr('class', (p) => (kept(p) ? 'pair kept' : 'pair'))
      .attr('cx', (p) => x(p.birth)).attr('cy', (p) => y(p.persistence)).attr('r', (p) => (kept(p) ? 3.2 : 1.8))
      .attr('fill', (p) => kKindColors[p.kind] ?? '#ccc').attr('fill-opacity', (p) => (kept(p) ? 0.95 : 0.3))
      .append('title').text((p) => `${p.kind}: birth ${fmt(p.birth)}, death ${fmt(p.death)}, persistence ${fmt(p.persistence)} ${units}; ` +
        `extremum at ${p.lat.toFixed(1)}°N ${p.lon.toFixed(1)}°E, ${p.depthKm.toFixed(0)} km deep`);

    // The threshold handle: dragged vertically; at or below the stored threshold it removes the filter.
    const usable = Boolean(stored && stored.seedPersistenceColumn);
    const floor = stored ? Math.max(lo, stored.threshold) : lo;
    const handleY = y(t === null ? floor : Math.max(floor, t));
    const handle = g.append('g').attr('id', 'persistenceHandle').attr('class', usable ? 'handle' : 'handle disabled')
      .attr('transform', `translate(0,${handleY})`).style('cursor', usable ? 'ns-resize' : 'not-allowed');
    handle.append('rect').attr('x', 0).attr('y', -6).attr('width', iw).attr('height', 12).attr('fill', 'transparent');
    handle.append('line').attr('x1', 0).attr('x2', iw).attr('y1', 0).attr('y2', 0).attr('stroke', '#ffcc4d').attr('stroke-width', 1.5);
    handle.append('path').attr('d', 'M -8 -5 L 0 0 L -8 5 Z').attr('fill', '#ffcc4d');
    handle.append('text').attr('id', 'persistenceHandleLabel').attr('x', iw - 2).attr('y', -3).attr('text-anchor', 'end').attr('fill', '#ffcc4d')
      .text(t === null ? '' : `≥ ${fmt(t)}`);
    if (usable) {
      const toT = (py: number): number | null => {
        const clamped = Math.min(ih, Math.max(0, py));
        const v = ys.invert(clamped);
        return v <= floor * 1.0001 ? null : v;
      };
      // d3 5: the drag event is d3.event (y in the plot's coordinates).
      const eventY = () => (d3.event as d3.D3DragEvent<SVGGElement, unknown, unknown>).y;
      handle.call(d3.drag<SVGGElement, unknown>()
        .on('start', () => { this.dragging = true; })
        .on('drag', () => {
          const py = eventY();
          handle.attr('transform', `translate(0,${Math.min(ih, Math.max(0, py))})`);
          this.setThresholdQuietly(toT(py));
        })
        .on('end', () => {
          this.dragging = false;
          this.setThreshold(toT(eventY()), false);
        }));
    }
    this.describe(t, kept);
  }

  // While dragging: the state and the count follow at once, the plot's points on release.
  private setThresholdQuietly(t: number | null): void {
    const pl = this.store.state.pathlines;
    if (!pl || !this.dragging) return;
    const others = pl.filters.filter((f) => f.name !== kSeedPersistence);
    if (t !== null) others.push({ name: kSeedPersistence, min: t, max: this.upperBound(t) });
    pl.filters = others;
    this.host.filtersChanged(true);
    this.host.commit(true);
    // The value beside the handle; the note below keeps its lines, so that the panel does not move
    // under the pointer.
    d3.select('#persistenceHandleLabel').text(t === null ? 'every stored line' : `≥ ${fmt(t)}`);
  }

  private describe(t: number | null, kept: (p: PersistencePair) => boolean): void {
    const d = this.diagram;
    if (!d) return;
    const units = displayUnits(d.units);
    const parts = [`step ${d.step}, ${d.variable}: ${d.pairCount.toLocaleString()} pairs` +
      (d.rest.count ? ` (the ${d.pairs.length} most persistent shown)` : '')];
    if (!d.stored) parts.push('no pathlines stored for this variable');
    else if (!d.stored.seedPersistenceColumn) parts.push('the stored lines carry no seed persistence: rerun raypc preprocess to filter by it');
    else {
      parts.push(`seeds stored above ${fmt(d.stored.threshold)} ${units} (${d.stored.lines} lines)`);
      parts.push(t === null ? 'threshold: every stored line' : `threshold ${fmt(t)} ${units}: ${plural(d.pairs.filter(kept).length, 'pair')} kept`);
    }
    if (!this.store.state.pathlines?.visible) parts.push('tick Show to see the lines');
    $('persistenceNote').textContent = parts.join(' · ');
  }
}

function plural(n: number, word: string): string {
  return `${n} ${word}${n === 1 ? '' : 's'}`;
}

function fmt(v: number): string {
  return Math.abs(v) >= 100 ? v.toFixed(0) : v.toPrecision(3);
}
