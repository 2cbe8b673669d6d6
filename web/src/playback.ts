// Playback over all steps at the chosen speed. It never floods the server: the next step is
// requested only after a frame of the current one has arrived (`caughtUp`). Pausing renders the
// current step at full quality.
const $ = <T extends HTMLElement = HTMLElement>(id: string) => document.getElementById(id) as T;

export interface PlaybackHost {
  readonly stepCount: number;
  currentStep(): number;
  caughtUp(): boolean;
  // interactive: one pass while playing; false: the still frame when paused.
  setStep(step: number, interactive: boolean): void;
  // Called when playing starts or stops (before the still frame of the step paused at is asked).
  playingChanged(playing: boolean): void;
}

export class Playback {
  playing = false;
  private lastAdvance = 0;
  private advanceTimer = 0;

  constructor(private readonly host: PlaybackHost) {}

  toggle(): void {
    this.playing = !this.playing;
    $('play').textContent = this.playing ? '❚❚' : '▶';
    this.host.playingChanged(this.playing);
    if (this.playing) {
      this.lastAdvance = 0;
      this.maybeAdvance();
    } else {
      clearTimeout(this.advanceTimer);
      this.host.setStep(this.host.currentStep(), false);
    }
  }

  // Advances one step once the frame for the current step has arrived and the speed allows. Steps
  // are due on a regular schedule (lastAdvance is when the last one was due, not when it went): a
  // step whose frame came late is followed by one sent at once, so the speed holds on average;
  // more than a period behind, the schedule starts again from now.
  maybeAdvance(): void {
    if (!this.playing || !this.host.caughtUp()) return;
    const fps = Number($<HTMLSelectElement>('fps').value) || 2;
    const period = 1000 / fps, now = performance.now();
    const wait = period - (now - this.lastAdvance);
    clearTimeout(this.advanceTimer);
    if (wait > 0) {
      this.advanceTimer = window.setTimeout(() => this.maybeAdvance(), wait);
      return;
    }
    this.lastAdvance = wait > -period ? this.lastAdvance + period : now;
    const next = (this.host.currentStep() + 1) % this.host.stepCount;
    this.host.setStep(next, true);
    $<HTMLInputElement>('step').value = String(next);
  }
}
