"""Scenario scripts: each module runs the FMU through fmpy and writes CSV, plots and a summary.

A scenario module has ``DESCRIPTION`` (one line) and ``run(runner, out_dir, *, quick=False) ->
dict`` (the summary, also written to ``out_dir/summary.json``). ``quick`` shortens the run for
smoke tests. Each scenario enables only the model parts it needs.

This package's own module holds what the command line needs to know of them without importing them: their
names (:data:`SCENARIOS`), their costs for ``run all`` (:data:`EXPECTED_CPU_S`, :data:`EXPECTED_QUICK_CPU_S`,
:data:`READS_FITS_OF`) and what the run's page shows of each (:data:`PAGES`, in :data:`READING_ORDER`).
"""

from double_pendulum.runs.page import Headline, ScenarioPage
from double_pendulum.runs.player import Animation, Drawn

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
    "free_swing": 4.0,
    "friction_budget": 5.2,
    "energy_decay": 1.1,
    "loss_identification": 62.0,
    "suspension_transfer": 54.6,
    "measured_vs_sim": 28.0,
    "work_precision": 47.1,
    "stability": 15.3,
    "chaos": 63.0,
    "base_excitation": 45.0,
}
"""CPU time [s] of each scenario's default run, as last measured (first run of ``run all`` on a fresh clone,
2 cores, one worker process each, 2026-12-02, after the faster driven component and solvers; loss_identification
measured again after it came to fit eight models from eleven starts: 83 s under another job's load, which made the
others 1.3 to 1.4 times their entries here, so about 62 s on the quiet machine; free_swing measured again with its
third run and its animation: 5.0 s beside other jobs; measured_vs_sim measured again after it came to run the main start
under the four other supported loss models: 28.5 s on a fresh clone, 2026-12-03): ``run all``
starts the longest first, packs the small ones into shared children and weights its progress bar by them;
nothing else depends on them."""

EXPECTED_QUICK_CPU_S: dict[str, float] = {
    "cosimulation": 2.1,
    "free_swing": 1.4,
    "friction_budget": 0.5,
    "energy_decay": 0.9,
    "loss_identification": 3.7,
    "suspension_transfer": 5.0,
    "measured_vs_sim": 3.7,
    "work_precision": 0.2,
    "stability": 1.2,
    "chaos": 3.3,
    "base_excitation": 1.6,
}
"""CPU time [s] of each scenario's quick run (``--quick``), as last measured (2 cores, ``run all --quick``
on a fresh cache, mean of 4 runs, quiet machine, 2026-12-06; ``measured_vs_sim`` reading ``loss_identification``'s
fit; the runs of 2026-12-02 took 1.5 to 3.3 times as long on a slower day and before the faster scenes): ``run all
--quick`` shares the scenarios out among its processes by them and weights its progress bar by them;
nothing else depends on them. Measure again when a quick run gets cheaper or dearer."""

READS_FITS_OF: dict[str, str] = {"measured_vs_sim": "loss_identification"}
"""Scenarios that read a fit another scenario caches on disk, by the name of that one: ``measured_vs_sim`` reads
``loss_identification``'s air+drag fit of the same mode (on a cold cache, without it, it fits it itself: about 7 s
more CPU in a quick run). ``run all --quick`` runs each in the process of the one it reads from, after it
(:func:`double_pendulum.runs.pool.balanced_groups`); :data:`SCENARIOS` lists each after it too."""


READING_ORDER: tuple[str, ...] = (
    "measured_vs_sim",
    "free_swing",
    "chaos",
    "energy_decay",
    "loss_identification",
    "friction_budget",
    "suspension_transfer",
    "base_excitation",
    "cosimulation",
    "work_precision",
    "stability",
)
"""The order of the scenarios on the run's page (``index.html``): the pendulum against its measurement first,
then chaos, the losses, the driven and coupled pendulum, the solvers."""

