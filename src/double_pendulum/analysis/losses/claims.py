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
    models = {r["model"]: {"delta_aic": r["delta_aic"], "akaike_weight": r["akaike_weight"], "shares": r["shares"],
                           "b_sim_per_s": r.get("b_sim_per_s"), "p_sim": r.get("p_sim")}
              for r in rows if r["converged"] and r["delta_aic"] < daic}  # fmt: skip
    air = [m["shares"][AIR_LABEL] for m in models.values() if AIR_LABEL in m["shares"]]
    parts = "; ".join(f"{name} (delta AIC {m['delta_aic']:.2f}, weight {m['akaike_weight']:.2f}: "
                      + ", ".join(f"{k} {x:.0%}" for k, x in m["shares"].items()) + ")"
                      for name, m in models.items())  # fmt: skip
    text = (f"{len(models)} models lie within delta AIC {daic:g} of the lowest: {parts}. The energy record does "
            "not rank them, so none is the model and no split of the loss is measured: "
            + (f"the air-drag share ranges from {min(air):.0%} to {max(air):.0%} across them, depending on which "
               "second mechanism is assumed." if air else "none of them has air drag."))
    return {"daic": daic, "models": models, "air_share_range": [min(air), max(air)] if air else None, "text": text}


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
