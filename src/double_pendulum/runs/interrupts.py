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

_state: dict[str, Any] = {"installed": False, "interrupted": False, "acknowledged": False, "hurried": False,
                          "ends_process": False}
_stop_repeating = threading.Event()
_repeating = threading.Lock()
"""Held while the repeating thread decides to raise again, so that once :func:`_stop_repeat` returns it never does."""


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
        with _repeating:
            if _stop_repeating.is_set():  # stopped while this thread woke: an interrupt now would come too late
                return
            _thread.interrupt_main(signal.SIGINT)


def _stop_repeat() -> None:
    """Stop raising the interrupt again; after this returns no new one is raised."""
    with _repeating:
        _stop_repeating.set()


def ends_the_process() -> None:
    """Called by the command's entry point, whose process ends with the run: after an interrupted run SIGINT is
    ignored (:data:`signal.SIG_IGN`, which Python's finalisation keeps, where it resets a Python handler to the
    default) until the process exits. Without this a second Ctrl-C that came after the clean-up, while the
    interpreter exited, killed the process by the signal (exit status -2, not 130) or printed a traceback."""
    _state["ends_process"] = True


def _ignore_sigint() -> None:
    """Ignore SIGINT. :func:`signal.signal` may first run the handler of a SIGINT still pending, :func:`_on_first`
    raising the interrupt being handled already: that one is dropped and the call made again (a pending SIGINT is
    consumed by the attempt that runs it, so a further one needs yet another Ctrl-C in between; three attempts)."""
    for _ in range(3):
        with contextlib.suppress(KeyboardInterrupt):
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            return


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
    _stop_repeat()
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
    after it (a run started from Python, e.g. by the tests, leaves the caller's handler as it was), except after
    an interrupted run in a process that ends with it (:func:`ends_the_process`). An error that leaves the block
    after SIGINT leaves it as KeyboardInterrupt: the interrupt, reported as an error by code that could not pass
    it on (scipy's C extension raised "ImportError: initialization failed" when it landed in its import)."""
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
    except Exception:
        if _state["interrupted"]:  # Ctrl-C that code in between turned into an error of its own: an FMU's error
            raise KeyboardInterrupt from None  # status, a C extension's "ImportError: initialization failed"
        raise
    finally:
        _stop_repeat()
        if _state["interrupted"] and _state["ends_process"]:
            _ignore_sigint()  # the run is cleaned up and the process ends: a later Ctrl-C has nothing to do
        else:
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
