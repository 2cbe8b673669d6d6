// The link between the state and the 3D view: sends states over the WebSocket (interactive ones
// coalesced), shows the frames that come back (View3D: exact or warped), and runs work that must
// wait until the frame of the state sent last is on screen (afterFrameShown).
//
// Cost classes (docs/state.md): camera, transfer function and brushes restart progressive passes;
// step and level reload data. While the user drags, states go out as `interactive` (one pass at
// the interactive level), at most one per display frame and only when the server has answered
// the previous one or 120 ms passed; on release the final state asks for all passes. Playback
// sends the step ahead (sendPlayback) and holds its frames until its time comes (releaseHeld).
import { Connection, type Frame, type FrameHeader, type SendMode } from './connection';
import { cloneState, type Brush, type CameraState, type RenderState } from './state';
import type { StateStore } from './store';
import { View3D, type DrawKind } from './view';

// How long deferred work waits at most for the still frame it asked for.
const kAfterFrameMs = 1000;

export interface RenderLinkEvents {
  // A frame arrived for the newest state or a newer one than shown (before it is decoded).
  onFrameArrived(header: FrameHeader): void;
  // A frame of the state being held (holdFramesOf) arrived and was kept, not shown.
  onFrameHeld(frame: Frame): void;
  // A frame is on screen.
  onFrameShown(header: FrameHeader): void;
  // The view was drawn: the frame as rendered ('exact'), re-projected to the moving camera
  // ('warped'), or as rendered for another camera ('unwarped').
  onDrawn?(kind: DrawKind): void;
  onError(message: string): void;
  onStatus(text: string): void;
  // A state a program set (POST /api/link; Connection's onLink).
  onLink(state: unknown, version: number): void;
}

// What the browser tests observe (test_hooks.ts); absent in normal use.
export interface RenderLinkObserver {
  sent(entry: SentEntry): void;
  // Returns false to hold the frame back (it is passed to `receive` later).
  received(frame: Frame): boolean;
  shown(header: FrameHeader, latency: Latency | null): void;
  drawn(kind: DrawKind, waiting: boolean): void;
  afterFrame(record: { id: number; shownId: number; afterShown: boolean }): void;
}

export interface SentEntry {
  id: number;
  t: number;
  step: number;
  interactive: boolean;
  playback: boolean;
  brushes: Brush[];
  camera: CameraState;
  stereoMode: string;
  image: { width: number; height: number };
}

export interface Latency {
  id: number;
  interactive: boolean;
  playback: boolean;
  firstFrameMs: number; // sent -> first frame received
  shownMs: number; // sent -> first frame on screen (for a step of playback, when its time came)
}

export class RenderLink {
  readonly view: View3D;
  private readonly connection: Connection;
  observer: RenderLinkObserver | null = null;
  lastSentId = 0;
  lastShownId = 0;
  lastHeader: FrameHeader | null = null;
  lastLatency: Latency | null = null;
  private drawPending = false;
  private decodingFrame = false;
  private nextFrame: Frame | null = null; // arrived while another was decoded: shown next
  private interactivePending = false;
  private lastSendTime = 0;
  private readonly sendTimes = new Map<number, { t: number; mode: SendMode; first?: number; shown?: boolean }>();
  // Playback: the frames of this state are kept (the newest in `held`) until releaseHeld.
  private holdId = 0;
  private held: Frame | null = null;
  private droppedId = 0; // a step of playback shown or stopped: its later passes are not shown
  private afterFrame: { id: number; run: (() => void)[]; timer: number } | null = null;
  // While a WebXR session runs (xr.ts): what is sent is the store's state made into the session's
  // (the eyes' views, a side-by-side pair), and the session's animation frames draw, not this link.
  xr: { stateToSend(state: RenderState): RenderState } | null = null;

  // A pair's second view (pair.ts): every state sent here goes there too, and it draws when this does.
  mirror: RenderLink | null = null;

