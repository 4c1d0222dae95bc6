"""A one-line progress display on stderr for long runs (sweeps, flip maps, Lyapunov scans).

``ProgressLine(total, label)`` rewrites a single line ``label: done/total (pct) elapsed, ETA`` with
a carriage return, at most every ``min_interval`` seconds, and ends it with a newline on
:meth:`close`. It is a context manager. With ``enabled=None`` it is shown only when stderr is a
terminal, so CI logs and test output stay clean; ``enabled=True`` forces it.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO


def _format_seconds(seconds: float) -> str:
    """Return ``"12.3 s"`` below a minute, ``"4 min 05 s"`` above."""
    if seconds < 60.0:
        return f"{seconds:.1f} s"
    minutes, secs = divmod(int(round(seconds)), 60)
    return f"{minutes} min {secs:02d} s"


class ProgressLine:
    """Count finished work items and show ``done/total`` with elapsed time and an ETA."""

    def __init__(
        self,
        total: int,
        label: str,
        *,
        enabled: bool | None = None,
        stream: TextIO | None = None,
        min_interval: float = 0.5,
    ) -> None:
        self.total = max(int(total), 0)
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            enabled = bool(getattr(self.stream, "isatty", lambda: False)())
        self.enabled = enabled
        self.min_interval = min_interval
        self.done = 0
        self.start = time.perf_counter()
        self._last_shown = -float("inf")

    def line(self) -> str:
        """The current progress text (without carriage return)."""
        elapsed = time.perf_counter() - self.start
        pct = 100.0 * self.done / self.total if self.total else 100.0
        text = f"{self.label}: {self.done}/{self.total} ({pct:.0f} %), {_format_seconds(elapsed)}"
        if 0 < self.done < self.total:
            eta = elapsed * (self.total - self.done) / self.done
            text += f", ETA {_format_seconds(eta)}"
        return text

    def update(self, n: int = 1) -> None:
        """Add ``n`` finished items and redraw if ``min_interval`` has passed (or all are done)."""
        self.done += n
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self._last_shown >= self.min_interval or self.done >= self.total:
            self._last_shown = now
            self.stream.write("\r" + self.line())
            self.stream.flush()

    def close(self) -> None:
        """Draw the final state and end the line."""
        if self.enabled:
            self.stream.write("\r" + self.line() + "\n")
            self.stream.flush()

    def __enter__(self) -> ProgressLine:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
