// The Transfer function section: variable, colour map, colour range, opacity unit and the opacity
// editor drawn over the variable's histograms (this step's bars, all steps' line).
import { fetchHistogram, type Histogram } from './api';
import type { StateStore } from './store';
import { TfEditor } from './tf_editor';
import { displayUnits } from './units';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;

export interface TfPanelHost {
  commit(interactive: boolean): void;
  showError(message: string): void;
  // The colours of the volume changed (the lines of the parallel coordinates follow them).
  coloursChanged(): void;
  // The colour variable changed.
  variableChanged(): void;
}

export class TfPanel {
  private readonly editor: TfEditor;
  private stepHistogram: Histogram | null = null;

  constructor(private readonly store: StateStore, private readonly host: TfPanelHost) {
    this.editor = new TfEditor($<HTMLCanvasElement>('tf'), {
      onChange: (opacity, interactive) => {
        this.store.state.color.opacity = opacity;
        this.host.commit(interactive);
      },
    });
    const info = store.info;
    const varSel = $<HTMLSelectElement>('variable');
    for (const v of info.variables) varSel.add(new Option(`${v.name} [${displayUnits(v.units)}]`, v.name));
    varSel.addEventListener('change', () => {
      this.store.state.color.variable = varSel.value;
      this.store.state.color.range = null;
      this.stepHistogram = null;
      this.update();
      this.loadHistogram();
      this.host.coloursChanged();
      this.host.variableChanged();
      this.host.commit(false);
    });
    const mapSel = $<HTMLSelectElement>('colorMap');
    for (const m of info.colorMaps) mapSel.add(new Option(m, m));
    mapSel.addEventListener('change', () => {
      this.store.state.color.colorMap = mapSel.value;
      this.update();
      this.host.coloursChanged();
      this.host.commit(false);
    });
    const rangeChanged = () => {
      const lo = Number($<HTMLInputElement>('rangeMin').value), hi = Number($<HTMLInputElement>('rangeMax').value);
      if (!(Number.isFinite(lo) && Number.isFinite(hi) && lo < hi)) {
        this.host.showError(`colour range: min ${lo} must be less than max ${hi}`);
        this.update();
        return;
      }
      this.store.state.color.range = [lo, hi];
      this.update();
      this.host.coloursChanged();
      this.host.commit(false);
    };
    $('rangeMin').addEventListener('change', rangeChanged);
    $('rangeMax').addEventListener('change', rangeChanged);
    $('rangeReset').addEventListener('click', () => {
      this.store.state.color.range = null;
      this.update();
      this.host.coloursChanged();
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
    this.editor.set(color.opacity, range, color.colorMap, displayUnits(v.units), hist);
    $<HTMLInputElement>('rangeMin').value = String(+range[0].toPrecision(6));
    $<HTMLInputElement>('rangeMax').value = String(+range[1].toPrecision(6));
  }

  // Puts the state into the controls (after load, preset, URL).
  sync(): void {
    const c = this.store.state.color;
    $<HTMLSelectElement>('variable').value = c.variable;
    $<HTMLSelectElement>('colorMap').value = c.colorMap;
    $<HTMLInputElement>('opacityUnit').value = String(c.opacityUnitKm);
    this.update();
  }
}