  // `dataset`: which dataset of a pair this link renders (0 the first or only one).
  constructor(canvas: HTMLCanvasElement, private readonly store: StateStore, private readonly events: RenderLinkEvents, dataset = 0) {
    this.view = new View3D(canvas);
    this.connection = new Connection({
      onFrame: (f) => this.receive(f),
      onError: (m, id) => events.onError(id !== undefined ? `state ${id}: ${m}` : m),
      onStatus: (t) => events.onStatus(t),
      onLink: (state, version) => events.onLink(state, version),
    }, dataset);
  }

  // Ends the session (a pair's second view closed).
  close(): void {
    this.connection.close();
  }

  // True when the newest sent state has been answered by at least one frame.
  get caughtUp(): boolean {
    return this.connection.caughtUp;
  }

  cancel(): void {
    this.mirror?.cancel();
    this.connection.cancel();
  }

  // Sends the state; interactive states are coalesced to one per display frame.
  send(interactive: boolean): void {
    this.requestDraw();
    if (interactive) {
      this.interactivePending = true;
      this.pumpInteractive();
      return;
    }
    this.interactivePending = false;
    this.sendNow('still');
  }

  // Sends the store's state at `step` as a step of playback, shown for about `budgetMs` (the
  // server's level choice), and holds its frames; returns its id.
  // What a state sent for another step than the store's changes for that step (the Features
  // panel's highlighted feature of that step); null: only the step.
  forStep: ((s: RenderState, step: number) => RenderState) | null = null;

  sendPlayback(step: number, budgetMs: number): number {
    this.interactivePending = false;
    this.held = null;
    const id = this.sendNow('playback', (s) => {
      const t = { ...s, step, timeBudgetMs: budgetMs };
      return this.forStep ? this.forStep(t, step) : t;
    });
    this.holdId = id;
    return id;
  }

  // True when a frame of state `id` is held.
  hasHeld(id: number): boolean {
    return this.held?.header.id === id;
  }

  // Shows the held frame (the newest pass that arrived) and stops holding; the passes of that state
  // still in flight are dropped (the next step is being sent: decoding them would only compete
  // with it for the CPU).
  releaseHeld(): void {
    const frame = this.held;
    this.droppedId = Math.max(this.droppedId, this.holdId);
    this.holdId = 0;
    this.held = null;
    if (frame) this.show(frame);
  }

  // Frames are shown as they arrive again; the held state's frames are dropped.
  stopHolding(): void {
    this.droppedId = Math.max(this.droppedId, this.holdId);
    this.holdId = 0;
    this.held = null;
  }

  private pumpInteractive(): void {
    if (!this.interactivePending) return;
    const now = performance.now();
    if (this.connection.caughtUp || now - this.lastSendTime > 120) {
      this.interactivePending = false;
      this.sendNow('interactive');
    } else {
      requestAnimationFrame(() => this.pumpInteractive());
    }
  }

  // Sends the store's state at once (the XR session coalesces its own requests), as `adjust`
  // makes it when given; returns its id.
  sendNow(mode: SendMode, adjust?: (s: RenderState) => RenderState): number {
    let state = this.xr ? this.xr.stateToSend(cloneState(this.store.state)) : cloneState(this.store.state);
    if (adjust) state = adjust(state);
    const id = this.connection.send(state, mode);
    this.lastSendTime = performance.now();
    this.sendTimes.set(id, { t: this.lastSendTime, mode });
    if (this.sendTimes.size > 200) this.sendTimes.delete(this.sendTimes.keys().next().value as number);
    this.lastSentId = id;
    this.mirror?.sendNow(mode, adjust);
    this.observer?.sent({ id, t: this.lastSendTime, step: state.step, interactive: mode === 'interactive', playback: mode === 'playback',
      brushes: state.brushes.map((b) => ({ ...b })), camera: cloneState(state).camera, stereoMode: state.stereo.mode,
      image: { ...state.image } });
    return id;
  }

