"""Run the FMU through fmpy, the way FMI users know it (``fmpy.simulate_fmu``).

:class:`FmuRunner` extracts the FMU once and runs it as often as needed. An FMI 2 co-simulation
FMU is instantiated once and reset between runs (``fmi2Reset``, as in FMPy's own parameter-variation
example): a run then costs no new instance, and a long sweep no memory per case. FMU log messages
are always collected, so a failing run raises :class:`FmuRunError` with the FMU's own message (for
instance ``invalid l1 = -1.0 m: must be > 0``) even though fmpy itself only reports the status.
"""

from __future__ import annotations

import contextlib
import shutil
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ...model.outputs import OUTPUT_NAMES
from ..build.fmi2 import DEFAULT_FMU_PATH, build_fmu, fmu_is_current


class FmuRunError(RuntimeError):
    """An FMU call failed; the message includes what the FMU logged.

    ``partial_result`` holds the rows fmpy returned before the failure (or ``None``).
    """

    def __init__(self, message: str, partial_result: np.ndarray | None = None) -> None:
        super().__init__(message)
        self.partial_result = partial_result


def ensure_fmu(path: str | Path = DEFAULT_FMU_PATH, *, rebuild: bool = False) -> Path:
    """Return ``path``, building the FMU there first if it is missing or older than the sources."""
    path = Path(path)
    if rebuild or not fmu_is_current(path):
        build_fmu(path)
    return path


class FmuRunner:
    """Simulate one FMU file repeatedly with fmpy (extracted once; an FMI 2 co-simulation instance reused).

    ``fmu_path`` is an FMU file, extracted here and removed again by :meth:`close`, or the folder of an FMU already
    extracted (:func:`fmpy.extract`), which stays: its owner removes it (the app extracts once for all its runs'
    processes, so a run's process killed at any point leaves nothing behind)."""

    def __init__(self, fmu_path: str | Path, *, reuse_instance: bool = True) -> None:
        from fmpy import extract, read_model_description

        self.fmu_path = Path(fmu_path)
        self.model_description = read_model_description(str(self.fmu_path))
        self._owns_unzipdir = not self.fmu_path.is_dir()
        self.unzipdir = extract(str(self.fmu_path)) if self._owns_unzipdir else str(self.fmu_path)
        self.units = {
            v.name: (v.unit or (v.declaredType.unit if v.declaredType else None) or "")
            for v in self.model_description.modelVariables
        }
        md = self.model_description
        self.reuse_instance = reuse_instance and md.fmiVersion == "2.0" and md.coSimulation is not None
        self._instance: Any = None  # the FMI 2 instance runs reuse, with its log sink
        self._messages: list[str] = []

    def close(self) -> None:
        """Free the instance, then remove the extracted FMU."""
        instance, self._instance = self._instance, None
        if instance is not None:
            _SINKS.pop(id(self), None)
            with contextlib.suppress(Exception):
                instance.freeInstance()
        if self._owns_unzipdir:
            shutil.rmtree(self.unzipdir, ignore_errors=True)

    def __enter__(self) -> FmuRunner:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _reused_instance(self) -> Any:
        """The runner's FMI 2 instance, reset (a new one if there is none, or if it cannot be reset)."""
        from fmpy.fmi2 import FMU2Slave

        if self._instance is not None:
            try:
                self._instance.reset()
                return self._instance
            except Exception:  # not resettable: start afresh
                instance, self._instance = self._instance, None
                with contextlib.suppress(Exception):
                    instance.freeInstance()
        md = self.model_description
        identifier = md.coSimulation.modelIdentifier
        instance = FMU2Slave(guid=md.guid, unzipDirectory=self.unzipdir, modelIdentifier=identifier,
                             instanceName=identifier)
        _SINKS[id(self)] = self._messages
        instance.instantiate(callbacks=_callbacks(id(self)), loggingOn=False)  # errors are logged all the same
        self._instance = instance
        return instance

    def simulate(
        self,
        start_values: Mapping[str, Any] | None = None,
        *,
        stop_time: float = 10.0,
        output_interval: float = 0.01,
        start_time: float = 0.0,
        outputs: Sequence[str] = OUTPUT_NAMES,
        **fmpy_options: Any,
    ) -> np.ndarray:
        """Run the FMU and return fmpy's structured result array (``time`` plus ``outputs``).

        ``output_interval`` [s] is also the communication step size. Extra keyword arguments go
        to :func:`fmpy.simulate_fmu` (e.g. ``input=`` a structured array of input signals). A
        failing call raises :class:`FmuRunError` with the rows recorded before it. Results do not
        depend on the instance being reused: a reset instance starts from its defaults, bit for bit
        as a new one (tests/test_sweep.py).
        """
        from fmpy import simulate_fmu

        recorders: list[Any] = []
        user_step_finished = fmpy_options.pop("step_finished", None)

        def step_finished(time: float, recorder: Any) -> bool:
            if not recorders:
                recorders.append(recorder)
            return True if user_step_finished is None else user_step_finished(time, recorder)

        reuse = self.reuse_instance and fmpy_options.get("fmi_type", "CoSimulation") == "CoSimulation"
        messages = self._messages
        messages.clear()

        def logger(*call: Any) -> None:  # FMI 2: (env, instance, status, category, message); FMI 3: no instance
            _collect(messages, call[-3], call[-1])

        try:
            how = {"fmu_instance": self._reused_instance()} if reuse else {"debug_logging": True,
                                                                            "logger": logger}
            result = simulate_fmu(
                self.unzipdir,
                validate=False,  # validated once by read_model_description
                model_description=self.model_description,
                start_time=start_time,
                stop_time=stop_time,
                output_interval=output_interval,
                start_values=dict(start_values or {}),
                output=list(outputs),
                step_finished=step_finished,
                **how,
                **fmpy_options,
            )
        except Exception as error:
            partial = recorders[0].result() if recorders else None
            raise FmuRunError(f"{error} -- FMU says: {_summarise(messages)}", partial_result=partial) from error
        finally:
            if not reuse:
                keep_fmpy_logger_alive()
        # fmpy ends a run quietly when doStep returns fmi2Discard: turn that into an error.
        end = float(result["time"][-1]) if len(result) else start_time
        if end < stop_time and not np.isclose(end, stop_time, rtol=1e-12, atol=1e-12):
            raise FmuRunError(
                f"the FMU stopped at t = {end:g} s before stop_time = {stop_time:g} s -- "
                f"FMU says: {_summarise(messages)}",
                partial_result=result,
            )
        return result