HEADLINES: dict[str, tuple[Headline, ...]] = {
    "measured_vs_sim": (
        Headline("lower bob within 5 cm of the track (smoothed over 0.25 s), start and camera geometry fitted, with "
                 "each of the loss models the measured energy supports equally: for", "loss_model_sensitivity/"
                 "smoothed_5cm_claim", note="loss_model_sensitivity/statement"),
        Headline("the same, frame by frame: within 5 cm for", "loss_model_sensitivity/raw_5cm_claim"),
        Headline("started as the seed started (the state reconstructed at t0, no friction): within 5 cm for",
                 "horizons_smoothed_s/seed_start_frictionless/lower_bob_5cm_s", unit="s",
                 resolution="smoothing/window_s"),
        Headline("the motion at the measured energy", "regime/verdict"),
        Headline("the same horizon with every uncertain input drawn at once (rods, l1, losses, start, geometry): "
                 "16-84 % of the runs", "horizon_budget/distribution/range_16_84_claim",
                 note="horizon_budget/statement"),
        Headline("the uncertain input that moves it most", "horizon_budget/dominant_input"),
    ),
    "free_swing": (
        Headline("two chaotic starts 1e-5 rad apart: lower bobs 1 cm apart after",
                 "twin_starts/lower_bobs_1cm_apart_at_s", unit="s"),
        Headline("turns of the lower rod from the chaotic start", "runs/chaotic/flips_rod2"),
        Headline("largest relative change of the energy, chaotic start (no friction: should be 0)",
                 "runs/chaotic/max_relative_energy_drift"),
    ),
    "chaos": (
        Headline("largest Lyapunov exponent (a small difference grows e-fold every 1/lambda)",
                 "lyapunov/lyapunov_per_s", "lyapunov/lyapunov_sem_per_s", "1/s"),
        Headline("three releases within 5 mm: lower bobs 1 cm apart after", "fmu_runs/releases_part_by_1cm_at_s",
                 unit="s"),
        Headline("releases within 5 mm: their spread exceeds 1 cm after", "predictability/horizon_1cm_at_5mm_s",
                 unit="s"),
        Headline("start angles from which a rod turns over (flip map)", "flip_map/fraction_flipped*100", unit="%"),
    ),
    "energy_decay": (
        Headline("decay rate b of the measured energy, E = a exp(b t) (statistical error)", "b_per_s",
                 "error_budget/b_statement/statistical_per_s", "1/s"),
        Headline("largest shift of b by the choice of weights, window or energy (a range, apart)",
                 "error_budget/b_statement/systematic_max_shift_per_s", unit="1/s"),
        Headline("the decay's exponent p, dE/dt ~ -E^p (1: exponential; 1/2: a constant friction torque), AR(1) noise",
                 "tilt/tilted/exponent/p", "tilt/tilted/exponent/p_stderr"),
        Headline("energy a at the release", "a_J", "error_budget/total_a_J", "J"),
        Headline("the seed's decay rate", "seed/b_per_s", unit="1/s"),
    ),
    "loss_identification": (
        Headline("loss models that fit the measured energy about equally well (within delta AIC 2)",
                 "supported_models/n_models", note="supported_models/text"),
        Headline("air drag's share of the loss: the shares some model reaches within delta(-2 ln L) 4 of the best "
                 "fit (profile likelihood)", "air_share_profile/share_interval*100", unit="%"),
        Headline("a damped springy pivot as the main loss (the seed's explanation): its AIC above the best, at least",
                 "suspension_as_main_loss/delta_aic_at_best", note="suspension_as_main_loss/statement"),
    ),
    "friction_budget": (
        Headline("energy lost, all mechanisms on", "runs/all/lost_fraction*100", unit="%"),
        Headline("the suspension's share of the loss", "share_of_loss_all_on/suspension*100", unit="%"),
        Headline("air drag's share of the loss", "share_of_loss_all_on/air_drag*100", unit="%"),
        Headline("bearing friction's share of the loss", "share_of_loss_all_on/bearing_friction*100", unit="%"),
        Headline("decay rate, all mechanisms on", "decay_rate_b_per_s/all",
                 "runs/all/exponential_fit/b_per_s_stderr", "1/s"),
    ),
    "suspension_transfer": (
        Headline("suspension damping c fitted at the assumed k = 20000 N/m and M_s = 2 kg (conditional)",
                 "identified/c_N_s_per_m", "identified/c_stderr", "N s/m"),
        Headline("loss exponent p of the measured energy", "measured/decay_shape/p", "measured/decay_shape/p_stderr"),
        Headline("loss exponent p with that suspension", "refit/identified/p"),
    ),
    "base_excitation": (
        Headline("Kapitza: amplitude that holds the single pendulum upright at 50 rad/s",
                 "kapitza_threshold_amplitude_m*1000", "kapitza_threshold_uncertainty_m*1000", "mm"),
        Headline("Acheson: points of the stability map where simulation and theory agree",
                 "acheson_agreement_fraction*100", unit="%"),
        Headline("resonance peaks against the damped linear theory: largest relative error",
                 "resonance_max_abs_relative_error*100", unit="%"),
    ),
    "cosimulation": (
        Headline("plain exchange (Jacobi), regular start: order of the angle error in the macro step",
                 "order_angles/regular / default / jacobi", resolution=0.01),
        Headline("iterative master (states saved and restored), regular start: order",
                 "order_angles/regular / default / iterative", resolution=0.01),
        Headline("cheapest way to an angle error of 1e-4 rad, regular start",
                 "cheapest_to_1e-4_rad/regular / default/method"),
    ),
    "work_precision": (
        Headline("configurations run (solvers, tolerances, steps)", "configurations"),
        Headline("fastest to an error of 1e-6, regular case", "best_per_band/regular/max_error_le_1e-6/solver"),
        Headline("its CPU time", "best_per_band/regular/max_error_le_1e-6/cpu_time_s", unit="s", resolution=0.01),
    ),
    "stability": (
        Headline("hard cases run", "cases"),
        Headline("cases that met their pass criterion", "passed"),
    ),
}
"""The headline figures the run's page shows of each scenario: paths into its ``summary.json``
(:class:`~double_pendulum.runs.page.Headline`), the numbers as the scenario wrote them."""

