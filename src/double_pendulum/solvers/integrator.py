"""A persistent integrator: step control and dense output around any method of this package.

The integrator takes its own steps (adaptive: the step-size controller below; fixed: the grid
``t0 + n * fixed_step``) and answers ``advance_to(t)`` by interpolating the last step with the
method's continuous extension. The sequence of steps therefore does not depend on the times at
which results are requested: an FMU communication step of 1 ms or 50 ms sees the same
trajectory, up to the interpolation error, and the integrator's state (including its step size)
carries over from one ``doStep`` to the next.

Step-size control (Hairer, Norsett, Wanner I, II.4): a step is accepted when the scaled error
norm ``err <= 1``; the next step is ``h * min(10, max(0.2, 0.9 * err^(-1/(q+1))))`` with ``q`` the
order of the error estimate, never growing right after a rejection.

A jump of the right-hand side (an FMU input changing at a communication point) is handled by
:meth:`Integrator.restart`: the last step and its dense output are forgotten, the integration
goes on from the given state with the new right-hand side and the current step size.

**Short landing steps.** After such a jump the integrator must land on the next communication
point (:meth:`Integrator.advance_to` with ``land=True``). When that point lies within the
controller's next step, the step is short for the method (a 1 ms communication step against
DOP853's 10 ms or so), and a method of lower order meets the same tolerance with fewer stages.
A method may name such a ``landing_method`` (DOP853: the Dormand-Prince 5(4) pair, 7 evaluations
instead of 12): the short step ``H`` is tried with it and accepted if its own error estimate meets
``rtol``/``atol`` per unit step, ``err <= H / h`` with ``h`` the controller's step (so landing steps
add no more error per second than the method's own steps would); otherwise it is taken with the
method itself, and the landing method rests for the next :data:`LANDING_REST` short steps. The
controller's step size is left as the method's own.
"""

from __future__ import annotations

import math
from typing import Any

from .method import Method, VectorField

SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
DEFAULT_MAX_STEPS_PER_CALL = 1_000_000
# A step landing on a stop time may be stretched by this factor rather than leave a sliver.
LANDING_SLACK = 1.01
# Short landing steps the landing method skips after its error estimate failed once.
LANDING_REST = 16


class SolverError(RuntimeError):
    """The integration could not continue (step size underflow, non-finite state, step budget)."""


def _all_finite(values: list[float]) -> bool:
    """True if every value is finite (a NaN or infinity anywhere makes the sum non-finite; a sum that
    overflows from finite values, beyond 1e308, is taken as blown up too)."""
    return math.isfinite(sum(values))