def _collect(messages: list[str], status: int, message: Any) -> None:
    if status >= 2:  # discard, error, fatal
        messages.append(message.decode("utf-8", "replace") if isinstance(message, bytes) else str(message))


# ------------------------------------------------------------------------------- fmpy's logger
#
# fmpy formats the FMI 2 log messages in a small C proxy (``fmpy/logging/logging.c``) that keeps one
# logger for the whole process: the last one any instance was given. A logger that is garbage
# collected while the proxy holds it makes the next message of any FMU call freed memory (a crash;
# docs/fmu.md, "fmpy's logger"). The runner's instances therefore share one logger that lives as long
# as the process and dispatches by componentEnvironment to the runner's messages; a message of an
# instance it does not know (fmpy's default callbacks, after the proxy was given this logger) is
# printed as fmpy's own printLogMessage does.

_SINKS: dict[int, list[str]] = {}  # componentEnvironment -> the runner's messages
_LIVE: dict[str, Any] = {}  # the dispatcher's native callback and fmi2CallbackFunctions, kept for good


def _dispatch(environment: Any, instance_name: Any, status: int, category: Any, message: Any) -> None:
    from fmpy.fmi2 import printLogMessage

    sink = _SINKS.get(environment or 0)
    if sink is None:
        printLogMessage(environment, instance_name, status, category, message)
    else:
        _collect(sink, status, message)


def _callbacks(key: int) -> Any:
    """fmi2CallbackFunctions for one runner's instance: the process-long dispatcher, its key as environment."""
    from ctypes import c_void_p

    from fmpy.fmi2 import fmi2CallbackFunctions

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = _dispatcher()
    callbacks.componentEnvironment = c_void_p(key)
    with contextlib.suppress(Exception):  # no proxy on this platform: the logger gets no variadic arguments
        from ctypes import byref

        from fmpy.logging import addLoggerProxy

        addLoggerProxy(byref(callbacks))
    _LIVE.setdefault("instances", {})[key] = callbacks  # as long as its instance may log
    return callbacks


def _dispatcher() -> Any:
    from fmpy.fmi2 import fmi2CallbackLoggerTYPE

    if "thunk" not in _LIVE:
        _LIVE["thunk"] = fmi2CallbackLoggerTYPE(_dispatch)
    return _LIVE["thunk"]


def keep_fmpy_logger_alive() -> None:
    """Point fmpy's native logger proxy back at a logger that lives as long as the process (after a
    ``simulate_fmu(logger=...)`` run, whose logger is about to be garbage collected)."""
    from ctypes import byref

    from fmpy.fmi2 import fmi2CallbackFunctions

    try:
        from fmpy.logging import addLoggerProxy
    except Exception:  # no proxy on this platform: nothing to point back
        return
    callbacks = _LIVE.setdefault("restore", fmi2CallbackFunctions())
    callbacks.logger = _dispatcher()  # the proxy takes it only from a struct not yet proxied
    addLoggerProxy(byref(callbacks))


def _summarise(messages: list[str]) -> str:
    """Join the FMU's error messages, keeping the last line of each (the exception itself)."""
    return "; ".join(m.strip().split("\n")[-1] for m in messages) or "no message logged"
