// The Transfer function section: variable, colour map (reversed, log scale), colour range, opacity
// unit, the editor (opacity over the variable's histograms, colour points on the bar), a colour
// picker for the selected colour point, and ParaView colour-map JSON import/export.
//
// Switching the variable picks defaults that suit it: a diverging map centred on 0 (vik) for a
// signed quantity with both tails, else a sequential map (batlow) over the data range, with a fresh
// opacity ramp; the log scale is offered only for positive quantities.
import { fetchHistogram, type Histogram, type VariableInfo } from './api';
import { mapKind, type ColorStop } from './colormaps';
import { download, onFileChosen } from './controls';
import { paraViewMapJson, parseParaViewMap } from './paraview_colormap';
import type { StateStore } from './store';
import { TfEditor } from './tf_editor';
import { displayUnits } from './units';
import { variableOrigin } from './variable_origin';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;

export interface TfPanelHost {
  commit(interactive: boolean): void;
  showError(message: string): void;
  setStatusNote(text: string): void;
  // The colours of the volume changed (the lines of the parallel coordinates follow them).
  colorsChanged(): void;
  // The colour variable changed.
  variableChanged(): void;
}

// A signed quantity with both tails (the smaller at least a tenth of the larger): its colours
// diverge from 0. Anything else (temperature, conductivity, |v|) is sequential.
export function isSignedQuantity(v: Pick<VariableInfo, 'min' | 'max'>): boolean {
  return v.min < 0 && v.max > 0 && Math.min(-v.min, v.max) >= 0.1 * Math.max(-v.min, v.max);
}

const toHex = (c: number) => Math.round(Math.min(1, Math.max(0, c)) * 255).toString(16).padStart(2, '0');

export class TfPanel {
  private readonly editor: TfEditor;
  private stepHistogram: Histogram | null = null;

  constructor(private readonly store: StateStore, private readonly host: TfPanelHost) {
    this.editor = new TfEditor($<HTMLCanvasElement>('tf'), {
      onChange: (opacity, interactive) => {
        this.store.state.color.opacity = opacity;
        this.host.commit(interactive);
      },
      onColorPoints: (points, interactive) => {
        const c = this.store.state.color;
        c.points = points;
        c.reversed = false; // the points hold the colours as shown
        this.syncMapControls();
        this.host.colorsChanged();
        this.host.commit(interactive);
      },
      onSelectColorPoint: (i) => this.showSelectedColor(i),
    });
    const info = store.info;
    const varSel = $<HTMLSelectElement>('variable');
    for (const v of info.variables) {
      const option = new Option(`${v.name} [${displayUnits(v.units)}]`, v.name);
      option.title = `${option.text}: ${variableOrigin(v)}`; // stored, derived or computed when read
      varSel.add(option);
    }
    varSel.addEventListener('change', () => {
      this.applyVariableDefaults(varSel.value);
      this.stepHistogram = null;
      this.sync();
      this.loadHistogram();
      this.host.colorsChanged();
      this.host.variableChanged();
      this.host.commit(false);
    });
    const mapSel = $<HTMLSelectElement>('colorMap');
    mapSel.add(new Option('custom points', ''));
    for (const m of info.colorMaps) mapSel.add(new Option(m, m));
    mapSel.addEventListener('change', () => {
      if (!mapSel.value) return;
      this.store.state.color.colorMap = mapSel.value;
      this.store.state.color.points = [];
      this.update();
      this.host.colorsChanged();
      this.host.commit(false);
    });
    $('colorReversed').addEventListener('change', () => {
      this.store.state.color.reversed = $<HTMLInputElement>('colorReversed').checked;
      this.update();
      this.host.colorsChanged();
      this.host.commit(false);
    });
    $('logScale').addEventListener('change', () => {
      const on = $<HTMLInputElement>('logScale').checked;
      const [lo] = this.store.effectiveRange();
      if (on && !(lo > 0)) {
        this.host.showError(`log scale: the colour range starts at ${lo}; it needs positive values (set min > 0)`);
        $<HTMLInputElement>('logScale').checked = false;
        return;
      }
      this.store.state.color.logScale = on;
      this.update();
      this.host.colorsChanged();
      this.host.commit(false);
    });
    $('tfPointColor').addEventListener('input', () => {
      const i = this.editor.selectedColor, c = this.store.state.color;
      if (i < 0 || i >= c.points.length) return;
      const hex = $<HTMLInputElement>('tfPointColor').value;
      const rgb = [1, 3, 5].map((k) => parseInt(hex.slice(k, k + 2), 16) / 255);
      c.points[i] = [c.points[i][0], rgb[0], rgb[1], rgb[2]];
      this.update();
      this.host.colorsChanged();
      this.host.commit(false);
    });
    $('pvExport').addEventListener('click', () => {
      // Colour points go out exactly (at their values); a named map as 65 samples of what is shown
      // (a centred map's middle stays at 0).
      const c = this.store.state.color;
      const valueAt = (u: number) => this.store.valueAt(u);
      let colors: [number, number, number, number][];
      if (c.points.length) {
        colors = c.points.map((p) => [valueAt(c.reversed ? 1 - p[0] : p[0]), p[1], p[2], p[3]] as [number, number, number, number]);
        colors.sort((a, b) => a[0] - b[0]);
      } else {
        const colorOf = this.store.colorOf();
        colors = Array.from({ length: 65 }, (_, k) => { const v = valueAt(k / 64); return [v, ...colorOf(v)] as [number, number, number, number]; });
      }
      const text = paraViewMapJson(`RayPC ${c.variable}`, colors, valueAt, c.opacity as [number, number][], c.logScale);
      download(new Blob([text], { type: 'application/json' }), `raypc-colormap-${c.variable.replace(/\W+/g, '_')}.json`);
    });
    onFileChosen($<HTMLInputElement>('pvImport'), 'ParaView colour map ', (text, name) => {
      this.importParaView(text);
      this.host.setStatusNote(`colour map ${name} imported`);
    }, (m) => this.host.showError(m));
    const rangeChanged = () => {
      const lo = Number($<HTMLInputElement>('rangeMin').value), hi = Number($<HTMLInputElement>('rangeMax').value);
      if (!(Number.isFinite(lo) && Number.isFinite(hi) && lo < hi)) {
        this.host.showError(`colour range: min ${lo} must be less than max ${hi}`);
        this.update();
        return;
      }
      if (this.store.state.color.logScale && !(lo > 0)) {
        this.host.showError(`colour range: min ${lo} must be positive with the log scale`);
        this.update();
        return;
      }
      this.store.state.color.range = [lo, hi];
      this.update();
      this.host.colorsChanged();
      this.host.commit(false);
    };
    $('rangeMin').addEventListener('change', rangeChanged);
    $('rangeMax').addEventListener('change', rangeChanged);
    $('rangeReset').addEventListener('click', () => {
      this.store.state.color.range = null;
      if (this.store.state.color.logScale && !(this.store.effectiveRange()[0] > 0)) this.store.state.color.logScale = false;
      this.sync();
      this.host.colorsChanged();
      this.host.commit(false);
    });
    $('opacityUnit').addEventListener('change', () => {
      const v = Number($<HTMLInputElement>('opacityUnit').value);
      if (v > 0) {
        this.store.state.color.opacityUnitKm = v;
        this.host.commit(false);
      }
    });
  }

