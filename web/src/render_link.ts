// The link between the state and the 3D view: sends states over the WebSocket (interactive ones
// coalesced), shows the frames that come back (View3D: exact or warped), and runs work that must
// wait until the frame of the state sent last is on screen (afterFrameShown).
//
// Cost classes (docs/state.md): camera, transfer function and brushes restart progressive passes;
// step and level reload data. While the user drags, states go out as `interactive` (one pass at
// the interactive level), at most one per display frame and only when the server has answered
// the previous one or 120 ms passed; on release the final state asks for all passes.
import { Connection, type Frame, type FrameHeader } from './connection';
import { cloneState, type Brush, type CameraState, type RenderState } from './state';
import type { StateStore } from './store';
import { View3D } from './view';

// How long deferred work waits at most for the still frame it asked for.
const kAfterFrameMs = 1000;

export interface RenderLinkEvents {
  // A frame arrived for the newest state or a newer one than shown (before it is decoded).
  onFrameArrived(header: FrameHeader): void;
  // A frame is on screen.
  onFrameShown(header: FrameHeader): void;
  onError(message: string): void;
  onStatus(text: string): void;
}

// What the browser tests observe (test_hooks.ts); absent in normal use.
export interface RenderLinkObserver {
  sent(entry: SentEntry): void;
  // Returns false to hold the frame back (it is passed to `receive` later).
  received(frame: Frame): boolean;
  shown(header: FrameHeader, latency: Latency | null): void;
  drawn(kind: 'exact' | 'warped' | 'none', waiting: boolean): void;
  afterFrame(record: { id: number; shownId: number; afterShown: boolean }): void;
}

export interface SentEntry {
  id: number;
  t: number;
  step: number;
  interactive: boolean;
  brushes: Brush[];
  camera: CameraState;
  stereoMode: string;
  image: { width: number; height: number };
}

export interface Latency {
  id: number;
  interactive: boolean;
  firstFrameMs: number; // sent -> first frame received
  shownMs: number; // sent -> first frame on screen
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
  private interactivePending = false;
  private lastSendTime = 0;
  private readonly sendTimes = new Map<number, { t: number; interactive: boolean; first?: number }>();
  private afterFrame: { id: number; run: (() => void)[]; timer: number } | null = null;
  // While a WebXR session runs (xr.ts): what is sent is the store's state made into the session's
  // (the eyes' views, a side-by-side pair), and the session's animation frames draw, not this link.
  xr: { stateToSend(state: RenderState): RenderState } | null = null;

  constructor(canvas: HTMLCanvasElement, private readonly store: StateStore, private readonly events: RenderLinkEvents) {
    this.view = new View3D(canvas);
    this.connection = new Connection({
      onFrame: (f) => this.receive(f),
      onError: (m, id) => events.onError(id !== undefined ? `state ${id}: ${m}` : m),
      onStatus: (t) => events.onStatus(t),
    });
  }

  // True when the newest sent state has been answered by at least one frame.
  get caughtUp(): boolean {
    return this.connection.caughtUp;
  }

  cancel(): void {
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
    this.sendNow(false);
  }

  private pumpInteractive(): void {
    if (!this.interactivePending) return;
    const now = performance.now();
    if (this.connection.caughtUp || now - this.lastSendTime > 120) {
      this.interactivePending = false;
      this.sendNow(true);
    } else {
      requestAnimationFrame(() => this.pumpInteractive());
    }
  }

  // Sends the store's state at once (the XR session coalesces its own requests).
  sendNow(interactive: boolean): void {
    const state = this.xr ? this.xr.stateToSend(cloneState(this.store.state)) : this.store.state;
    const id = this.connection.send(cloneState(state), interactive);
    this.lastSendTime = performance.now();
    this.sendTimes.set(id, { t: this.lastSendTime, interactive });
    if (this.sendTimes.size > 200) this.sendTimes.delete(this.sendTimes.keys().next().value as number);
    this.lastSentId = id;
    this.observer?.sent({ id, t: this.lastSendTime, step: state.step, interactive, brushes: state.brushes.map((b) => ({ ...b })),
      camera: cloneState(state).camera, stereoMode: state.stereo.mode, image: { ...state.image } });
  }

  receive(frame: Frame): void {
    if (this.observer && !this.observer.received(frame)) return;
    const h = frame.header;
    const sent = this.sendTimes.get(h.id);
    if (sent && sent.first === undefined) sent.first = frame.receivedAt - sent.t;
    if (h.id < this.lastShownId) return; // a pass of an older state that was still in flight
    this.lastHeader = h;
    this.events.onFrameArrived(h);
    void this.view.setFrame(frame).then(() => {
      if (h.id >= this.lastShownId) this.lastShownId = h.id;
      let latency: Latency | null = null;
      if (sent && h.pass === 1) {
        latency = { id: h.id, interactive: sent.interactive, firstFrameMs: sent.first ?? NaN, shownMs: performance.now() - sent.t };
        this.lastLatency = latency;
      }
      this.observer?.shown(h, latency);
      this.drawNow(); // at once, not in the next animation frame (which may queue behind other work)
      this.events.onFrameShown(h);
      if (this.afterFrame && h.id >= this.afterFrame.id) this.runAfterFrame();
    });
  }

  requestDraw(): void {
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
