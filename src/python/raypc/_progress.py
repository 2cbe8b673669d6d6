"""The progress bar of long calls (preprocessing, rendering, statistics, features), which the
compiled module calls back with each phase's steps done."""
from __future__ import annotations

import sys
import time


class _Progress:
    """A one-line progress report on stderr ("\\r"-updated; a notebook shows it in place), once
    the work has taken `delay` seconds (quick work prints nothing)."""

    def __init__(self, label: str, enabled: bool, delay: float = 0.0):
        self.label, self.enabled, self.shown = label, enabled, False
        self.start, self.delay = time.monotonic(), delay

    def __call__(self, phase: str, done: int, total: int) -> None:
        if not self.enabled or (not self.shown and time.monotonic() - self.start < self.delay):
            return
        width = 30
        filled = int(width * done / max(total, 1))
        sys.stderr.write(f"\r{self.label} {phase}: [{'#' * filled}{'.' * (width - filled)}] {done}/{total}")
        sys.stderr.flush()
        self.shown = True

    def close(self) -> None:
        if self.shown:
            sys.stderr.write("\n")
            sys.stderr.flush()
