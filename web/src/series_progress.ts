// While the server shows the first step of netCDF files and preprocesses the rest of the series in
// the background (`raypc serve FILE.nc…`, GET /api/progress in docs/protocol.md), the header says how
// far it is. Once the server of the whole series has replaced it (same address), the page reloads:
// the URL holds the state, so the view stays as it was and every step becomes available.
import { fetchProgress, type SeriesProgress } from './api';

const kPollMs = 1000;

function minutesText(seconds: number): string {
  if (seconds < 90) return `${Math.max(1, Math.round(seconds))} s`;
  if (seconds < 5400) return `${Math.round(seconds / 60)} min`;
  return `${(seconds / 3600).toFixed(1)} h`;
}

export function progressText(p: SeriesProgress): string {
  const steps = p.steps ?? 0;
  if (p.state === 'failed')
    return `Preprocessing the other ${steps - 1} steps stopped: ${p.message ?? 'unknown error'}. Showing step 0 only.`;
  if (p.state === 'ready') return `All ${steps} steps are ready; reloading…`;
  const what = p.phase === 'pathlines' ? 'pathlines of step' : 'step';
  const eta = p.etaSeconds == null ? '' : ` · about ${minutesText(p.etaSeconds)} left`;
  return `Showing step 0 while the series is preprocessed: ${what} ${p.done ?? 0} of ${p.total ?? steps} done${eta}`;
}

// Polls until the series is served whole (then reloads) or its preprocessing failed.
export function watchSeriesProgress(element: HTMLElement): void {
  let seenPartial = false;
  const poll = async (): Promise<void> => {
    let p: SeriesProgress | null = null;
    try {
      p = await fetchProgress();
    } catch {
      // The server is being replaced by the one of the whole series: ask again.
    }
    if (p?.state === 'complete') {
      if (seenPartial) location.reload();
      return;
    }
    if (p) {
      seenPartial = true;
      element.hidden = false;
      element.textContent = progressText(p);
      element.classList.toggle('failed', p.state === 'failed');
      if (p.state === 'failed') return;
    }
    setTimeout(() => void poll(), kPollMs);
  };
  void poll();
}
