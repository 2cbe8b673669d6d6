// Playback over all steps at the chosen speed, each step rendered while the one before it shows
// (so that its frame is there at its due time). At a step's due time the frame of the step ahead that has arrived (the
// newest pass of it) is shown and the step after it is sent; the server renders that one for the
// whole period: its level is the finest whose pass fits the period less the transport (the state's
// timeBudgetMs, docs/protocol.md "playback"), at full size, and its passes refine it until the next
// step is sent. So at 2 steps/s a step gets half a second of rendering, at 10 steps/s a tenth.
// It never floods the server: the next step goes only once a frame of the one ahead has been
// shown. Pausing renders the step on screen at full quality.
import type { Frame } from './connection';

const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;

export interface PlaybackHost {
  readonly stepCount: number;
  // The step on screen (the store's).
  currentStep(): number;
  // Sends `step` as a step of playback with the time budget and holds its frames; returns its id.
  sendStep(step: number, budgetMs: number): number;
  // Whether a frame of state `id` is held, and showing it (it becomes the step on screen).
  hasHeld(id: number): boolean;
  showHeld(step: number): void;
  // The id of the newest state sent (by playback or anything else) and whether it has a frame.
  lastSentId(): number;
  caughtUp(): boolean;
  // Shows frames as they come again (a held one is dropped).
  stopHolding(): void;
  // The still frame of a step (when paused).
  setStep(step: number, interactive: boolean): void;
  // Called when playing starts or stops (before the still frame of the step paused at is asked).
  playingChanged(playing: boolean): void;
}

// How late a step may be shown (a share of the period) and the schedule still kept.
const kLateShare = 0.25;
// What the server is told to leave for the transport when the first frame's has not been measured, ms.
const kInitialTransportMs = 40;

export class Playback {
  playing = false;
  private ahead: { step: number; id: number; sentAt: number } | null = null;
  private lastAdvance = 0;
  private advanceTimer = 0;
  // From a step sent to its first frame received, less the server's pass: preparing, encoding and
  // sending (an exponential average).
  private transportMs = kInitialTransportMs;

  constructor(private readonly host: PlaybackHost) {}

  toggle(): void {
    this.playing = !this.playing;
    $('play').textContent = this.playing ? '❚❚' : '▶';
    this.host.playingChanged(this.playing);
    clearTimeout(this.advanceTimer);
    if (this.playing) {
      this.lastAdvance = performance.now();
      this.sendAhead();
      this.schedule(this.periodMs());
    } else {
      this.ahead = null;
      this.host.stopHolding();
      this.host.setStep(this.host.currentStep(), false);
    }
  }

  private periodMs(): number {
    return 1000 / (Number($<HTMLSelectElement>('fps').value) || 2);
  }

  private schedule(ms: number): void {
    clearTimeout(this.advanceTimer);
    this.advanceTimer = window.setTimeout(() => this.maybeAdvance(), Math.max(0, ms));
  }

  private sendAhead(): void {
    const step = (this.host.currentStep() + 1) % this.host.stepCount;
    const period = this.periodMs();
    const budget = Math.max(1, period - Math.min(this.transportMs, period / 2));
    this.ahead = { step, id: this.host.sendStep(step, budget), sentAt: performance.now() };
  }

  // A frame of the step ahead arrived (and was held): it measures the transport.
  frameHeld(frame: Frame): void {
    const h = frame.header;
    if (!this.playing || !this.ahead || h.id !== this.ahead.id) return;
    if (h.pass === 1) {
      const transport = Math.max(0, frame.receivedAt - this.ahead.sentAt - (h.stats?.passMs ?? 0));
      this.transportMs = 0.7 * this.transportMs + 0.3 * transport;
    }
    this.maybeAdvance();
  }

  // Shows the step ahead once it is due and a frame of it has arrived, then sends the next. Steps
  // are due on a regular schedule (lastAdvance is when the last one was due, not when it showed), so
  // a timer that fires a little late does not slow playback down; a step whose frame came more than
  // a quarter of a period late starts the schedule again from now, so that the next step still gets
  // at least three quarters of a period on the server (the speed drops instead). Called by the timer,
  // on every frame held, and on every frame shown (another state — a brush, the camera — may have
  // replaced the step ahead on the server: it is sent again once that state has its frame).
  maybeAdvance(): void {
    const ahead = this.ahead;
    if (!this.playing || !ahead) return;
    if (!this.host.hasHeld(ahead.id)) {
      if (this.host.lastSentId() !== ahead.id && this.host.caughtUp()) this.sendAhead();
      return;
    }
    const period = this.periodMs(), now = performance.now();
    const wait = this.lastAdvance + period - now;
    if (wait > 0) {
      this.schedule(wait);
      return;
    }
    this.lastAdvance = wait >= -kLateShare * period ? this.lastAdvance + period : now;
    this.host.showHeld(ahead.step); // the time bar follows when its frame is on screen
    this.sendAhead();
    this.schedule(this.lastAdvance + period - performance.now());
  }
}
