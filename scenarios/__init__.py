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
    "cosimulation": 50.0,
    "free_swing": 5.0,
    "friction_budget": 14.0,
    "energy_decay": 3.0,
    "loss_identification": 116.0,
    "suspension_transfer": 189.0,
    "measured_vs_sim": 18.0,
    "work_precision": 88.0,
    "stability": 31.0,
    "chaos": 283.0,
    "base_excitation": 59.0,
}
"""CPU time [s] of each scenario's default run, as last measured (first run, 2 cores, 2026-12-01): ``run
all`` starts the longest first and weights its progress bar by them; nothing else depends on them."""
