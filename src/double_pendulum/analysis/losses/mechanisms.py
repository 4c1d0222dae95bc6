"""The loss mechanisms (air drag, bearing friction, drag torques, viscous damping, a suspension), their
parameters with reference values and bounds, and the models that combine them (``air+drag``).

Units: energies J, times s, c_R 1, tau_b N m, b_v N m s/rad, c N s/m, the air factor 1 (multiplies
rho_air, i.e. all drag coefficients).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...model.parameters import AirDragParameters

OMEGA_REG = 0.01
"""Regularisation speed [rad/s] of the friction sign functions in every loss model."""
SIM_SETTINGS: dict[str, Any] = {"solver": "dop853", "rtol": 1e-6, "atol": 1e-8, "omega_reg": OMEGA_REG}
"""Integration tolerances: energy errors ~1e-6 J (chi2 changes by < 0.01 against 1e-8), far below
the effect of a 2 % parameter step (~1e-3 J)."""
QUICK_SIM_SETTINGS: dict[str, Any] = {**SIM_SETTINGS, "rtol": 1e-5, "atol": 1e-7}
"""Integration tolerances of the quick fit (a smoke run): energy errors ~1e-4 J, still a tenth of a 2 %
parameter step's effect, for 0.6 of the CPU per run. Converging at them would stall (Gauss-Newton ran out
of descent after 25 runs), but the quick fit takes one step (:data:`QUICK_RUN_BUDGET`), whose direction the
integration noise turns: chi2 609.3 to 610.1 in trials (air factor 1.5 to 1.7, tau_b 1.2 to 1.3 mN.m)
against 608.9 at the default settings' converged optimum, about one standard error away."""
DIFF_STEP = 0.02
"""Finite-difference step in x = theta / theta_ref: 2 % of a parameter's reference value."""
SUSPENSION_K = 2e4
"""Fixed spring stiffness [N/m] of the suspension mechanism (the parameter default)."""
SUSPENSION_M = 2.0
"""Fixed suspension mass [kg] of the suspension mechanism (the parameter default)."""
RHO_AIR = AirDragParameters().rho_air


@dataclass(frozen=True)
class Parameter:
    """A free loss parameter: name (as in the summary), unit, reference value (start), bounds."""

    name: str
    unit: str
    ref: float
    bounds: tuple[float, float]
    description: str
    warm_scan: tuple[float, ...] = ()
    """Values tried when the parameter joins a fitted model (:func:`warm_starts`) where its loss is not
    monotonic in it; empty: it joins at :data:`WARM_START_FRACTION` of ``ref``, a negligible loss."""
    start_from: str = ""
    """The parameter of a nested mechanism (:attr:`Mechanism.generalises`) whose fitted value it starts at."""


@dataclass(frozen=True)
class Mechanism:
    """A loss mechanism: its parameters, the FMU start values they give, the work output it books."""

    name: str
    label: str
    work: str
    parameters: tuple[Parameter, ...]
    values: Callable[[Sequence[float]], dict[str, Any]]
    generalises: str = ""
    """The mechanism this one contains as a special case (``drag2`` with equal torques is ``drag``): a model
    with it nests the model with that mechanism instead (:func:`contains`)."""


def _air(x: Sequence[float]) -> dict[str, Any]:
    return {"air_drag": True, "rod_drag": True, "rho_air": RHO_AIR * x[0]}


def _bearing(x: Sequence[float]) -> dict[str, Any]:
    return {"bearing_friction": True, "c_R1": x[0], "c_R2": x[0]}


def _viscous(x: Sequence[float]) -> dict[str, Any]:
    return {"bearing_friction": True, "c_R1": 0.0, "c_R2": 0.0, "b_v1": x[0], "b_v2": x[0]}


def _drag(x: Sequence[float]) -> dict[str, Any]:
    return {"bearing_drag": True, "tau_b1": x[0], "tau_b2": x[0]}


def _drag2(x: Sequence[float]) -> dict[str, Any]:
    return {"bearing_drag": True, "tau_b1": x[0], "tau_b2": x[1]}


def _suspension(x: Sequence[float]) -> dict[str, Any]:
    k, m = SUSPENSION_K, SUSPENSION_M
    return {"suspension": True, "k_x": k, "k_y": k, "c_x": x[0], "c_y": x[0], "M_s": m}


