"""What the loss identification supports: the models the energy record cannot tell apart, the range of the
air-drag share across them, the comparison of the fitted drag torque with the seed's rolling friction, and the
measurements that would separate the models (a proposal).

The fits themselves are :mod:`double_pendulum.analysis.losses.identification`'s; this module only reads its
comparison rows (one dict a model: ``delta_aic``, ``akaike_weight``, ``shares``, ``b_sim_per_s``, ``p_sim``,
``converged``) and states what they support.

* Models within :data:`SUPPORTED_DAIC` of the lowest AIC are supported about as well (Burnham and
  Anderson); none of them is "the" model, and a share of the loss is only as good as the pair of mechanisms
  assumed: :func:`supported_models` reports each with its Akaike weight, and the range of the air share.
* Every model that reaches the lowest chi2 band reproduces the measured decay rate b, because b is what the
  fit matches: agreement in b discriminates nothing (:func:`b_sim_range`).
* The seed's own estimate of the bearing loss is rolling friction, a force c_R F_N with c_R = 0.5e-3 to
  1e-3 (its section 4.2.4); as a torque at the bearing's friction radius r_b,
  :math:`\\tau_R = c_R\\, r_b\\, M g` [N m] at the pivot, which carries the whole weight M g
  (:func:`seed_rolling_friction`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from ...model.parameters import BearingParameters, PendulumParameters
from .mechanisms import model_title

SUPPORTED_DAIC = 2.0
"""Models within this AIC of the lowest are supported about as well by the data (Burnham & Anderson)."""
SEED_C_R = (0.5e-3, 1e-3)
"""The seed's rolling-friction coefficients of ball bearings (its section 4.2.4, from a table it cites)."""
AIR_LABEL = "air drag"
"""The air-drag entry of a model's ``shares``."""

SEPARATING_MEASUREMENTS = (
    "Proposal, not a result: the energy of one free swing cannot separate these models, since each of them "
    "reproduces b and the loss exponent p within their errors. Two measurements would: (1) an "
    "amplitude-resolved decay down to small energies (a long record, or many short releases from small "
    "angles), where the laws part most: a constant torque takes the same energy per swing at any amplitude "
    "(dE/dt ~ E^0.5), viscous damping E^1, air drag E^1.5; (2) a spin-down of each joint alone (the lower "
    "rod clamped, then the upper), which separates the pivot's two bearings from the elbow's one and a "
    "load-independent torque from a load-proportional one (repeat with added mass)."
)
PER_JOINT_MODEL = "air+drag2"
"""The model with one drag torque per joint (``tau_b1`` pivot, ``tau_b2`` elbow), fitted with ``--thorough``."""


def per_joint_text(rows: Sequence[Mapping[str, Any]]) -> str:
    """Why one drag torque serves both joints: the per-joint fit's result where it ran, else where it runs."""
    row = next((r for r in rows if r["model"] == PER_JOINT_MODEL), None)
    head = ("The pivot runs in two bearings and the elbow in one, yet the default models fit one torque to both "
            "joints. ")
    if row is None:
        return (head + f"A torque per joint ({PER_JOINT_MODEL}) is fitted with --thorough only: the energy sees the "
                "sum of the two joints' dissipation, so the split per joint is not expected to be identified (in "
                "the thorough runs so far it was not); a spin-down of each joint alone would measure it.")
    p = row["parameters"]
    return (head + f"The per-joint fit ({PER_JOINT_MODEL}, delta AIC {row['delta_aic']:.1f}) gives tau_b1 = "
            f"{1e3 * p['tau_b1']['value']:.2f} +- {1e3 * p['tau_b1']['stderr']:.2f} and tau_b2 = "
            f"{1e3 * p['tau_b2']['value']:.2f} +- {1e3 * p['tau_b2']['stderr']:.2f} mN.m: the energy sees the sum of "
            "the two joints' dissipation, not the split; a spin-down of each joint alone would measure it.")


def supported_models(rows: Sequence[Mapping[str, Any]], daic: float = SUPPORTED_DAIC) -> dict[str, Any]:
    """The converged models within ``daic`` of the lowest AIC (the top model included), with their Akaike
    weights, loss shares, b_sim [1/s] and p_sim; the range of the air-drag share across them (None where no
    model in the set has air drag) and a sentence saying the record does not rank them."""
    near = [r for r in rows if r["converged"] and r["delta_aic"] < daic]
    models = {r["model"]: {"delta_aic": r["delta_aic"], "akaike_weight": r["akaike_weight"], "shares": r["shares"],
                           "b_sim_per_s": r.get("b_sim_per_s"), "p_sim": r.get("p_sim")}
              for r in near if not r.get("reduces_to")}  # fmt: skip
    reduced = {r["model"]: r["reduces_to"] for r in near if r.get("reduces_to")}
    air = [m["shares"][AIR_LABEL] for m in models.values() if AIR_LABEL in m["shares"]]
    if air and any(AIR_LABEL not in m["shares"] for m in models.values()):
        air.append(0.0)  # a supported model without air drag
    parts = "; ".join(f"{model_title(name)} (delta AIC {m['delta_aic']:.2f}, weight {m['akaike_weight']:.2f}: "
                      + ", ".join(f"{k} {x:.0%}" for k, x in m["shares"].items()) + ")"
                      for name, m in models.items())  # fmt: skip
    same = "".join(f" {model_title(name)} fits no better than {model_title(other)}, which it contains (its extra "
                   "mechanism fitted to nothing), so it is no candidate of its own." for name, other in reduced.items())
    if len(models) == 1:  # a sentence of its own: "1 models lie within ...; the share ranges from 37% to 37%"
        text = (f"One model lies within delta AIC {daic:g} of the lowest, the lowest itself: {parts}.{same} "
                + (f"It puts air drag's share of the loss at {max(air):.0%}; that holds only among the candidates "
                   "fitted." if air else "It has no air drag."))
    else:
        text = (f"{len(models)} models lie within delta AIC {daic:g} of the lowest: {parts}.{same} The energy record "
                "does not rank them, so none is the model and no split of the loss is measured: "
                + (f"the air-drag share ranges from {min(air):.0%} to {max(air):.0%} across them, depending on which "
                   "mechanism is assumed beside it or instead of it." if air else "none of them has air drag."))
    return {"daic": daic, "models": models, "n_models": len(models), "reduced": reduced,
            "air_share_range": [min(air), max(air)] if air else None, "text": text}