FIGURES: dict[str, tuple[tuple[str, str], ...]] = {
    "measured_vs_sim": (
        ("measured_vs_sim.gif", "the camera's two markers and the FMU's pendulum overlaid, in real time"),
        ("lower_bob_paths.png", "the lower bob's measured and simulated paths in the x-y plane"),
        ("prediction_error.png", "how far the simulated lower bob is from the measured one, over time"),
        ("horizon_budget.png", "what moves the prediction horizon, and its range over every uncertain input"),
    ),
    "free_swing": (
        ("twin_starts.gif", "two chaotic starts a hair's breadth apart stay together, then part (real time)"),
        ("traces.png", "the paths of the bobs from the small and the large start"),
    ),
    "chaos": (
        ("release_traces.png", "three releases within the seed's 5 mm, as its photographs show them"),
        ("predictability.png", "how long the pendulum stays predictable, by the start's uncertainty"),
        ("flip_map.png", "the time until a rod first turns over, by the start angles"),
    ),
    "energy_decay": (("energy_decay.png", "the measured energy over time and the decay laws fitted to it"),),
    "loss_identification": (
        ("energy_fit.png", "the measured energy and the loss models fitted to it"),
        ("loss_shares.png", "each model's split of the loss among the mechanisms"),
    ),
    "friction_budget": (("energy_budget_stacked.png", "where the energy went, all mechanisms on"),),
    "suspension_transfer": (("decay_rate_map.png", "the decay rate over the suspension's stiffness and damping"),),
    "base_excitation": (
        ("kapitza_threshold.png", "Kapitza's pendulum: the shaking that holds it upright"),
        ("acheson_map.png", "Acheson's inverted double pendulum: where shaking holds it upright"),
    ),
    "cosimulation": (
        ("error_vs_macro_step.png", "the coupling error of each master against the macro step"),
        ("stability_map.png", "where plain exchange blows up"),
    ),
    "work_precision": (("work_precision_regular.png", "error against CPU time for every solver, regular case"),),
    "stability": (("worst_residuals.png", "the energy balance of the hardest passing cases"),),
}
"""The key figures and animations the run's page shows of each scenario (file name, caption), in order."""