MECHANISMS: dict[str, Mechanism] = {
    m.name: m
    for m in (
        Mechanism("air", "air drag", "W_air", (Parameter("air_factor", "1", 1.5, (1e-3, 50.0),
                  "factor on the default drag of bobs and rods (rho_air x factor)"),), _air),
        Mechanism("bearing", "load-proportional bearing friction", "W_bearing",
                  (Parameter("c_R", "1", 1e-3, (1e-7, 1.0), "rolling friction coefficient, both joints"),), _bearing),
        Mechanism("viscous", "viscous joint damping", "W_bearing",
                  (Parameter("b_v", "N.m.s/rad", 1e-4, (1e-9, 1e-1), "viscous joint damping, both joints"),),
                  _viscous),
        Mechanism("drag", "bearing drag torque", "W_bearing_drag",
                  (Parameter("tau_b", "N.m", 1e-3, (1e-7, 1.0), "bearing drag torque, both joints"),), _drag),
        Mechanism("drag2", "bearing drag torque", "W_bearing_drag",
                  (Parameter("tau_b1", "N.m", 1e-3, (1e-7, 1.0), "bearing drag torque, pivot", start_from="tau_b"),
                   Parameter("tau_b2", "N.m", 1e-3, (1e-7, 1.0), "bearing drag torque, elbow", start_from="tau_b")),
                  _drag2, generalises="drag"),
        Mechanism("suspension", "damped suspension", "W_suspension",
                  (Parameter("c_suspension", "N.s/m", 20.0, (1e-2, 1e5),
                             f"suspension damping c_x = c_y at k = {SUSPENSION_K:g} N/m, M_s = {SUSPENSION_M:g} kg",
                             warm_scan=(3.0, 10.0, 30.0, 100.0, 300.0, 1000.0)),),
                  _suspension),
    )
}  # fmt: skip
"""The loss mechanisms a model combines (``drag2``: one drag torque per joint)."""

FULL_MODELS: tuple[str, ...] = (
    "air",
    "drag",
    "viscous",
    "bearing",
    "air+drag",
    "air+bearing",
    "air+viscous",
    "air+suspension",
)
"""Models of the default identification: mechanisms joined by '+': each loss of the pendulum alone (air drag, the
drag torque, viscous joint damping, load-proportional friction), each bearing loss with air drag, and the
suspension with air drag."""
THOROUGH_MODELS: tuple[str, ...] = (
    *FULL_MODELS,
    "air+drag2",
    "air+drag+bearing",
    "air+drag+viscous",
    "air+drag+suspension",
)
"""Models of the thorough identification: the default ones, ``air+drag2`` (one drag torque per joint: it
generalises air+drag, whose optimum it contains, and ended within 0.05 of its chi2 with a flat valley, dAIC
2.0, in a sequential round of its own) and the three-mechanism models (each the best model plus a third
loss; in the last default run two of them ended at their parent's optimum and the suspension one above
it, at about 90 s of CPU together)."""
QUICK_MODELS: tuple[str, ...] = ("air+drag",)
"""Models of the quick identification (a smoke run: the best model alone, no comparison)."""
QUICK_RUN_BUDGET = 6
"""Runs of each quick fit (:func:`fit_models` with ``max_runs``; the default and thorough fits: up to 30): the
residuals at the references, their Jacobian, one Gauss-Newton step and the Jacobian there, so the fit stops
at ``"run limit"`` after one step. On the seed's record air+drag then ends at chi2 609.2 against 608.9 at its
converged optimum (9 runs, both at :data:`SIM_SETTINGS`), for two thirds of the CPU."""

def mechanisms_of(model: str) -> list[Mechanism]:
    """The mechanisms of a model name such as ``"air+drag"``."""
    return [MECHANISMS[name] for name in model.split("+")]


def contains(model: str, other: str) -> bool:
    """True if ``other`` is nested in ``model`` (and not the same): each of its mechanisms is one of
    ``model``'s or a special case of one (:attr:`Mechanism.generalises`)."""
    mine = {name for m in mechanisms_of(model) for name in (m.name, m.generalises) if name}
    return model != other and set(other.split("+")) <= mine and set(other.split("+")) != set(model.split("+"))


def model_rank(model: str) -> int:
    """Fitting round of a model: its mechanisms, a generalising one (``drag2``) counting twice, so every
    model it contains is fitted in an earlier round and can warm-start it."""
    return sum(2 if m.generalises else 1 for m in mechanisms_of(model))


def parameters_of(model: str) -> list[Parameter]:
    """The free parameters of a model, in order."""
    return [p for m in mechanisms_of(model) for p in m.parameters]


def model_values(model: str, theta: Sequence[float]) -> dict[str, Any]:
    """FMU start values of ``model`` at parameter values ``theta`` (in :func:`parameters_of` order)."""
    values: dict[str, Any] = {}
    i = 0
    for mech in mechanisms_of(model):
        n = len(mech.parameters)
        values.update(mech.values(theta[i : i + n]))
        i += n
    return values


def shares(result: np.ndarray, model: str) -> dict[str, float]:
    """Each mechanism's share of the dissipated work at the end of the run (W_i / sum W) by its label."""
    works = {m.label: float(result[m.work][-1]) for m in mechanisms_of(model)}
    total = sum(works.values())
    return {name: w / total for name, w in works.items()}


def model_title(model: str) -> str:
    """A model in words: its mechanisms' labels joined by " + " (``air+drag``: "air drag + bearing drag torque"),
    a single one "... alone"."""
    labels = [m.label + (" per joint" if m.name == "drag2" else "") for m in mechanisms_of(model)]  # not drag's
    return labels[0] + " alone" if len(labels) == 1 else " + ".join(labels)
