// Two datasets side by side (docs/compare.md, "Side by side"; `raypc serve A B`): the second dataset's
// view beside the first's, each half the width. One state drives both: the first's RenderLink sends
// every state it sends to the second's too (RenderLink.mirror), over a session of the second dataset
// (`/ws?dataset=1`), where the server matches the step by time or index and leaves out what the
// second lacks (render/pair_state.h; its frames say so in `pair.notes`). Both views draw with the
// store's camera, so a drag on either turns both. Each view is labelled with its dataset, the step it
// shows (and its time) and the selection's share of the mantle; the parallel coordinates draw both
// samples, each in its own colour. Swap exchanges the sides; close ends the second view.
import { fetchInfo, fetchSample, postPairCorrelation, type Info } from './api';
import { drawPairCorrelation } from './pair_correlation';
import { setUpCameraInput } from './camera_input';
import type { FrameHeader } from './connection';
import type { ParallelCoordinates } from './parcoords';
import { RenderLink } from './render_link';
import { placeShellLabels } from './shell_labels';
import type { StateStore } from './store';

// What the pair needs of the App.
export interface PairHost {
  readonly info: Info;
  readonly store: StateStore;
  readonly link: RenderLink;
  readonly pc: ParallelCoordinates;
  commit(interactive: boolean): void;
  showError(message: string): void;
  // The views' sizes changed (opened, closed): the image size follows them.
  layoutChanged(): void;
  // The first dataset's selection, 0..1 of the mantle, or null (no brushes, not known yet).
  firstSelection(): number | null;
}

// The samples' colours in the parallel coordinates and the labels: the first's, the second's.
export const kPairColors: [string, string] = ['#4aa3ff', '#ff9933'];

function el<K extends keyof HTMLElementTagNameMap>(tag: K, attrs: Record<string, string>, text = ''): HTMLElementTagNameMap[K] {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  e.textContent = text;
  return e;
}

export class PairView {
  readonly link: RenderLink;
  private readonly panel: HTMLElement;
  private readonly canvas: HTMLCanvasElement;
  private readonly labels: [HTMLElement, HTMLElement];
  private readonly bar: HTMLElement;
  private readonly shellBox: HTMLElement; // the second view's shell depth labels (shell_labels.ts)
  // "Compare A and B" in the side panel: the correlation per depth of the shown variable.
  private readonly compareSection: HTMLElement;
  private correlationKey = '';
  private correlationAbort: AbortController | null = null;
  private readonly resize: ResizeObserver;
  private secondInfo: Info | null = null;
  private sampleStep = -1;
  private sampleLoading = false;
  swapped = false;
  closed = false;
  // The second view's frames shown, newest last (the browser tests read them).
  readonly headers: FrameHeader[] = [];

  constructor(private readonly host: PairHost) {
    const pair = host.info.pair!;
    this.panel = document.getElementById('viewPanel')!;
    this.canvas = el('canvas', { id: 'view3dB', tabindex: '0', 'aria-label': `3D view of the second dataset, ${pair.datasets[1].name}: navigates as the first` });
    this.labels = [
      el('div', { id: 'pairLabelA', class: 'pairLabel', role: 'status' }),
      el('div', { id: 'pairLabelB', class: 'pairLabel', role: 'status' }),
    ];
    this.labels[0].style.borderColor = kPairColors[0];
    this.labels[1].style.borderColor = kPairColors[1];
    const swap = el('button', { id: 'pairSwap', title: 'Exchange the two views’ sides' }, '⇄ Swap');
    const close = el('button', { id: 'pairClose', title: 'Close the second dataset’s view: one view again' }, '✕ Close B');
    swap.addEventListener('click', () => this.swap());
    close.addEventListener('click', () => this.close());
    this.bar = el('div', { id: 'pairBar' });
    this.bar.append(swap, close);
    this.shellBox = el('div', { id: 'shellLabelsB', 'aria-hidden': 'true' });
    this.shellBox.hidden = true;
    this.host.link.view.canvas.after(this.canvas);
    this.canvas.after(this.shellBox);
    this.panel.append(this.labels[0], this.labels[1], this.bar);
    this.panel.classList.add('pair');
    this.compareSection = el('section', { id: 'pairCompare' });
    const svg = document.createElementNS('http://www.w3.org/2000/svg', 'svg');
    svg.id = 'pairCorrelation';
    svg.setAttribute('width', '300');
    svg.setAttribute('height', '200');
    svg.setAttribute('aria-label', 'correlation of the two datasets against depth');
    this.compareSection.append(el('h2', {}, 'Compare A and B'), el('div', { id: 'pairCorrelationNote', class: 'note' }), svg);
    document.getElementById('selectionSection')?.after(this.compareSection);

    const store = host.store;
    this.link = new RenderLink(this.canvas, store, {
      onFrameArrived: () => {},
      onFrameHeld: () => {},
      onFrameShown: (h) => this.secondShown(h),
      onError: (m) => host.showError(`second dataset: ${m}`),
      onStatus: () => {},
      onLink: () => {},
      onDrawn: (kind) => placeShellLabels(this.shellBox, this.link.view.frameHeader, kind, this.link.view.pictureRect),
    }, 1);
    host.link.mirror = this.link;
    setUpCameraInput(this.canvas, store, (i) => host.commit(i));
    this.resize = new ResizeObserver(() => this.fitView());
    this.resize.observe(this.canvas);
    this.stateLoaded();
    fetchInfo(1)
      .then((info) => {
        this.secondInfo = info;
        this.loadSample(this.link.lastHeader?.step ?? 0);
      })
      .catch((e) => host.showError((e as Error).message));
    this.fitView();
    this.updateLabels();
  }

