"""The sizes of the ``chaos`` scenario's runs (quick, default, thorough) and what each headline figure is good
for at those sizes (:func:`precision`).

Cost: the parts are independent and run on parallel worker processes (one per core), the flip map
after them split over the same cores. The default run follows the frictionless exponents of 32
starts for 100 s and the damped one for 180 s (the exponent has fallen to about 0.1 by 150 s, as the
energy drops below the flip energy); ``thorough=True`` (``--thorough``) takes 64 starts, adds RK4's
own estimate at h and h / 2, and follows the damped exponent for 360 s, as the seed's energy falls to a
fifth. The summary's ``precision`` states what each headline figure is good for.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .lyapunov import Integration

H = 1e-3  # s, RK4 step of the ensembles, maps and sections
METHODS = {"dop853": Integration("dop853", rtol=1e-10, atol=1e-12),  # the high-accuracy estimate
           "rk4_h": Integration("rk4", h=H),
           "rk4_h_half": Integration("rk4", h=H / 2)}  # step halving
RK4_STEPS = {"rk4_h": "h", "rk4_h_half": "h / 2"}  # the RK4 integrations' steps, as the precision text names them


@dataclass(frozen=True)
class Plan:
    """Sizes of the runs (full or quick); times in s, uncertainties in m."""

    workers: int | None  # local processes for FMU sweeps and the flip map (None: all cores)
    fmu_stop: float
    sigmas: tuple[float, ...]
    members: int
    spread_t_end: float
    lyap_t_end: float
    lyap_members: int
    scan_thetas: tuple[float, ...]
    scan_t_end: float
    spectrum_t_end: float
    flip_n: int
    flip_t_max: float
    poincare_starts: int
    poincare_t_end: float
    friction_t_end: float
    friction_window: float
    rk4: tuple[str, ...] = ("rk4_h", "rk4_h_half")  # RK4's own estimates beside DOP853 (keys of METHODS; at h / 2
    # the most expensive integration, 200 000 steps per 100 s; without them the two-trajectory estimate checks RK4 at h)
    lyap_rtol: float = 1e-10  # DOP853 tolerance of the largest exponent (atol: 1e-2 of it)
    friction_rtol: float = 1e-8  # DOP853 tolerance of the damped exponent (rtol 1e-6 costs a third but is not
    # safe: in a trial its trajectory stayed chaotic to 200 s where rtol 1e-8 settled on a regular orbit by 110 s;
    # when it settles is itself a matter of chance: with the runtime's DOP853, not the batch one, by 150 s)

    def methods(self) -> dict[str, Integration]:
        """The integrations of the largest exponent in this plan (DOP853 at :attr:`lyap_rtol`)."""
        dop853 = dataclasses.replace(METHODS["dop853"], rtol=self.lyap_rtol, atol=self.lyap_rtol * 1e-2)
        return {"dop853": dop853, **{name: METHODS[name] for name in self.rk4}}


THOROUGH = Plan(
    workers=None, fmu_stop=30.0, sigmas=(1e-5, 3e-5, 1e-4, 3e-4, 1e-3, 3e-3, 5e-3, 1e-2), members=200,
    spread_t_end=15.0, lyap_t_end=100.0, lyap_members=63, scan_thetas=tuple(np.round(np.arange(0.5, 3.0001, 0.1), 2)),
    scan_t_end=100.0, spectrum_t_end=100.0, flip_n=200, flip_t_max=10.0, poincare_starts=12, poincare_t_end=100.0,
    friction_t_end=360.0, friction_window=20.0,
)
FULL = dataclasses.replace(THOROUGH, fmu_stop=20.0, friction_t_end=180.0, flip_n=120, scan_t_end=50.0,
                           poincare_t_end=50.0,
                           spectrum_t_end=50.0,
                           rk4=(), lyap_members=31, lyap_rtol=1e-8,
                           scan_thetas=tuple(np.round(np.arange(0.5, 3.0001, 0.2), 2)))
"""The default, about a quarter of :data:`THOROUGH`'s CPU time: the FMU runs
over 20 s (the releases part after about 1 s; 30 s in the thorough run), the damped exponent up to
180 s (it has fallen to about 0.1 by 150 s, where the energy drops below the flip energy; the thorough
run shows the later windows scattering about 0),
the flip map on 120 x 120 cells (3 degrees, 5 pixels a cell in the figure), the energy scan (every 0.2 rad, the
thorough run every 0.1 rad), the spectrum (its middle exponents vanish to about 1/T = 0.02 1/s) and the
Poincare sections over 50 s, the largest exponent from 32 starts
(standard error about 0.02 1/s, below the finite-time bias of about 0.05 1/s; 64 in the thorough run) by
DOP853 at rtol 1e-8 (half the CPU of 1e-10, the thorough run's: on the same 32 starts the two means
differ by 0.004 1/s), checked by the two-trajectory estimate, which integrates with RK4 at h = 1 ms as the
ensembles and maps do (1 % above DOP853's mean in the default run). RK4's own Benettin estimate at h
(2 % above DOP853 in the last default run that had it, within the finite-time scatter) and at h / 2 (as
much CPU as all the others; it agreed with both to 0.7 % in the thorough run) need --thorough."""
QUICK = Plan(
    workers=1, fmu_stop=2.5, sigmas=(1e-4, 1e-3, 5e-3), members=24, spread_t_end=3.0, lyap_t_end=2.0, lyap_members=7,
    scan_thetas=(0.5, 1.5, 2.5, 3.0), scan_t_end=2.0, spectrum_t_end=1.5, flip_n=16, flip_t_max=2.0,
    poincare_starts=3, poincare_t_end=2.0, friction_t_end=2.0, friction_window=1.0, friction_rtol=1e-6,
    lyap_rtol=1e-8, rk4=(),  # the default run's integrations
)
"""The quick run (a smoke run, in this process): every part and figure at small sizes. The FMU runs to 2.5 s
(past the FMU-batch check at 2 s; the drawn releases part by 1 cm at about 1 s), 24 releases per
uncertainty, the largest exponent of 8 starts over 2 s by the default run's integrations (DOP853 at rtol
1e-8, checked by the two-trajectory estimate), four
release angles of the energy scan, the spectrum over 1.5 s, Poincare sections of 3 starts over 2 s, the
flip map on 16 x 16 cells."""


def precision(plan: Plan, summary: dict) -> dict[str, str]:
    """What each headline figure is good for (the run's settings)."""
    lyap = summary["lyapunov"]
    return {
        "lyapunov_per_s": f"{lyap['lyapunov_per_s']:.3f} +- {lyap['lyapunov_sem_per_s']:.3f} 1/s: mean and standard "
        f"error of {plan.lyap_members + 1} finite-time estimates over {plan.lyap_t_end:g} s (the running mean still "
        "falls by about 0.05 1/s from 50 to 100 s: finite-time bias of the same order as the standard error); "
        + (f"RK4 at {' and '.join(RK4_STEPS[name] for name in plan.rk4)} and DOP853 compared" if plan.rk4 else
           "DOP853, checked by the two-trajectory estimate (RK4, h = 1 ms); RK4's Benettin estimate at h and h / 2 "
           "with --thorough"),
        "spectrum": f"final estimates after {plan.spectrum_t_end:g} s; the two middle exponents and lambda1 + lambda4 "
        f"vanish to within about 1/T = {1 / plan.spectrum_t_end:.2f} 1/s",
        "energy_scan": f"one finite-time estimate per angle over {plan.scan_t_end:g} s (scatter about 0.1-0.2 1/s "
        "in the chaotic range)",
        "with_friction": f"exponent per {plan.friction_window:g} s window up to {plan.friction_t_end:g} s "
        f"(single trajectory, the FMU runtime's DOP853 at rtol {plan.friction_rtol:g}, scatter about 0.1-0.3 1/s "
        "per window)",
        "predictability": f"horizons from {plan.members} releases per uncertainty; spread sampled every "
        f"{10 * H * 1e3:g} ms (horizons interpolated between samples)",
        "flip_map": f"{plan.flip_n} x {plan.flip_n} release angles (cells of {360 / plan.flip_n:.1f} degrees), RK4 "
        f"h = {H * 1e3:g} ms, flips up to {plan.flip_t_max:g} s",
    }
