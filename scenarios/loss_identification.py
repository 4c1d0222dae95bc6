"""Scenario ``loss_identification``: which loss mechanisms drain the seed's pendulum (issue 12, item 3).

Fits the simulated energy of the seed's pendulum (rigid links, start state from the track) to the
measured energy (the track turned back by the camera's tilt against gravity,
:mod:`double_pendulum.analysis.track.tilt`) over the whole 21 s record for combinations of air drag (free factor),
load-proportional bearing friction, bearing drag torque, viscous joint damping and a damped
suspension, and compares them by AIC/BIC with the residuals' correlation accounted for
(:mod:`double_pendulum.analysis.losses.identification`). Outputs in ``results/loss_identification/``:

- ``energy.csv``: per fitted frame the measured energy, its error, the top model's simulated energy
  (FMU run) and its dissipated work per mechanism;
- ``energy_fit.png``, ``loss_shares.png``, ``out_of_sample.png`` and ``profiles.png`` (``--thorough`` only;
  ``out_of_sample.png`` also in the quick run: each model fitted to one half of the record, predicting the
  other, :mod:`double_pendulum.analysis.losses.holdout`);
- ``summary.json``: ``top_model`` (lowest AIC, not a verdict: ``supported_models`` lists every model within
  delta AIC 2), ``b_measured_per_s``, ``b_sim_per_s``, ``p_measured``,
  ``p_measured_stderr``, ``p_sim`` and ``top_model_shares`` (the top model's) and the model comparison;
  ``noise_model``: AIC and BIC from an AR(1) likelihood of each model's residuals beside those with the common
  factor F, and which models tie under each (:mod:`double_pendulum.analysis.losses.noise`); ``out_of_sample``:
  the half-record test's scores and rankings (``--thorough`` and ``--quick`` only: in the default run it
  would take 109 s to 203 s of wall time); ``air_share_profile``: air drag's share as a profile-likelihood
  interval (:mod:`double_pendulum.analysis.losses.air_profile`, not in the quick run); ``untilted_track``: the same
  comparison and profile on the untilted track (``--thorough`` only, about 50 s more CPU);
- ``report.md``.

Default: the one- and two-mechanism models but air+drag2
(:data:`~double_pendulum.analysis.losses.identification.FULL_MODELS`), about 45 s of CPU on one worker
process per core (the worker pool is started once for every fitting round). ``thorough``
(``--thorough``) adds air+drag2 (one drag torque per joint), the three-mechanism models
air+drag+bearing, air+drag+viscous and air+drag+suspension, with 30 runs for every fit, and the top
model's profile likelihood (about 2.5 min more CPU; in the last runs the added models ended at or above
their parent's optimum, so they change no figure of the default run, and the profile intervals matched
the curvature errors). ``quick``: air+drag alone in this process, one Gauss-Newton step (6 runs) at
rtol 1e-5, no comparison, no profile likelihood (a smoke run; the fit is the one ``measured_vs_sim``
reads from the cache).

With a user's own record (``--track FILE.csv --pendulum FILE.toml``, :mod:`double_pendulum.analysis.track.user_track`)
the same identification runs on it, without the seed's friction estimates, and the report is
:func:`~double_pendulum.analysis.losses.own_report.own_report_text`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from double_pendulum import plots
from double_pendulum.analysis.losses.claims import SUPPORTED_DAIC
from double_pendulum.analysis.losses.identification import identify_losses
from double_pendulum.analysis.losses.mechanisms import model_title, parameters_of
from double_pendulum.analysis.losses.own_report import own_report_text
from double_pendulum.analysis.losses.report import report_text
from double_pendulum.analysis.track.user_track import UserRecord
from double_pendulum.runs.results_io import table_from_columns, write_json, write_results_csv, write_text

DESCRIPTION = "loss mechanisms of the real pendulum identified from its measured energy (AIC/BIC, shares)"


def run(runner: Any, out_dir: Path, *, quick: bool = False, thorough: bool = False,
        record: UserRecord | None = None) -> dict:  # fmt: skip
    """Identify the losses of the seed's record, or of a user's ``record``
    (:mod:`double_pendulum.analysis.track.user_track`: no comparison with the seed), run the best model through the
    FMU and write CSV, plots, summary, report."""
    out_dir = Path(out_dir)
    ident = identify_losses(runner, quick=quick, thorough=thorough, record=record)
    s = ident.summary
    table = table_from_columns(t=ident.t, E_measured=ident.e_measured, sigma_E=ident.sigma,
                               E_simulated=ident.e_sim, **ident.works)  # fmt: skip
    units = {"t": "s", "E_measured": "J", "sigma_E": "J", "E_simulated": "J", **{w: "J" for w in ident.works}}
    write_results_csv(out_dir / "energy.csv", table, units)
    best = s["top_model"]
    tied = len(s["supported_models"]["models"]) if s["supported_models"] else 1
    label = model_title(best) + (f" (the lowest AIC of {tied} models that tie)" if tied > 1 else "")
    whose = {} if record is None else {"whose": f"the pendulum of {record.name}",
                                       "swing_frames": max(3, round(1.3 / record.track.track.dt))}  # fmt: skip
    plots.plot_energy_fit(ident.t, ident.e_measured, ident.sigma, ident.e_sim, label, out_dir / "energy_fit.png",
                          **whose)  # fmt: skip
    plots.plot_loss_shares(s["models"], out_dir / "loss_shares.png", supported_daic=SUPPORTED_DAIC)
    oos = s["out_of_sample"]
    if oos:
        plots.plot_out_of_sample(oos, {m: model_title(m) for m in oos["both_directions"]["order"]},
                                 out_dir / "out_of_sample.png")
    if s["profile_likelihood"]:
        labels = {p.name: f"{p.name}: {p.description} [{p.unit}]" for p in parameters_of(best)}
        plots.plot_profiles(s["profile_likelihood"], labels, out_dir / "profiles.png")
    write_json(out_dir / "summary.json", s)
    write_text(out_dir / "report.md", report_text(s) if record is None else own_report_text(s))
    return s
