"""Scenario scripts: each module runs the FMU through fmpy and writes CSV, plots and a summary.

A scenario module has ``DESCRIPTION`` (one line) and ``run(runner, out_dir, *, quick=False) ->
dict`` (the summary, also written to ``out_dir/summary.json``). ``quick`` shortens the run for
smoke tests. Each scenario enables only the model parts it needs.
"""

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
    "cosimulation": 19.6,
    "free_swing": 2.1,
    "friction_budget": 5.2,
    "energy_decay": 1.1,
    "loss_identification": 62.0,
    "suspension_transfer": 54.6,
    "measured_vs_sim": 24.0,
    "work_precision": 47.1,
    "stability": 15.3,
    "chaos": 63.0,
    "base_excitation": 45.0,
}
"""CPU time [s] of each scenario's default run, as last measured (first run of ``run all`` on a fresh clone,
2 cores, one worker process each, 2026-12-02, after the faster driven component and solvers; loss_identification
measured again after it came to fit eight models from eleven starts: 83 s under another job's load, which made the
others 1.3 to 1.4 times their entries here, so about 62 s on the quiet machine): ``run all``
starts the longest first, packs the small ones into shared children and weights its progress bar by them;
nothing else depends on them."""

EXPECTED_QUICK_CPU_S: dict[str, float] = {
    "cosimulation": 5.2,
    "free_swing": 2.2,
    "friction_budget": 1.7,
    "energy_decay": 1.6,
    "loss_identification": 7.0,
    "suspension_transfer": 13.2,
    "measured_vs_sim": 5.8,
    "work_precision": 0.9,
    "stability": 4.0,
    "chaos": 8.7,
    "base_excitation": 5.3,
}
"""CPU time [s] of each scenario's quick run (``--quick``), as last measured (2 cores, ``run all --quick``
on a fresh cache, mean of 6 runs, 2026-12-02; ``measured_vs_sim`` reading ``loss_identification``'s fit): ``run all
--quick`` shares the scenarios out among its processes by them and weights its progress bar by them;
nothing else depends on them. Measure again when a quick run gets cheaper or dearer."""

READS_FITS_OF: dict[str, str] = {"measured_vs_sim": "loss_identification"}
"""Scenarios that read a fit another scenario caches on disk, by the name of that one: ``measured_vs_sim`` reads
``loss_identification``'s air+drag fit of the same mode (on a cold cache, without it, it fits it itself: about 7 s
more CPU in a quick run). ``run all --quick`` runs each in the process of the one it reads from, after it
(:func:`double_pendulum.runs.pool.balanced_groups`); :data:`SCENARIOS` lists each after it too."""
