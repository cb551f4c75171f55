"""Wall-clock stage times of a run (fits and diagnoses report where their time went)."""
from __future__ import annotations

import time


class StageClock:
    """Started on creation; end(name) records the wall time [s] of the stage that began at the previous end()
    (or at the start) and ends now. `stages` maps stage name -> seconds, in order."""

    def __init__(self):
        self.start = self._last = time.perf_counter()
        self.stages: dict[str, float] = {}

    def end(self, name: str) -> None:
        """Close the current stage under `name`."""
        now = time.perf_counter()
        self.stages[name] = now - self._last
        self._last = now

    def elapsed(self) -> float:
        """Wall time since the start [s]."""
        return time.perf_counter() - self.start