  // Defaults for a newly chosen variable (see the top of the file).
  applyVariableDefaults(name: string): void {
    const c = this.store.state.color;
    const v = this.store.variableInfo(name);
    c.variable = name;
    c.range = null;
    c.points = [];
    c.reversed = false;
    c.logScale = false;
    if (isSignedQuantity(v)) {
      c.colorMap = 'vik';
      c.opacity = [[0, 0.5], [0.5, 0], [1, 0.5]];
    } else {
      c.colorMap = 'batlow';
      c.opacity = [[0, 0], [1, 0.5]];
    }
  }

  private importParaView(text: string): void {
    const m = parseParaViewMap(text);
    if (m.logScale && !(m.range[0] > 0)) throw new Error('UseLogScale over a range that is not positive');
    const c = this.store.state.color;
    c.points = m.colorPoints;
    c.range = m.range;
    c.reversed = false;
    c.logScale = m.logScale;
    if (m.opacity?.length) c.opacity = m.opacity;
    this.sync();
    this.host.colorsChanged();
    this.host.commit(false);
  }

  private showSelectedColor(i: number): void {
    const input = $<HTMLInputElement>('tfPointColor');
    const p = this.store.state.color.points[i];
    input.disabled = !p;
    if (p) input.value = `#${toHex(p[1])}${toHex(p[2])}${toHex(p[3])}`;
  }

  // The histogram of the colour variable at the current step.
  loadHistogram(): void {
    const step = this.store.state.step, name = this.store.state.color.variable;
    fetchHistogram(step, name)
      .then((h) => {
        if (this.store.state.step === step && this.store.state.color.variable === name) {
          this.stepHistogram = h;
          this.update();
        }
      })
      .catch((e) => this.host.showError((e as Error).message));
  }

  // Redraws the editor and the range fields from the state.
  update(): void {
    const v = this.store.variableInfo();
    const hist = [];
    if (this.stepHistogram && this.stepHistogram.name === v.name) hist.push({ data: this.stepHistogram, style: 'bars' as const });
    hist.push({ data: v, style: 'line' as const });
    const range = this.store.effectiveRange();
    const color = this.store.state.color;
    const colorOf = this.store.colorOf();
    this.editor.set(color.opacity as [number, number][], range, {
      colorAt: (u) => colorOf(this.store.valueAt(u)),
      positionOf: (value) => this.store.positionOf(value),
      valueAt: (u) => this.store.valueAt(u),
      colorPoints: color.points as ColorStop[],
    }, displayUnits(v.units), hist);
    $<HTMLInputElement>('rangeMin').value = String(+range[0].toPrecision(6));
    $<HTMLInputElement>('rangeMax').value = String(+range[1].toPrecision(6));
    $<HTMLInputElement>('logScale').disabled = !(range[0] > 0) && !color.logScale;
    this.showSelectedColor(this.editor.selectedColor);
  }

  private syncMapControls(): void {
    const c = this.store.state.color;
    $<HTMLSelectElement>('colorMap').value = c.points.length ? '' : c.colorMap;
    $<HTMLSelectElement>('colorMap').title = c.points.length ? 'custom colour points (pick a map to go back to it)' : `${mapKind(c.colorMap)} map`;
    $<HTMLInputElement>('colorReversed').checked = c.reversed;
    $<HTMLInputElement>('logScale').checked = c.logScale;
  }

  // Puts the state into the controls (after load, preset, URL).
  sync(): void {
    const c = this.store.state.color;
    $<HTMLSelectElement>('variable').value = c.variable;
    $<HTMLInputElement>('opacityUnit').value = String(c.opacityUnitKm);
    this.syncMapControls();
    this.update();
  }
}