  receive(frame: Frame): void {
    if (this.observer && !this.observer.received(frame)) return;
    const h = frame.header;
    const sent = this.sendTimes.get(h.id);
    if (sent && sent.first === undefined) sent.first = frame.receivedAt - sent.t;
    if (this.superseded(frame)) return;
    if (h.id === this.holdId) {
      if (!this.held || this.held.header.pass < h.pass) this.held = frame;
      this.events.onFrameHeld(frame);
      return;
    }
    this.show(frame);
  }

  private show(frame: Frame): void {
    this.lastHeader = frame.header;
    this.events.onFrameArrived(frame.header);
    this.decode(frame);
  }

  // One frame is decoded at a time; of those that arrive meanwhile only the newest waits, the
  // others are dropped. Frames that come faster than the page decodes them (a drag on shared
  // cores) would otherwise queue, and the picture lag ever further behind the mouse.
  private decode(frame: Frame): void {
    if (this.decodingFrame) {
      this.nextFrame = frame;
      return;
    }
    this.decodingFrame = true;
    const id = frame.header.id;
    this.decodeAndDraw(frame).catch((e) => this.events.onError(`frame of state ${id}: ${(e as Error).message}`)).finally(() => {
      this.decodingFrame = false;
      const next = this.nextFrame;
      this.nextFrame = null;
      if (next && !this.superseded(next)) this.decode(next);
    });
  }

  // A pass of an older state than the one shown, or of a step of playback already shown or stopped.
  private superseded(frame: Frame): boolean {
    return frame.header.id < this.lastShownId || frame.header.id === this.droppedId;
  }

  private decodeAndDraw(frame: Frame): Promise<void> {
    const h = frame.header;
    const sent = this.sendTimes.get(h.id);
    return this.view.setFrame(frame).then(() => {
      if (h.id >= this.lastShownId) this.lastShownId = h.id;
      let latency: Latency | null = null;
      if (sent && !sent.shown) {
        sent.shown = true;
        latency = { id: h.id, interactive: sent.mode === 'interactive', playback: sent.mode === 'playback',
          firstFrameMs: sent.first ?? NaN, shownMs: performance.now() - sent.t };
        this.lastLatency = latency;
      }
      this.observer?.shown(h, latency);
      this.drawNow(); // at once, not in the next animation frame (which may queue behind other work)
      this.events.onFrameShown(h);
      if (this.afterFrame && h.id >= this.afterFrame.id) this.runAfterFrame();
    });
  }

  requestDraw(): void {
    this.mirror?.requestDraw();
    if (this.drawPending) return;
    this.drawPending = true;
    requestAnimationFrame(() => {
      if (this.drawPending) this.drawNow();
    });
  }

  private drawNow(): void {
    this.drawPending = false;
    if (this.xr) return;
    const s = this.store.state;
    const bg = (s.background as [number, number, number] | undefined) ?? [0, 0, 0];
    const kind = this.view.draw(s.camera, s.stereo, s.image.width, s.image.height, bg);
    this.observer?.drawn(kind, this.lastShownId < this.lastSentId);
    this.events.onDrawn?.(kind);
  }

  // Work that waits until the frame of the state sent last is on screen (or kAfterFrameMs passed),
  // so that it does not compete with that frame for the CPU (the browser and the server share it):
  // the full line redraw after a brush release, the exact selection and the statistics over time.
  afterFrameShown(run: () => void): void {
    const id = this.lastSentId;
    if (this.afterFrame && this.afterFrame.id !== id) this.runAfterFrame(); // older work runs now
    if (!this.afterFrame) this.afterFrame = { id, run: [], timer: window.setTimeout(() => this.runAfterFrame(), kAfterFrameMs) };
    this.afterFrame.run.push(run);
  }

  private runAfterFrame(): void {
    const pending = this.afterFrame;
    if (!pending) return;
    this.afterFrame = null;
    clearTimeout(pending.timer);
    const shownId = this.lastShownId;
    this.observer?.afterFrame({ id: pending.id, shownId, afterShown: shownId >= pending.id });
    for (const run of pending.run) run();
  }
}
