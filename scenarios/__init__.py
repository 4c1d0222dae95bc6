"""Scenario scripts: each module runs the FMU through fmpy and writes CSV, plots and a summary.

A scenario module has ``DESCRIPTION`` (one line) and ``run(runner, out_dir, *, quick=False) ->
dict`` (the summary, also written to ``out_dir/summary.json``). ``quick`` shortens the run for
smoke tests. Each scenario enables only the model parts it needs.
"""

# ``cosimulation`` runs first: its engines (libcosim, fmpy's container FMU) failed to load the FMUs
# in a process that had already run the pythonfmu FMU through fmpy for other scenarios (libcosim:
# "The FMU contains no binary for this platform"; the container aborted). Run first, all pass.
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