CONCLUSIONS: dict[str, str] = {
    "measured_vs_sim": "Started from a state fitted to the camera's first frames, the simulated pendulum keeps its "
                       "lower bob within 5 cm of the measured one (smoothed) for {0}, with each loss model the "
                       "measured energy supports (in-sample); started from the state reconstructed at t0 without "
                       "friction, for {2}.",
    "chaos": "From a large start the motion is chaotic: a small difference grows e-fold at the rate of the largest "
             "Lyapunov exponent, {0}, and hand releases within 5 mm of each other spread beyond 1 cm after {2}.",
    "energy_decay": "The measured energy decays at the rate b = {0} of E = a exp(b t) (statistical error; the choice "
                    "of weights, window or energy shifts it by up to {1}), but not exactly exponentially: dE/dt ~ "
                    "-E^p with p = {2}.",
    "loss_identification": "Loss models that fit the measured energy within delta AIC 2 of the best: {0}; air drag's "
                           "share of the loss lies within {1} (profile likelihood), so the split of the loss is "
                           "measured only that far.",
    "base_excitation": "Shaking the pivot at 50 rad/s holds the single pendulum upright from an amplitude of {0} "
                       "(Kapitza), and the simulated resonance peaks are within {2} of the damped linear theory.",
    "cosimulation": "Split into two FMUs, plain exchange converges with order {0} in the macro step, the iterative "
                    "master with order {1}.",
    "work_precision": "The fastest way to an error of 1e-6 in the regular case is {1}.",
}
"""The run's conclusions at the top of its page: a sentence for each scenario that ran, ``{k}`` its k-th headline
figure of :data:`HEADLINES` as the table shows it; the first five of the scenarios that ran, in :data:`READING_ORDER`
(:class:`~double_pendulum.runs.page.ScenarioPage`'s ``conclusion``). No figure is written here."""

ANIMATIONS: dict[str, tuple[Animation, ...]] = {
    "measured_vs_sim": (Animation(
        "measured_vs_sim.gif", "measured (camera) and simulated (FMU) pendulum", time="t_since_t0",
        time_label="t - t0", drawn=(
            Drawn("camera", "k", "paths.csv", "_measured", links=False),
            Drawn("FMU", "C0", "paths.csv", "_simulated", pivot=("pivot_x_simulated", "pivot_y_simulated")))),),
    "free_swing": (Animation(
        "twin_starts.gif", "frictionless: two chaotic starts a hair apart",
        drawn=(Drawn("first start", "C0", "chaotic.csv"), Drawn("second start", "C3", "chaotic_nudged.csv"))),),
}
"""The players the run's page shows in place of these GIFs (each GIF only where scripts cannot run), drawn from the
CSV files the GIFs are drawn from
(:class:`~double_pendulum.runs.player.Animation`), with play, pause, step, speed and a time slider."""


OWN_RECORD_DESCRIPTIONS: dict[str, str] = {
    "energy_decay": "energy decay of your pendulum from your camera track {record}, decay models compared",
    "loss_identification": "loss mechanisms of your pendulum identified from its measured energy in {record} "
                           "(AIC/BIC, shares)",
    "measured_vs_sim": "FMU prediction of your camera track {record} from the end of its release: the start fitted "
                       "to your track, the losses to its energy",
}
"""The one line of a scenario that ran on a user's own record (``run --track``), in place of its description."""


def page(name: str, description: str, record: str = "") -> ScenarioPage:
    """What the run's page shows of scenario ``name`` (``description``: its one line; ``record``: the file name of a
    user's own track it analysed, "" for the seed's)."""
    if record and name in OWN_RECORD_DESCRIPTIONS:
        description = OWN_RECORD_DESCRIPTIONS[name].format(record=record)
    return ScenarioPage(name, description, HEADLINES.get(name, ()), FIGURES.get(name, ()),
                        conclusion=CONCLUSIONS.get(name, ""), animations=ANIMATIONS.get(name, ()))
