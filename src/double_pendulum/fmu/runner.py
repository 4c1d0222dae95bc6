"""Run the FMU through fmpy, the way FMI users know it (``fmpy.simulate_fmu``).

:class:`FmuRunner` extracts the FMU once and runs it as often as needed. FMU log messages are
always collected, so a failing run raises :class:`FmuRunError` with the FMU's own message (for
instance ``invalid l1 = -1.0 m: must be > 0``) even though fmpy itself only reports the status.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..model.outputs import OUTPUT_NAMES
from .build import DEFAULT_FMU_PATH, build_fmu, fmu_is_current

FMU_STDERR_SWITCH = "DOUBLE_PENDULUM_FMU_STDERR"


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
    """Simulate one FMU file repeatedly with fmpy (extracted once)."""

    def __init__(self, fmu_path: str | Path) -> None:
        from fmpy import extract, read_model_description

        self.fmu_path = Path(fmu_path)
        self.model_description = read_model_description(str(self.fmu_path))
        self.unzipdir = extract(str(self.fmu_path))
        self.units = {
            v.name: (v.unit or (v.declaredType.unit if v.declaredType else None) or "")
            for v in self.model_description.modelVariables
        }

    def close(self) -> None:
        """Remove the extracted FMU."""
        shutil.rmtree(self.unzipdir, ignore_errors=True)

    def __enter__(self) -> FmuRunner:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

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
        failing call raises :class:`FmuRunError` with the rows recorded before it.
        """
        from fmpy import simulate_fmu

        messages: list[str] = []
        recorders: list[Any] = []
        user_step_finished = fmpy_options.pop("step_finished", None)

        def step_finished(time: float, recorder: Any) -> bool:
            if not recorders:
                recorders.append(recorder)
            return True if user_step_finished is None else user_step_finished(time, recorder)

        def logger(_env: Any, _instance: Any, status: int, _category: Any, message: bytes) -> None:
            if status >= 2:  # discard, error, fatal
                messages.append(
                    message.decode("utf-8", "replace") if isinstance(message, bytes) else str(message)
                )

        try:
            with _fmu_errors_to_log_only():
                result = simulate_fmu(
                    self.unzipdir,
                    validate=False,  # validated once by read_model_description
                    model_description=self.model_description,
                    start_time=start_time,
                    stop_time=stop_time,
                    output_interval=output_interval,
                    start_values=dict(start_values or {}),
                    output=list(outputs),
                    debug_logging=True,
                    logger=logger,
                    step_finished=step_finished,
                    **fmpy_options,
                )
        except Exception as error:
            partial = recorders[0].result() if recorders else None
            raise FmuRunError(f"{error} -- FMU says: {_summarise(messages)}", partial_result=partial) from error
        # fmpy ends a run quietly when doStep returns fmi2Discard: turn that into an error.
        end = float(result["time"][-1]) if len(result) else start_time
        if end < stop_time and not np.isclose(end, stop_time, rtol=1e-12, atol=1e-12):
            raise FmuRunError(
                f"the FMU stopped at t = {end:g} s before stop_time = {stop_time:g} s -- "
                f"FMU says: {_summarise(messages)}",
                partial_result=result,
            )
        return result


@contextlib.contextmanager
def _fmu_errors_to_log_only() -> Iterator[None]:
    """While the runner collects the FMU's log, the FMU does not also print its errors to stderr.

    The runner turns every logged error into :class:`FmuRunError`, so a failure still reaches the
    user, in the words of the scenario that expected it or not (``DOUBLE_PENDULUM_FMU_STDERR``,
    read by the adapter ``fmu_src/DoublePendulum.py``).
    """
    previous = os.environ.get(FMU_STDERR_SWITCH)
    os.environ[FMU_STDERR_SWITCH] = "0"
    try:
        yield
    finally:
        if previous is None:
            os.environ.pop(FMU_STDERR_SWITCH, None)
        else:
            os.environ[FMU_STDERR_SWITCH] = previous


def _summarise(messages: list[str]) -> str:
    """Join the FMU's error messages, keeping the last line of each (the exception itself)."""
    return "; ".join(m.strip().split("\n")[-1] for m in messages) or "no message logged"


def simulate_fmu_file(
    fmu_path: str | Path, start_values: Mapping[str, Any] | None = None, **options: Any
) -> np.ndarray:
    """One-shot convenience: extract, simulate, clean up."""
    with FmuRunner(fmu_path) as runner:
        return runner.simulate(start_values, **options)