  // The state says it is a pair's (saved files, `raypc render --state`, screenshots): after a state
  // is loaded too (a preset, a file), keeping the file's step matching if it has one.
  stateLoaded(): void {
    if (this.closed) return;
    const s = this.host.store.state;
    s.pair = { dataset: this.host.info.pair!.datasets[1].name, steps: s.pair?.steps ?? 'time' };
  }

  // The second view's canvas at its size in device pixels.
  private fitView(): void {
    const dpr = window.devicePixelRatio || 1;
    this.link.view.resize(Math.max(1, Math.round(this.canvas.clientWidth * dpr)), Math.max(1, Math.round(this.canvas.clientHeight * dpr)));
    this.link.requestDraw();
  }

  private secondShown(h: FrameHeader): void {
    this.headers.push(h);
    if (this.headers.length > 200) this.headers.shift();
    this.updateLabels();
    if (!h.interactive && !h.playback) {
      this.loadSample(h.step);
      this.refreshCorrelation();
    }
  }

  // The correlation per depth of the shown variable at the shown steps, asked again when the step,
  // the variable or the step matching changed.
  private refreshCorrelation(): void {
    const s = this.host.store.state;
    const key = JSON.stringify([s.step, s.color.variable, s.pair?.steps]);
    if (key === this.correlationKey || this.closed) return;
    this.correlationKey = key;
    this.correlationAbort?.abort();
    const ctl = new AbortController();
    this.correlationAbort = ctl;
    const note = document.getElementById('pairCorrelationNote')!;
    note.textContent = 'computing the correlation per depth…';
    postPairCorrelation(s)
      .then((c) => {
        if (ctl.signal.aborted || this.closed) return;
        note.textContent = drawPairCorrelation(document.getElementById('pairCorrelation') as unknown as SVGSVGElement, c);
      })
      .catch((e) => {
        if (ctl.signal.aborted) return;
        this.correlationKey = '';
        note.textContent = (e as Error).message;
      });
  }

  // The second dataset's sample of `step` into the parallel coordinates (one at a time; the newest
  // step wins).
  private loadSample(step: number): void {
    const info = this.secondInfo;
    if (!info || this.closed || this.sampleLoading || step === this.sampleStep) return;
    this.sampleLoading = true;
    fetchSample(step, info.sample.columns, 'all', 1)
      .then((sample) => {
        if (this.closed) return;
        this.sampleStep = step;
        this.host.pc.setSecond(sample, kPairColors);
      })
      .catch((e) => this.host.showError((e as Error).message))
      .finally(() => {
        this.sampleLoading = false;
        const shown = this.link.lastHeader?.step;
        if (shown !== undefined && shown !== this.sampleStep) this.loadSample(shown);
      });
  }

  // Each view's dataset, the step it shows (its time) and the selection's share; the second's notes.
  updateLabels(): void {
    if (this.closed) return;
    const pair = this.host.info.pair!;
    const brushed = this.host.store.state.brushes.length > 0;
    const percent = (f: number | null | undefined) => (brushed && typeof f === 'number' ? ` · selected ${(f * 100).toFixed(2)} %` : '');
    const a = this.host.link.lastHeader, b = this.link.lastHeader;
    const stepText = (h: FrameHeader | null, times: number[]) =>
      h ? ` · step ${h.step} (${(times[h.step] ?? NaN).toFixed(1)} Myr)` : ' · waiting for its first frame';
    this.labels[0].textContent = `A · ${pair.datasets[0].name}${stepText(a, pair.datasets[0].timesMyr)}${percent(this.host.firstSelection())}`;
    const notes = b?.pair?.notes ?? [];
    this.labels[1].textContent = `B · ${pair.datasets[1].name}${stepText(b, pair.datasets[1].timesMyr)}${percent(b?.selection?.fractionOfMantle)}` +
      (notes.length ? ` · ${notes.join('; ')}` : '');
  }

  swap(): void {
    this.swapped = !this.swapped;
    this.panel.classList.toggle('swapped', this.swapped);
  }

  // One view again: the second's session ends, its lines leave the parallel coordinates, and the
  // state is no longer a pair's.
  close(): void {
    if (this.closed) return;
    this.closed = true;
    this.host.link.mirror = null;
    this.link.close();
    this.resize.disconnect();
    this.canvas.remove();
    for (const l of this.labels) l.remove();
    this.shellBox.remove();
    this.correlationAbort?.abort();
    this.compareSection.remove();
    this.bar.remove();
    this.panel.classList.remove('pair', 'swapped');
    this.host.pc.setSecond(null);
    this.host.store.state.pair = null;
    this.host.layoutChanged();
    this.host.commit(false);
  }
}
