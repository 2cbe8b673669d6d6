// The UI's one render state (docs/state.md) and what follows from it together with the dataset's
// info: the server's defaults, the colour range in force, the parallel-coordinates axes. Every
// panel reads and writes `state` here; App.commit sends it.
import type { Info } from './api';
import { centredMaps } from './colormaps';
import type { AxisInfo } from './parcoords';
import { cloneState, normaliseState, stateFromHash, type RenderState } from './state';

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

  // One axis per column of the dataset's sample, with units and global ranges.
  axes(): AxisInfo[] {
    const { columns, units } = this.info.sample;
    return columns.map((name, i) => {
      const v = this.info.variables.find((x) => x.name === name);
      const c = this.info.coordinates.find((x) => x.name === name);
      const r = v ?? c;
      return { name, units: units[i] ?? r?.units ?? '', min: r?.min ?? 0, max: r?.max ?? 1 };
    });
  }
}
