"""Run the FMU in an independent FMI importer: libcosim (Open Simulation Platform) via libcosimpy.

libcosim loads the FMU with its own FMI library (FMI Library), so agreement with fmpy checks the
FMU itself, not one importer's behaviour. libcosim counts time in integer nanoseconds.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

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
