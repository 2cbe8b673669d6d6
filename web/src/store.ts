// The UI's one render state (docs/state.md) and what follows from it together with the dataset's
// info: the server's defaults, the colour range in force, the parallel-coordinates axes. Every
// panel reads and writes `state` here; App.commit sends it.
import type { Info } from './api';
import { centredMaps, mapStops, sampleStops, type ColorStop } from './colormaps';
import type { AxisInfo } from './parcoords';
import { cloneState, normaliseState, stateFromHash, type RenderState } from './state';
import { variableOrigin } from './variable_origin';

export class StateStore {
  state: RenderState;
  readonly defaults: RenderState;
  // The image size follows the view (cleared when a loaded state names its own size).
  autoFitImage = true;

  constructor(readonly info: Info) {
    this.defaults = normaliseState(info.defaultState, info.defaultState);
    this.state = cloneState(this.defaults);
  }

  // Takes the state of the page URL (#state=…), if any. Throws an Error for a bad one.
  loadFromHash(hash: string): void {
    const fromUrl = stateFromHash(hash);
    if (fromUrl) {
      this.state = normaliseState(fromUrl, this.defaults);
      this.autoFitImage = false;
    }
  }

  // Replaces the state with a checked document; returns the previous state. Throws on a bad one
  // (and then changes nothing).
  replace(doc: unknown): RenderState {
    const prev = this.state;
    this.state = normaliseState(doc, this.defaults);
    this.autoFitImage = false;
    return prev;
  }

  variableInfo(name = this.state.color.variable) {
    return this.info.variables.find((v) => v.name === name) ?? this.info.variables[0];
  }

  // The colour range in force: the state's, or the one the renderer takes without it (from
  // /api/info: the global range, symmetric for centred maps, a constant one widened).
  effectiveRange(): [number, number] {
    if (this.state.color.range) return this.state.color.range;
    const d = this.variableInfo().defaultColorRange;
    return centredMaps.has(this.state.color.colorMap) ? d.centred : d.other;
  }

  // The normalised position of a value over the colour range: linear, or over log10 with
  // color.logScale (clamped to [0, 1]), as the renderer's TransferFunction::positionOf.
  positionOf(value: number): number {
    const [lo, hi] = this.effectiveRange();
    const u = this.state.color.logScale
      ? (Math.log10(Math.max(value, lo)) - Math.log10(lo)) / (Math.log10(hi) - Math.log10(lo))
      : (value - lo) / (hi - lo);
    return Math.min(1, Math.max(0, Number.isFinite(u) ? u : 0));
  }

  // The value at a normalised position (the inverse of positionOf).
  valueAt(u: number): number {
    const [lo, hi] = this.effectiveRange();
    return this.state.color.logScale ? lo * Math.pow(hi / lo, u) : lo + u * (hi - lo);
  }

  // The stops in force: the colour points, else the named map's.
  colorStops(): ColorStop[] {
    const c = this.state.color;
    return c.points.length ? (c.points as ColorStop[]) : mapStops(c.colorMap);
  }

  // The colour of a value, as the renderer's TransferFunction::colorOf: centred maps put 0 in the
  // middle (named maps without a log scale), the colours reversed if asked.
  colorOf(): (value: number) => [number, number, number] {
    const c = this.state.color;
    const stops = this.colorStops();
    const [lo, hi] = this.effectiveRange();
    const centred = !c.points.length && !c.logScale && centredMaps.has(c.colorMap);
    const m = Math.max(Math.abs(lo), Math.abs(hi)) || 1;
    return (v) => {
      let u = centred ? Math.min(1, Math.max(0, 0.5 + (0.5 * v) / m)) : this.positionOf(v);
      if (c.reversed) u = 1 - u;
      return sampleStops(stops, u);
    };
  }

  // One axis per column of the dataset's sample, with units and global ranges.
  axes(): AxisInfo[] {
    const { columns, units } = this.info.sample;
    return columns.map((name, i) => {
      const v = this.info.variables.find((x) => x.name === name);
      const c = this.info.coordinates.find((x) => x.name === name);
      const r = v ?? c;
      return { name, units: units[i] ?? r?.units ?? '', min: r?.min ?? 0, max: r?.max ?? 1, ...(v ? { about: variableOrigin(v) } : {}) };
    });
  }
}