class Integrator:
    """Integrate ``dy/dt = f(t, y)`` forward from ``(t0, y0)`` with ``method``.

    ``rtol``/``atol`` [state units] control adaptive methods, ``fixed_step`` [s] fixed-step ones.
    Counters: ``n_steps`` (accepted), ``n_rejected``, ``nfev`` (right-hand side evaluations).
    """

    def __init__(
        self,
        f: VectorField,
        t0: float,
        y0: list[float],
        method: Method,
        *,
        rtol: float = 1e-9,
        atol: float = 1e-12,
        fixed_step: float = 1e-3,
        max_step: float = math.inf,
        max_steps_per_call: int = DEFAULT_MAX_STEPS_PER_CALL,
    ) -> None:
        y0 = [float(v) for v in y0]
        if not _all_finite(y0):
            raise SolverError(f"non-finite initial state {y0}")
        self.f = f
        self.method = method
        self.rtol = rtol
        self.atol = atol
        self.fixed_step = fixed_step
        self.max_step = max_step
        self.max_steps_per_call = max_steps_per_call
        self.t0 = float(t0)
        self.t = self.t0
        self.y = y0
        self.fy = f(self.t, y0)
        self.nfev = 1
        self.n_steps = 0
        self.n_rejected = 0
        self.grid_start = 0  # n_steps at the origin t0 of the fixed-step grid
        # The last accepted step [t_prev, t], kept for dense output.
        self.t_prev = self.t
        self.y_prev = list(y0)
        self.fy_prev = list(self.fy)
        self.stages: list[list[float]] = []
        self._interp = None
        self.landing_method = method.landing_method
        self.last_method = method  # the method of the last step (its dense output)
        self.landing_rest = 0
        if method.adaptive:
            self.h = self._initial_step()
        else:
            self.h = fixed_step

    # ------------------------------------------------------------------ stepping
    def _initial_step(self) -> float:
        """Hairer's starting step estimate (Solving ODEs I, II.4, algorithm on p. 169)."""
        f, t, y, fy = self.f, self.t, self.y, self.fy
        scale = [self.atol + self.rtol * abs(v) for v in y]
        d0 = math.sqrt(sum((v / s) ** 2 for v, s in zip(y, scale)) / len(y))
        d1 = math.sqrt(sum((v / s) ** 2 for v, s in zip(fy, scale)) / len(y))
        h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
        h0 = min(h0, self.max_step)
        y1 = [v + h0 * d for v, d in zip(y, fy)]
        f1 = f(t + h0, y1)
        self.nfev += 1
        d2 = math.sqrt(sum(((a - b) / s) ** 2 for a, b, s in zip(f1, fy, scale)) / len(y)) / h0
        if d1 <= 1e-15 and d2 <= 1e-15:
            h1 = max(1e-6, h0 * 1e-3)
        else:
            h1 = (0.01 / max(d1, d2)) ** (1.0 / (self.method.error_order + 1))
        return min(100.0 * h0, h1, self.max_step)

    def _accept(self, h: float, y_new: list[float], f_new: list[float], stages: list[list[float]]) -> None:
        self.t_prev, self.y_prev, self.fy_prev = self.t, self.y, self.fy
        self.stages = stages
        self._interp = None
        self.last_method = self.method
        self.y, self.fy = y_new, f_new
        self.n_steps += 1

    def _short_landing(self, t_stop: float) -> bool:
        """Try to reach ``t_stop`` [s] in one step of the landing method; True if accepted.

        Only for a stop within the controller's next step (see the module docstring); the step size
        ``self.h`` stays the method's own.
        """
        method, h = self.landing_method, t_stop - self.t
        if method is None or h > self.h or h <= 0.0:
            return False
        if self.landing_rest > 0:
            self.landing_rest -= 1
            return False
        self._complete_fy()
        y_new, f_new, stages = method.step(self.f, self.t, self.y, self.fy, h)
        self.nfev += method.evals_per_step
        # error per unit step: no more error per second than the method's own steps of self.h would make
        if not (method.error_norm(self.y, y_new, stages, h, self.rtol, self.atol) <= h / self.h and _all_finite(y_new)):
            self.n_rejected += 1
            self.landing_rest = LANDING_REST
            return False
        self._accept(h, y_new, f_new, stages)
        self.last_method = method
        self.t = t_stop
        return True

    def _fixed_step(self) -> None:
        n = self.n_steps - self.grid_start + 1
        t_new = self.t0 + n * self.fixed_step
        h = t_new - self.t
        y_new, f_new, stages = self.method.step(self.f, self.t, self.y, self.fy, h)
        self.nfev += self.method.evals_per_step
        if not _all_finite(y_new):
            raise SolverError(
                f"{self.method.name}: state became non-finite at t = {t_new:.6g} s "
                f"(fixed_step = {self.fixed_step:g} s is too large for this motion)"
            )
        self._accept(h, y_new, f_new, stages)
        self.t = t_new

    def _adaptive_step(self, t_stop: float | None = None) -> None:
        """Take one accepted adaptive step; with ``t_stop`` [s] never step past it.

        A step that would reach within :data:`LANDING_SLACK` of ``t_stop`` is stretched or clipped
        to end exactly there (``self.t = t_stop``, no rounding of ``t + h``), so no sliver is left.
        """
        method = self.method
        exponent = -1.0 / (method.error_order + 1)
        h = min(self.h, self.max_step)
        rejected = False
        while True:
            landing = t_stop is not None and t_stop - self.t <= LANDING_SLACK * h
            if landing:
                h = t_stop - self.t
            h_min = 16.0 * math.ulp(max(abs(self.t), 1.0))
            if h < h_min:
                raise SolverError(
                    f"{method.name}: step size underflow (h = {h:.3g} s) at t = {self.t:.6g} s; "
                    "the problem may be stiff or the state has blown up"
                )
            if landing and method.deferrable_f_new:
                # f(t_stop, y_new) waits until needed: a restart at t_stop replaces it (FSAL saved)
                y_new, f_new, stages = method.step(self.f, self.t, self.y, self.fy, h, with_f_new=False)
                self.nfev += method.evals_per_step - 1
            else:
                y_new, f_new, stages = method.step(self.f, self.t, self.y, self.fy, h)
                self.nfev += method.evals_per_step
            err = method.error_norm(self.y, y_new, stages, h, self.rtol, self.atol)
            if err <= 1.0 and _all_finite(y_new) and (f_new is None or _all_finite(f_new)):
                factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err**exponent)
                if rejected:
                    factor = min(1.0, factor)
                self._accept(h, y_new, f_new, stages)
                self.t = t_stop if landing else self.t + h
                self.h = h * factor
                return
            self.n_rejected += 1
            rejected = True
            if math.isfinite(err):
                h *= max(MIN_FACTOR, SAFETY * err**exponent)
            else:
                h *= MIN_FACTOR

    def _complete_fy(self) -> None:
        """Evaluate a deferred ``fy = f(t, y)`` of a landed step and append it to its stages."""
        if self.fy is None:
            self.fy = self.f(self.t, self.y)
            self.nfev += 1
            self.stages.append(self.fy)

    def step(self, t_stop: float | None = None) -> None:
        """Take one accepted step (adaptive methods: ending at ``t_stop`` [s] at the latest)."""
        self._complete_fy()
        if self.method.adaptive:
            self._adaptive_step(t_stop)
        else:
            self._fixed_step()

    def restart(self, t: float, y: list[float], f: VectorField | None = None) -> None:
        """Go on from ``(t, y)`` with right-hand side ``f`` (default: the current one).

        For a discontinuity at ``t``: the last step, its stages and dense output are dropped, so
        nothing computed with the old right-hand side is reused beyond ``t``; ``f(t, y)`` is
        evaluated anew. The step size (adaptive) and the counters carry over; the fixed-step grid
        restarts at ``t``.
        """
        y = list(map(float, y))
        if not _all_finite(y):
            raise SolverError(f"non-finite state {y} at t = {t:.6g} s")
        if f is not None:
            self.f = f
        self.t0 = self.t = self.t_prev = float(t)
        self.y = self.y_prev = y  # states and derivatives are never changed in place
        self.fy = self.fy_prev = self.f(self.t, y)
        self.nfev += 1
        self.stages = []
        self._interp = None
        self.last_method = self.method
        self.grid_start = self.n_steps

    # ------------------------------------------------------------------ output
    def advance_to(self, t_out: float, land: bool = False) -> list[float]:
        """Integrate until ``t >= t_out`` and return the state at ``t_out`` (dense output).

        ``land=True`` (adaptive methods): the last step ends exactly at ``t_out``, so the state
        needs no dense output. Cheaper when the integration restarts at ``t_out`` anyway (an
        input jump): a step past it would be thrown away, and the interpolant costs right-hand
        side evaluations (DOP853: 3). Otherwise stepping past ``t_out`` keeps the step sequence
        independent of the communication points.
        """
        if self.t_prev < t_out < self.t and self._interp is not None:  # within the last step (as state_at)
            return self._interp((t_out - self.t_prev) / (self.t - self.t_prev))
        if t_out < self.t_prev:
            raise SolverError(f"cannot return to t = {t_out:.9g} s: the integrator is at t = {self.t:.9g} s")
        if land and self.t < t_out and self._short_landing(t_out):
            return list(self.y)
        budget = self.max_steps_per_call
        while self.t < t_out:
            if budget == 0:
                raise SolverError(
                    f"{self.method.name}: more than {self.max_steps_per_call} steps before "
                    f"t = {t_out:.6g} s (stuck at t = {self.t:.6g} s, h = {self.h:.3g} s); "
                    "the problem may be stiff"
                )
            self.step(t_out if land else None)
            budget -= 1
        return self.state_at(t_out)

    def state_at(self, t_out: float) -> list[float]:
        """Return the state at ``t_out`` within the last step ``[t_prev, t]``."""
        if t_out == self.t:
            return list(self.y)
        if t_out == self.t_prev:
            return list(self.y_prev)
        if not self.t_prev <= t_out <= self.t:
            raise SolverError(
                f"t = {t_out:.9g} s is outside the last step [{self.t_prev:.9g}, {self.t:.9g}] s"
            )
        if self._interp is None:
            self._complete_fy()
            h = self.t - self.t_prev
            self._interp = self.last_method.interpolant(
                self.f, self.t_prev, self.y_prev, self.y, self.fy_prev, self.fy, h, self.stages
            )
            self.nfev += self.last_method.dense_evals
        return self._interp((t_out - self.t_prev) / (self.t - self.t_prev))

    # ------------------------------------------------------------------ state
    # The attributes get_state saves (with ``landed``: its keys).
    STATE_FIELDS = (
        "t0",
        "t",
        "y",
        "fy",
        "h",
        "t_prev",
        "y_prev",
        "fy_prev",
        "stages",
        "nfev",
        "n_steps",
        "n_rejected",
        "grid_start",
        "landing_rest",
    )

    def get_state(self) -> dict[str, Any]:
        """Return everything that determines the future steps, as JSON-serialisable data."""
        state = {
            name: (
                [list(s) for s in value]
                if name == "stages"
                else (list(value) if isinstance(value, list) else value)
            )
            for name in self.STATE_FIELDS
            for value in [getattr(self, name)]
        }
        state["landed"] = self.last_method is not self.method  # the last step was the landing method's
        return state

    def set_state(self, state: dict[str, Any]) -> None:
        """Restore a state from :meth:`get_state`; later steps are bit-identical."""
        for name in self.STATE_FIELDS:
            value = state[name]
            if name == "stages":
                value = [list(s) for s in value]
            elif isinstance(value, list):
                value = list(value)
            setattr(self, name, value)
        self.last_method = self.landing_method if state["landed"] else self.method
        self._interp = None
