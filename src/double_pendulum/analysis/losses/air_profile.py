r"""Air drag's share of the loss as a profile-likelihood interval, not a spread of best fits.

For each converged model with air drag beside another loss (:data:`AIR_MODELS`), the air factor is held at values
around its optimum, :math:`a = \hat a + k\,\sigma_a` (:data:`PROFILE_STEPS`, kept within its bounds), the other
loss re-fitted (and :math:`\kappa` profiled, :mod:`.fitting`), and the air share of the dissipated work read from
the run at that optimum. With the record's correlation factor F (:func:`.comparison.common_factor`),

.. math::

    \Delta(a) = \frac{\chi^2(a) - \chi^2_{best}}{F}

is :math:`\Delta(-2\ln L)` against the best fit of the record (the lowest chi2 of every converged model of the
comparison: a share is compatible with the data if some model reaches it within :data:`LEVEL` of the best fit).
A model whose own optimum lies beyond the level is not profiled (every share it reaches does too).
The share's interval is where :math:`\Delta \le` :data:`LEVEL` = 4 (about 95 % for one parameter), interpolated
linearly between the points; an end at the air factor's lower bound (no air) is the share there, an end beyond the
last point is None (a profile still below the level at the last of :data:`PROFILE_STEPS` gets the points of
:data:`EXTEND_STEPS` first). The union over the models, with share 0 if a model without air drag comes within the level,
is the share the record allows.

A model without air drag fits with share 0; BIC's preference for it over a model with air drag is the
:math:`\ln n_{eff}` penalty of one more parameter, no evidence against air drag: only :math:`\Delta > 4` for a
share is evidence against that share.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from .comparison import ProfileItem, inside_bounds, profile_point
from .fitting import FitProblem, ModelFit, fit_loss_model
from .mechanisms import parameters_of
from .noise import AIR_LABEL

AIR_MODELS: tuple[str, ...] = ("air+viscous", "air+bearing", "air+drag")
"""The models whose air share is profiled: air drag beside each bearing loss."""
PROFILE_STEPS: tuple[float, ...] = (-3.0, -2.0, -1.0, 1.0, 2.0, 3.0)
"""Profile points in standard errors (curvature, with F) of the air factor from its optimum."""
EXTEND_STEPS: tuple[float, ...] = (4.5, 6.0, 8.0, 11.0)
"""Further points above the optimum for a model whose profile is still below the level at the last of
:data:`PROFILE_STEPS` (a flat profile: the air factor barely determined)."""
LEVEL = 4.0
"""Delta(-2 ln L) of the interval's ends (about 95 % for one parameter)."""
PROFILE_RUNS = 12
"""Run budget of each profile point's fit (one free loss parameter: two or three Gauss-Newton steps)."""


AirPoint = ProfileItem
"""A profile point: the model, the air factor's index and held value, the warm start of the others (the profile
points of :mod:`.comparison`'s kind)."""


def air_point(item: AirPoint, problem: FitProblem) -> tuple[float, float]:
    """(chi2, air share) at a profile point, the other loss re-fitted (:func:`parallel_map` worker)."""
    fit = fit_loss_model(item.model, problem, fixed={item.index: item.value}, start=item.start,
                         max_nfev=PROFILE_RUNS)  # fmt: skip
    return fit.chi2, float(fit.extra["shares"].get(AIR_LABEL, 0.0))


def air_points(fits: Sequence[ModelFit], factor: float, models: Sequence[str] = AIR_MODELS,
               steps: Sequence[float] = PROFILE_STEPS) -> list[AirPoint]:  # fmt: skip
    """The profile points of every fit of ``models`` among ``fits`` at ``steps`` standard errors from the optimum
    (warm starts shifted along the covariance)."""
    items = []
    for fit in (f for f in fits if f.model in models):
        params = parameters_of(fit.model)
        i = [p.name for p in params].index("air_factor")
        cov = fit.cov(factor)
        s = math.sqrt(cov[i, i])
        values = sorted({inside_bounds(fit.theta[i] + k * s, params[i]) for k in steps} - {float(fit.theta[i])})
        items += [profile_point(fit, cov, i, value) for value in values]
    return items


def _crossing(points: Sequence[tuple[float, float, float]], k: int, side: int) -> float | None:
    """The share where Delta reaches LEVEL going from point k to ``side`` (points: air factor, share, Delta)."""
    j = k
    while 0 <= j + side < len(points):
        a, b = points[j], points[j + side]
        if a[2] <= LEVEL < b[2]:
            f = (LEVEL - a[2]) / (b[2] - a[2])
            return a[1] + f * (b[1] - a[1])
        j += side
    return points[j][1] if side < 0 and j == 0 and points[0][2] <= LEVEL and points[0][0] < 1e-2 else None