def supported_from_factor(rows: Sequence[Mapping[str, Any]], factor: float, daic: float = SUPPORTED_DAIC,
                          largest: float = 10.0) -> dict[str, float | None]:
    """How the supported set depends on the residual-correlation factor F: for each converged model outside it,
    the smallest F (up to ``largest``) at which it would lie within ``daic`` of the lowest AIC, None if none does.

    AIC = chi2 / F + 2 k (:mod:`.fitting`): a larger F shrinks the chi2 differences against the parameter counts,
    so models with fewer parameters join. The F used (``factor``) is the record's one estimate
    (:func:`~double_pendulum.analysis.decay.fit.record_correlation_factor`); this says how far it is from changing
    the answer, e.g. against the factor of another model's residuals."""
    fitted = [(r["model"], r["chi2"], r["k"]) for r in rows if r["converged"]]
    grid = [factor * (largest / factor) ** (i / 400) for i in range(401)] if largest > factor else []
    out: dict[str, float | None] = {}
    for model, chi2, k in fitted:
        aic = {f: chi2 / f + 2 * k for f in grid}
        if chi2 / factor + 2 * k - min(c / factor + 2 * q for _, c, q in fitted) < daic:
            continue
        out[model] = next((f for f in grid if aic[f] - min(c / f + 2 * q for _, c, q in fitted) < daic), None)
    return out


def suspension_bound(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any] | None:
    """The suspension as the main loss, reported as a bound: the row of the model with air drag and the
    suspension if its optimum is its nested limit (:func:`~.comparison.bound_entry`): delta AIC at best, the
    limit model, where the fit stopped. None if no such model was fitted or it converged to a finite damping."""
    row = next((r for r in rows if r["model"] == "air+suspension"), None)
    if row is None or "delta_aic_at_best" not in row:
        return None
    return {"model": row["model"], "delta_aic_at_best": row["delta_aic_at_best"],
            "model_in_words": model_title(row["model"]), "limit_in_words": model_title(row["best_is_limit_model"]),
            "best_is_limit_model": row["best_is_limit_model"], "statement": row["bound"],
            "stopped_at": {n: p["value"] for n, p in row["parameters"].items()},
            "stopped_at_delta_aic": row["delta_aic"], "stopped_at_p_sim": row.get("p_sim")}  # fmt: skip


def seed_friction_coefficient(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """The load-proportional friction coefficient c_R [1] of each converged model that has it, against the seed's
    ball-bearing values (:data:`SEED_C_R`): the value and its ratio to each end of the seed's range."""
    return {r["model"]: {"c_R": r["parameters"]["c_R"]["value"],
                         "over_seed": [r["parameters"]["c_R"]["value"] / c for c in SEED_C_R]}
            for r in rows if r["converged"] and "c_R" in r["parameters"]}  # fmt: skip


def b_sim_range(rows: Sequence[Mapping[str, Any]]) -> list[float] | None:
    """The smallest and largest simulated decay rate b_sim [1/s] over the converged models (None: none has it)."""
    values = [r["b_sim_per_s"] for r in rows if r["converged"] and r.get("b_sim_per_s") is not None]
    return [min(values), max(values)] if values else None


def seed_rolling_friction(params: PendulumParameters, tau_b: float,
                          bearings: BearingParameters | None = None) -> dict[str, Any]:
    """The seed's rolling-friction estimate as a pivot torque, against the fitted drag torque ``tau_b`` [N m].

    :math:`\\tau_R = c_R r_b M g` [N m] for the seed's c_R range (:data:`SEED_C_R`), the model's friction radius
    ``r_b1`` [m] (a 608 bearing's bore: the seed does not name its bearings' type) and the pendulum's whole
    weight M g [N] (bobs and rods) on the pivot; the ratio ``tau_b / tau_R`` for each end of the range.
    """
    r_b = (bearings or BearingParameters()).r_b1
    weight = (params.m1 + params.m2 + params.m_rod1 + params.m_rod2) * params.g
    torques = [c * r_b * weight for c in SEED_C_R]
    return {"c_R": list(SEED_C_R), "r_b_m": r_b, "pivot_load_N": weight, "torque_N_m": torques,
            "fitted_tau_b_N_m": tau_b, "fitted_over_seed": [tau_b / t for t in torques]}
