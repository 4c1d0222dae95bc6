"""Progress of long loops and of a scenario's steps, on a terminal, in a notebook and in a log file.

* :func:`step` prints what a scenario is doing now (one line on stdout: ``  - fitting ...``).
* :func:`progress_bar` counts a loop: a tqdm bar (``tqdm.auto``: a text bar on a terminal, a widget
  in a notebook) with rate and time left. When stderr is not a terminal (a log file, CI, a pipe) the
  bar becomes plain lines on stderr, one per 10 % of the loop and only for loops that last longer
  than :data:`QUIET_SECONDS`, so a log shows the progress of the long loops in a few lines.
* :func:`track` wraps an iterable in :func:`progress_bar`.
* :func:`write_line` prints a line while a bar is shown, without breaking the bar.

``DOUBLE_PENDULUM_PROGRESS`` overrides the choice: ``bar`` (always a tqdm bar), ``lines`` (always
plain lines), ``off`` (no progress at all; :func:`step` lines are still printed).
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Iterable, Iterator
from typing import Any, TypeVar

from tqdm.auto import tqdm
from tqdm.autonotebook import tqdm as notebook_or_std_tqdm
from tqdm.std import tqdm as std_tqdm

T = TypeVar("T")

ENV = "DOUBLE_PENDULUM_PROGRESS"
QUIET_SECONDS = 5.0
"""Plain-line mode stays silent for loops shorter than this [s]."""
LINE_FRACTION = 0.1
"""Plain-line mode prints a line each time this fraction of the loop is done."""
LINE_EVERY_S = 60.0
"""... and also when an item finishes this long [s] after the last line (or the start)."""


def step(text: str) -> None:
    """Say what the scenario does now: one line on stdout (flushed)."""
    print(f"  - {text}", flush=True)


def write_line(text: str, stream: Any = None) -> None:
    """Print ``text`` on ``stream`` (default stdout) without breaking a tqdm bar shown meanwhile."""
    stream = sys.stdout if stream is None else stream
    tqdm.write(text, file=stream)
    stream.flush()


def _in_notebook() -> bool:
    """True if ``tqdm.auto`` chose its notebook widget (running in a Jupyter kernel)."""
    return notebook_or_std_tqdm is not std_tqdm


def _mode(enabled: bool | None) -> str:
    """``bar``, ``lines`` or ``off`` for a loop (see the module docstring)."""
    if enabled is False:
        return "off"
    forced = os.environ.get(ENV, "").strip().lower()
    if forced in ("bar", "lines", "off"):
        return forced
    if enabled is True:
        return "bar"
    stream = sys.stderr
    on_terminal = bool(getattr(stream, "isatty", lambda: False)())
    return "bar" if (on_terminal or _in_notebook()) else "lines"


def _clock(seconds: float) -> str:
    seconds = int(round(seconds))
    minutes, seconds = divmod(seconds, 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}:{minutes:02d}:{seconds:02d}" if hours else f"{minutes}:{seconds:02d}"


class LineProgress:
    """The quiet stand-in for a tqdm bar when stderr is not a terminal (same ``update``/``close`` use).

    Prints ``label: 40/134 (30 %), 0:45 elapsed, 0.9 run/s, about 1:45 left`` on stderr each time
    another :data:`LINE_FRACTION` of ``total`` is done, once the loop has run :data:`QUIET_SECONDS`;
    a closing line if it printed anything.
    """

    def __init__(self, total: int, desc: str, unit: str = "run", file: Any = None) -> None:
        self.total, self.desc, self.unit = max(int(total), 0), desc, unit
        self.file = file
        self.n = 0
        self.start = time.monotonic()
        self.marks = 1  # lines printed for LINE_FRACTION, 2 LINE_FRACTION, ... of total
        self.printed = False
        self.closed = False
        self.last_line = self.start

    def _write(self, text: str) -> None:
        stream = self.file or sys.stderr
        print(f"{self.desc}: {text}", file=stream, flush=True)
        self.printed = True

    def _rate(self, elapsed: float) -> str:
        rate = self.n / elapsed if elapsed > 0 else 0.0
        return f"{rate:.3g} {self.unit}/s" if rate >= 1 or rate == 0 else f"{1 / rate:.3g} s/{self.unit}"

    def update(self, n: int = 1) -> None:
        self.n += n
        if self.total <= 0:
            return
        fraction = self.n / self.total
        now = time.monotonic()
        crossed = fraction >= self.marks * LINE_FRACTION - 1e-9
        overdue = now - self.last_line >= LINE_EVERY_S
        if not (crossed or overdue) or self.n >= self.total:
            return
        while self.marks * LINE_FRACTION - 1e-9 <= fraction:
            self.marks += 1
        elapsed = now - self.start
        if elapsed < QUIET_SECONDS:
            return
        self.last_line = now
        left = elapsed / self.n * (self.total - self.n)
        self._write(f"{self.n}/{self.total} ({100 * fraction:.0f} %), {_clock(elapsed)} elapsed, "
                    f"{self._rate(elapsed)}, about {_clock(left)} left")

    def set_total(self, total: int) -> None:
        """Make the loop ``total`` items long from now on (a run that turns out to need more work than expected)."""
        self.total = max(int(total), 0)

    def set_description(self, desc: str | None = None, refresh: bool = True) -> None:
        if desc:
            self.desc = desc

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        """Accepted for tqdm compatibility; plain lines carry no postfix."""

    def close(self, stopped: str = "") -> None:
        """Close with a line saying how far the loop got: "done" if it ended, or ``stopped`` ("interrupted") if
        it was cut short (then always, so that the last line never claims the work done)."""
        if self.closed:
            return
        self.closed = True
        elapsed = time.monotonic() - self.start
        if stopped:
            self._write(f"{stopped} at {self.n}/{self.total} after {_clock(elapsed)}")
        elif self.printed or (elapsed >= QUIET_SECONDS and self.n):
            self._write(f"{self.n}/{self.total} done in {_clock(elapsed)} ({self._rate(elapsed)})")

    def __enter__(self) -> LineProgress:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, *exc: object) -> None:
        self.close(stopped_word(exc_type))


def stopped_word(exc_type: type[BaseException] | None) -> str:
    """How a loop that ended with ``exc_type`` ended, for its closing line: "" (it ended), "interrupted" (Ctrl-C)
    or "stopped" (an error)."""
    if exc_type is None:
        return ""
    return "interrupted" if issubclass(exc_type, KeyboardInterrupt) else "stopped"


class _Off(LineProgress):
    def update(self, n: int = 1) -> None:
        self.n += n

    def close(self, stopped: str = "") -> None:
        self.closed = True


class _Bar:
    """A tqdm bar as a context manager that, when the loop is cut short, says so in the bar ("interrupted at 40/56")
    before closing, instead of leaving it standing as if it were still counting; everything else is tqdm's."""

    def __init__(self, bar: Any) -> None:
        self._bar = bar

    def __getattr__(self, name: str) -> Any:
        return getattr(self._bar, name)

    def set_total(self, total: int) -> None:
        """Make the bar ``total`` items long from now on."""
        self._bar.total = int(total)
        self._bar.refresh()

    def __enter__(self) -> _Bar:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, *exc: object) -> None:
        word = stopped_word(exc_type)
        if word:
            self._bar.set_description_str(f"{self._bar.desc}: {word} at {self._bar.n}/{self._bar.total}",
                                          refresh=False)
        self._bar.close()


def progress_bar(total: int, label: str, *, unit: str = "run", enabled: bool | None = None) -> Any:
    """A progress counter of ``total`` items named ``label``, used as ``with ...: bar.update(1)``.

    ``enabled=None``: a tqdm bar (rate, time left) on a terminal or in a notebook, plain lines
    (:class:`LineProgress`) otherwise; ``True``: always a tqdm bar; ``False``: nothing.
    """
    mode = _mode(enabled)
    if mode == "off":
        return _Off(total, label, unit)
    if mode == "lines":
        return LineProgress(total, label, unit)
    return _Bar(tqdm(total=total, desc=label, file=sys.stderr, mininterval=0.5, unit=unit, dynamic_ncols=True))


def track(items: Iterable[T], label: str, *, total: int | None = None, unit: str = "run",
          enabled: bool | None = None) -> Iterator[T]:
    """Iterate over ``items`` with a :func:`progress_bar` (``total`` defaults to ``len(items)``)."""
    if total is None:
        total = len(items)  # type: ignore[arg-type]
    with progress_bar(total, label, unit=unit, enabled=enabled) as bar:
        for item in items:
            yield item
            bar.update(1)
