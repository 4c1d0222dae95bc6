"""Ctrl-C for a run and its processes: one SIGINT stops the run promptly, a second one hurries its clean-up.

A run (``double-pendulum run``) handles SIGINT itself (:func:`handling_interrupts`): the first one raises
KeyboardInterrupt in the main thread, as Python does, and keeps raising it every :data:`REPEAT_S` until code
of the run catches it and calls :func:`acknowledge`. That matters because the FMU runs its Python code in
this interpreter: pythonfmu turns an exception raised there, KeyboardInterrupt included, into an FMI error
status, which fmpy reports as an ordinary failure that a scenario may catch and carry on from. After
:func:`acknowledge` the run cleans up (stops its worker processes, discards unfinished folders); a second
SIGINT then only sets :func:`hurried`, so that waits for child processes end at once and nothing of the
clean-up is cut short.

The interrupt can land in a finaliser or a weakref callback (a ``WeakKeyDictionary``'s, say), where Python cannot
raise it and prints "Exception ignored in ..." with a traceback instead. While the run handles SIGINT it drops
those reports of a KeyboardInterrupt (:func:`_quiet_unraisable`): the interrupt is raised again within
:data:`REPEAT_S` in the main thread, and a traceback is no message for a user who pressed Ctrl-C.

Worker processes never see Ctrl-C (:func:`worker_ignores_sigint`, :func:`sigint_blocked` while they start):
the process that started them stops them (:func:`double_pendulum.analysis.sweep.stop_workers`).
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Iterator
from typing import Any

REPEAT_S = 0.25
"""How often [s] an unacknowledged interrupt is raised again in the main thread."""

_state: dict[str, Any] = {"installed": False, "interrupted": False, "acknowledged": False, "hurried": False}
_stop_repeating = threading.Event()


def interrupted() -> bool:
    """Whether the run got SIGINT (while :func:`handling_interrupts` is active)."""
    return bool(_state["interrupted"])


def hurried() -> bool:
    """Whether a second SIGINT came after the run began to clean up: end waits at once."""
    return bool(_state["hurried"])


def _repeat() -> None:
    """Raise KeyboardInterrupt in the main thread again until it is acknowledged."""
    import _thread

    while not _stop_repeating.wait(REPEAT_S):
        _thread.interrupt_main(signal.SIGINT)


def _on_first(signum: int, frame: Any) -> None:
    """The first SIGINT: note it, raise KeyboardInterrupt, and again until acknowledged."""
    if not _state["interrupted"]:
        _state["interrupted"] = True
        threading.Thread(target=_repeat, name="repeat-interrupt", daemon=True).start()
    raise KeyboardInterrupt


def _on_later(signum: int, frame: Any) -> None:
    """SIGINT during the clean-up: hurry it, but do not interrupt it."""
    _state["hurried"] = True


def acknowledge() -> None:
    """Called where the run catches KeyboardInterrupt to clean up: stop raising it; a later SIGINT hurries."""
    if not _state["installed"] or _state["acknowledged"]:
        return
    _state["acknowledged"] = True
    _stop_repeating.set()
    with contextlib.suppress(ValueError):  # not the main thread: the handler stays
        signal.signal(signal.SIGINT, _on_later)


def _quiet_unraisable(hook: Any) -> Any:
    """An ``sys.unraisablehook`` that drops a KeyboardInterrupt Python could not raise (in a finaliser or weakref
    callback) and passes everything else to ``hook``."""

    def unraisable(info: Any) -> None:
        if isinstance(info.exc_value, KeyboardInterrupt) or info.exc_type is KeyboardInterrupt:
            return
        hook(info)

    return unraisable


@contextlib.contextmanager
def handling_interrupts() -> Iterator[None]:
    """Within the block, SIGINT acts as described in the module docstring; the previous handler is restored
    after it (a run started from Python, e.g. by the tests, leaves the caller's handler as it was)."""
    try:
        previous = signal.signal(signal.SIGINT, _on_first)
    except ValueError:  # not the main thread: Python's own handling
        yield
        return
    _state.update(installed=True, interrupted=False, acknowledged=False, hurried=False)
    _stop_repeating.clear()
    previous_hook = sys.unraisablehook
    sys.unraisablehook = _quiet_unraisable(previous_hook)
    try:
        yield
    finally:
        _stop_repeating.set()
        signal.signal(signal.SIGINT, previous)
        sys.unraisablehook = previous_hook
        _state.update(installed=False)


@contextlib.contextmanager
def sigint_blocked() -> Iterator[None]:
    """SIGINT is held back (not lost) within the block: processes started in it inherit the blocked signal
    until they ignore it (:func:`worker_ignores_sigint`), so Ctrl-C cannot hit them while they import."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def worker_ignores_sigint() -> None:
    """Initializer of a worker process: ignore SIGINT (the parent stops the worker) and let it through again."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