def air_share_intervals(fits: Sequence[ModelFit], rows: Sequence[Mapping[str, Any]], factor: float,
                        items: Sequence[AirPoint],
                        results: Sequence[tuple[float, float]]) -> dict[str, Any]:  # fmt: skip
    """Per model: the profile (air factor, share, Delta) and the share's interval where Delta <= LEVEL (module
    docstring); the union over the models; what BIC's verdict means."""
    best = min(r["chi2"] for r in rows if r["converged"])
    out: dict[str, Any] = {}
    for fit in (f for f in fits if f.model in AIR_MODELS):
        row = next(r for r in rows if r["model"] == fit.model)
        if not row["converged"]:
            continue
        if fit.model not in {it.model for it in items}:  # its own optimum beyond the level: not profiled
            out[fit.model] = {"delta_at_optimum": (fit.chi2 - best) / factor, "share_interval": None,
                              "share_at_optimum": float(fit.extra["shares"].get(AIR_LABEL, 0.0))}  # fmt: skip
            continue
        i = [p.name for p in parameters_of(fit.model)].index("air_factor")
        own = (float(fit.theta[i]), float(fit.extra["shares"].get(AIR_LABEL, 0.0)), fit.chi2)
        pts = sorted([own, *((it.value, s, c) for it, (c, s) in zip(items, results) if it.model == fit.model)])
        prof = [(a, s, (c - best) / factor) for a, s, c in pts]
        k = min(range(len(prof)), key=lambda j: prof[j][2])
        inside = prof[k][2] <= LEVEL
        out[fit.model] = {"air_factor": [p[0] for p in prof], "air_share": [p[1] for p in prof],
                          "delta_neg2_log_l": [p[2] for p in prof], "share_at_optimum": own[1],
                          "delta_at_optimum": (own[2] - best) / factor,
                          "share_interval": ([_crossing(prof, k, -1), _crossing(prof, k, 1)] if inside
                                             else None)}  # fmt: skip
    no_air = {r["model"]: (r["chi2"] - best) / factor for r in rows
              if r["converged"] and "air" not in r["model"].split("+")}  # fmt: skip
    ends = [m["share_interval"] for m in out.values() if m["share_interval"]]
    if any(d <= LEVEL for d in no_air.values()):  # a model without air drag within the level: share 0 allowed
        ends.append([0.0, 0.0])
    lows = [e[0] for e in ends]
    highs = [e[1] for e in ends]
    union = None
    if ends:
        union = [None if None in lows else min(lows), None if None in highs else max(highs)]
    return {"level": LEVEL, "models": out, "share_interval": union, "without_air_delta": no_air,
            "reference": "Delta(-2 ln L) = (chi2 - lowest chi2 of every converged model) / F",
            "bic_means": "BIC's preference for a model without air drag is the ln(n_eff) penalty of one more "
                         "parameter where adding air drag lowers chi2 / F by less than that: it says the record "
                         "does not need air drag, not that air drag is absent; only Delta > 4 for a share is "
                         "evidence against that share",
            "definitions": {"without_air_delta": "Delta(-2 ln L) of each converged model without air drag (share 0): "
                                                 "share 0 is in the union if one is within the level",
                            "share_interval": "air drag's share of the dissipated work where Delta <= 4 (None at an "
                                              "end: beyond the profiled points; the whole entry None: the model "
                                              "never comes within 4 of the best fit)"}}  # fmt: skip


def air_share_text(profile: Mapping[str, Any] | None, untilted: Mapping[str, Any] | None = None) -> str:
    """The air share's profile interval in words (and the untilted track's, if given); "" if not profiled."""
    if not profile:
        return ""

    def interval(p: Mapping[str, Any]) -> str:
        u = p["share_interval"]
        if u is None:
            return "no share comes within the level"
        lo, hi = (f"{v:.0%}" if v is not None else "beyond the profiled points" for v in u)
        return f"{lo} to {hi}"

    text = (f"Air drag's share of the loss, as a profile-likelihood interval (shares some model reaches within "
            f"Delta(-2 ln L) <= {profile['level']:g} of the best fit of the record): {interval(profile)}. "
            + "; ".join(f"{m}: {interval(d)} (its own optimum {d['delta_at_optimum']:.1f} from the best)"
                        for m, d in profile["models"].items()) + ".")  # fmt: skip
    if untilted and untilted.get("air_share_profile"):
        text += f" On the untilted track: {interval(untilted['air_share_profile'])}."
    return text + (" BIC's preference for a model without air drag, where it has one, is the penalty for one more "
                   "fitted number, not evidence against air drag: only a share outside this interval is excluded.")
