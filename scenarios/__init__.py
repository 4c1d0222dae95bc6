"""Scenario scripts: each module runs the FMU through fmpy and writes CSV, plots and a summary.

A scenario module has ``DESCRIPTION`` (one line) and ``run(runner, out_dir, *, quick=False) ->
dict`` (the summary, also written to ``out_dir/summary.json``). ``quick`` shortens the run for
smoke tests. Each scenario enables only the model parts it needs.
"""

# ``cosimulation`` runs first when scenarios share one process (``run all --jobs 1``): its engines
# (libcosim, fmpy's container FMU) failed to load the FMUs in a process that had already run the
# pythonfmu FMU through fmpy for other scenarios (libcosim: "The FMU contains no binary for this
# platform"; the container aborted). Run first, all pass; with child processes (the default) each
# scenario has a process of its own.
SCENARIOS: tuple[str, ...] = (
    "cosimulation",
    "free_swing",
    "friction_budget",
    "energy_decay",
    "loss_identification",
    "suspension_transfer",
    "measured_vs_sim",
    "work_precision",
    "stability",
    "chaos",
    "base_excitation",
)

EXPECTED_CPU_S: dict[str, float] = {
    "cosimulation": 67.0,
    "free_swing": 5.0,
    "friction_budget": 30.0,
    "energy_decay": 2.0,
    "loss_identification": 350.0,
    "suspension_transfer": 350.0,
    "measured_vs_sim": 80.0,
    "work_precision": 260.0,
    "stability": 130.0,
    "chaos": 300.0,
    "base_excitation": 55.0,
}
"""CPU time [s] of each scenario's default run, as last measured (first run, 2 cores): ``run all``
starts the longest first. Only the order depends on it."""
