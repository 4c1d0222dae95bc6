"""Run the FMU in an independent FMI importer: libcosim (Open Simulation Platform) via libcosimpy.

libcosim loads the FMU with its own FMI library (FMI Library), so agreement with fmpy checks the
FMU itself, not one importer's behaviour. libcosim counts time in integer nanoseconds.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..masters.coupling import PENDULUM_OUTPUTS, SUSPENSION_OUTPUTS, CouplingError, check_row, column_names

NANOSECONDS_PER_SECOND = 1_000_000_000


def simulate_with_libcosim(
    fmu_path: str | Path,
    start_values: Mapping[str, Any],
    outputs: Sequence[str],
    *,
    stop_time: float,
    step_size: float,
) -> dict[str, float]:
    """Run ``fmu_path`` in libcosim to ``stop_time`` [s] with ``step_size`` [s]; return the last outputs."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.WARNING)
    step_ns = round(step_size * NANOSECONDS_PER_SECOND)
    if step_ns <= 0:
        raise ValueError(f"invalid step_size = {step_size!r} s: libcosim needs at least 1 ns")
    execution = CosimExecution.from_step_size(step_size=step_ns)
    slave = CosimLocalSlave(fmu_path=str(fmu_path), instance_name="double_pendulum")
    index = execution.add_local_slave(local_slave=slave)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    variables = {v.name.decode(): v for v in execution.slave_variables(index)}
    for name, value in start_values.items():
        var = variables[name]
        if var.type == CosimVariableType.BOOLEAN.value:
            execution.boolean_initial_value(index, var.reference, bool(value))
        elif var.type == CosimVariableType.STRING.value:
            execution.string_initial_value(index, var.reference, str(value))
        else:
            execution.real_initial_value(index, var.reference, float(value))
    if not execution.simulate_until(target_time=round(stop_time * NANOSECONDS_PER_SECOND)):
        raise RuntimeError("libcosim: the simulation failed (see its log)")
    values = observer.last_real_values(index, [variables[n].reference for n in outputs])
    return dict(zip(outputs, values))


def simulate_ssp_with_libcosim(
    ssp_path: str | Path,
    *,
    stop_time: float,
    macro_step: float,
    pendulum_outputs: Sequence[str] = PENDULUM_OUTPUTS,
    suspension_outputs: Sequence[str] = SUSPENSION_OUTPUTS,
    energy_scale: float = 1.0,
) -> np.ndarray:
    """Run the SSP system (:mod:`double_pendulum.fmu.build.ssp`) in libcosim; return its rows at t = h, 2h, ...

    libcosim's fixed-step algorithm steps both FMUs side by side, reads their outputs and then
    sets the inputs (Jacobi, inputs held over the step; two more exchanges while initialising):
    :func:`~double_pendulum.fmu.masters.coupling.run_coupled` with ``scheme="jacobi"`` and
    ``initial_exchanges=2`` gives the same numbers. The columns are those of
    :func:`~double_pendulum.fmu.masters.coupling.run_coupled`; a run that blows up ends in
    :class:`~double_pendulum.fmu.masters.coupling.CouplingError` with the rows so far.
    """
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)
    step_ns = round(macro_step * NANOSECONDS_PER_SECOND)
    execution = CosimExecution.from_ssp_file(str(ssp_path), step_ns)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer=observer)
    reads = []
    for instance, names in (("DoublePendulum", pendulum_outputs), ("Suspension", suspension_outputs)):
        index = execution.slave_index_from_instance_name(instance)
        refs = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
        reads.append((index, [refs[n] for n in names]))
    names = column_names(pendulum_outputs, suspension_outputs)
    dtype = [("time", np.float64)] + [(n, np.float64) for n in names]

    def row(t: float) -> tuple[float, ...]:
        return (t, *(v for index, refs in reads for v in observer.last_real_values(index, refs)))

    n_steps = int(round(stop_time / macro_step))
    rows: list[tuple[float, ...]] = []  # libcosim initialises in its first step: no row at t = 0
    watch = "W_input" in names and "W_in" in names
    for n in range(n_steps):
        if not execution.step():
            raise CouplingError(f"libcosim, h = {macro_step:g} s: the step at t = {n * macro_step:.6g} s failed",
                                np.array(rows, dtype=dtype))
        rows.append(row((n + 1) * step_ns / NANOSECONDS_PER_SECOND))
        check_row(rows, dtype, "libcosim", macro_step, watch, energy_scale)
    return np.array(rows, dtype=dtype)


def simulate_container(
    container_fmu: str | Path,
    *,
    stop_time: float,
    macro_step: float,
    pendulum_outputs: Sequence[str] = PENDULUM_OUTPUTS,
    suspension_outputs: Sequence[str] = SUSPENSION_OUTPUTS,
    energy_scale: float = 1.0,
) -> np.ndarray:
    """Run the container FMU (:mod:`double_pendulum.fmu.build.container`) in fmpy; rows at t = 0, h, 2h, ...

    The container is an ordinary FMI 2.0 co-simulation FMU to fmpy (``FMU2Slave``); it is stepped
    with ``doStep(n h, h)``, ``macro_step`` [s] the container's fixed step (or a multiple of it).
    The columns are those of :func:`~double_pendulum.fmu.masters.coupling.run_coupled`; a failed step or
    a run that blows up ends in :class:`~double_pendulum.fmu.masters.coupling.CouplingError` with the
    rows so far.
    """
    import shutil

    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(container_fmu))
    refs = {v.name: v.valueReference for v in md.modelVariables}
    wanted = [refs[f"DoublePendulum.{n}"] for n in pendulum_outputs]
    wanted += [refs[f"Suspension.{n}"] for n in suspension_outputs]
    names = column_names(pendulum_outputs, suspension_outputs)
    dtype = [("time", np.float64)] + [(n, np.float64) for n in names]
    watch = "W_input" in names and "W_in" in names
    unzipdir = extract(str(container_fmu))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="PendulumOnSuspension")
    rows: list[tuple[float, ...]] = []
    try:
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        rows.append((0.0, *fmu.getReal(wanted)))
        for n in range(int(round(stop_time / macro_step))):
            try:
                fmu.doStep(currentCommunicationPoint=n * macro_step, communicationStepSize=macro_step)
            except Exception as error:
                raise CouplingError(f"container FMU, h = {macro_step:g} s: the step at t = {n * macro_step:.6g} s "
                                    f"failed: {error}", np.array(rows, dtype=dtype)) from error
            rows.append(((n + 1) * macro_step, *fmu.getReal(wanted)))
            check_row(rows, dtype, "container FMU", macro_step, watch, energy_scale)
        fmu.terminate()
    finally:
        fmu.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)
    return np.array(rows, dtype=dtype)
