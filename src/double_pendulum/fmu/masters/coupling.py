"""A small co-simulation master: DoublePendulum on Suspension, coupled across the FMU boundary.

Connections (no glue: the two FMUs' variables are meant for each other)::

    DoublePendulum.F_pivot_x, F_pivot_y            -> Suspension.F_x, F_y
    Suspension.x, y, vx, vy, ax, ay                -> DoublePendulum.pivot_x, ..., pivot_ay

(the pendulum with its own ``suspension`` off, the suspension's ``F_static_y`` the pendulum's
weight ``-(m1 + m2) g``: :func:`split_values`). ``F_pivot`` depends directly on ``pivot_a*`` and
the suspension's acceleration directly on the force: an algebraic loop. :func:`run_coupled`
steps the two slaves with a fixed macro step ``h`` [s] under one of four schemes
(:data:`SCHEMES`):

``jacobi``
    what libcosim does (it reads all outputs right after the step, then sets the inputs; plus
    two more exchanges while initialising: ``initial_exchanges=2``): at t_n both slaves read
    the other's outputs of t_n and step side by side with them held (zero-order hold of the force; the pendulum's own
    second-order hold of the pivot motion). The loop is broken by the outputs of the last
    communication point, which were computed with the inputs of the step before: a delay of one
    macro step on each side. First order in h; unstable for (m1 + m2) / M_s above about 1
    (the added-mass instability, see docs/coupling.md).
``jacobi_sequential``
    the slaves still step side by side with held inputs, but the exchange passes the force first
    and then the suspension's motion, read after the new force was set (its acceleration
    follows the force at once): the suspension side's delay is gone, the pendulum's remains.
    This is what fmpy's container FMU does (connections passed in the order listed, the force
    first, each read when it is passed).
``extrapolation``
    as ``jacobi``, but each held input is extrapolated linearly from the last two communication
    points to the middle of the step, u = u_n + (u_n - u_{n-1}) / 2 (an estimate of the step's
    mean at no extra cost; the pivot position and velocity stay as sent). Measured: no gain in
    accuracy, a lower added-mass limit (docs/coupling.md).
``iterative``
    implicit coupling: each step is repeated, both slaves rolled back with their FMU state
    (``get_state``/``set_state``, fmi2GetFMUstate/fmi2SetFMUstate), until the suspension's
    acceleration at the end of the step is consistent with the force it produced; the held
    values are the means of the step's start and end values (trapezoidal), the iteration is
    relaxed with Aitken's factor. Second order; stable beyond the added-mass limit; costs a few
    slave steps a macro step (plus the state copies).

The slaves are anything with ``set_input(name, value)``, ``get(name)`` and ``do_step(t, h)``
(plus ``get_state``/``set_state`` for ``iterative``): the in-process components, or FMUs
through :class:`FmuSlave`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, Protocol

import numpy as np

FORCE_CONNECTIONS: tuple[tuple[str, str], ...] = (("F_pivot_x", "F_x"), ("F_pivot_y", "F_y"))
MOTION_CONNECTIONS: tuple[tuple[str, str], ...] = (
    ("x", "pivot_x"), ("y", "pivot_y"), ("vx", "pivot_vx"), ("vy", "pivot_vy"), ("ax", "pivot_ax"), ("ay", "pivot_ay"),
)  # fmt: skip
SUSPENSION_PARAMETERS = ("M_s", "k_x", "k_y", "c_x", "c_y")
SCHEMES = ("jacobi", "jacobi_sequential", "extrapolation", "iterative")
PENDULUM_OUTPUTS = ("phi1", "phi2", "E_pendulum", "W_input", "F_pivot_x", "F_pivot_y")
SUSPENSION_OUTPUTS = ("x", "y", "vx", "vy", "ax", "ay", "E_suspension", "W_suspension", "W_in", "P_in")
BLOWUP_FACTOR = 1e3
"""A run is unstable once the coupling has created more than this many times the energy scale."""


class Slave(Protocol):
    """What the master needs of a co-simulation slave."""

    def set_input(self, name: str, value: float) -> None: ...

    def get(self, name: str) -> Any: ...

    def do_step(self, current_time: float, step_size: float) -> None: ...


class CouplingError(RuntimeError):
    """The coupled run blew up or a slave failed; ``rows`` holds the communication points so far."""

    def __init__(self, message: str, rows: np.ndarray) -> None:
        super().__init__(message)
        self.rows = rows


def split_values(values: Mapping[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """Split the start values of the monolith (``suspension`` on) into the two FMUs' values.

    The suspension parameters go to ``Suspension`` with ``F_static_y = -(m1 + m2) g`` [N] (the
    pendulum's weight: it hangs at rest without moving the mass); everything else but the
    ``suspension`` switch goes to ``DoublePendulum``, whose own suspension stays off.
    """
    from ...model.parameters import PendulumParameters

    p = PendulumParameters(**{n: values[n] for n in ("m1", "m2", "g") if n in values})
    pendulum = {n: v for n, v in values.items() if n not in SUSPENSION_PARAMETERS and n != "suspension"}
    suspension = {n: v for n, v in values.items() if n in SUSPENSION_PARAMETERS}
    suspension["F_static_y"] = -(p.m1 + p.m2) * p.g
    return pendulum, suspension


def column_names(pendulum_outputs: Sequence[str], suspension_outputs: Sequence[str]) -> list[str]:
    """The result columns after ``time``: pendulum outputs, then suspension outputs (``s_`` on a clash)."""
    return list(pendulum_outputs) + [f"s_{n}" if n in pendulum_outputs else n for n in suspension_outputs]


def exchange(pendulum: Slave, suspension: Slave) -> None:
    """Pass each slave the other's current outputs (both read before either is written)."""
    forces, motion = read_interface(pendulum, suspension)
    write_interface(pendulum, suspension, forces, motion)


def read_interface(pendulum: Slave, suspension: Slave) -> tuple[list[float], list[float]]:
    """The coupling outputs now: the pivot force [N] and the suspension's motion (m, m/s, m/s2)."""
    forces = [float(pendulum.get(source)) for source, _ in FORCE_CONNECTIONS]
    motion = [float(suspension.get(source)) for source, _ in MOTION_CONNECTIONS]
    return forces, motion


def write_interface(pendulum: Slave, suspension: Slave, forces: Sequence[float], motion: Sequence[float]) -> None:
    """Set the force on the suspension and the pivot motion on the pendulum."""
    for (_, target), value in zip(FORCE_CONNECTIONS, forces):
        suspension.set_input(target, value)
    for (_, target), value in zip(MOTION_CONNECTIONS, motion):
        pendulum.set_input(target, value)


def sequential_exchange(pendulum: Slave, suspension: Slave) -> None:
    """Pass the pendulum's force to the suspension, then the suspension's motion (now following it) back."""
    write_interface(pendulum, suspension, read_interface(pendulum, suspension)[0], [])
    write_interface(pendulum, suspension, [], read_interface(pendulum, suspension)[1])


def _extrapolated(now: Sequence[float], before: Sequence[float] | None) -> list[float]:
    """u_n + (u_n - u_{n-1}) / 2: the linear extrapolation of u to the middle of the next step."""
    if before is None:
        return list(now)
    return [u + 0.5 * (u - v) for u, v in zip(now, before)]


class _Extrapolation:
    """The ``extrapolation`` scheme's memory: the interface values of the last communication point."""

    def __init__(self) -> None:
        self.previous: tuple[list[float], list[float]] | None = None

    def step(self, pendulum: Slave, suspension: Slave, t: float, h: float) -> None:
        forces, motion = read_interface(pendulum, suspension)
        old_f, old_m = self.previous if self.previous is not None else (None, None)
        held_motion = motion[:4] + _extrapolated(motion[4:], old_m[4:] if old_m else None)
        write_interface(pendulum, suspension, _extrapolated(forces, old_f), held_motion)
        self.previous = (forces, motion)
        pendulum.do_step(t, h)
        suspension.do_step(t, h)


class _Iterative:
    """The ``iterative`` scheme: trapezoidal holds, fixed-point iteration with rollback and Aitken relaxation.

    The unknown is the suspension's acceleration a at the end of the step (2 values, m/s2). One
    sweep, both slaves first rolled back to t: pendulum over [t, t + h] with
    ``pivot_a = (a_n + a) / 2``, then ``pivot_a = a`` set to read its force F at t + h (direct
    feedthrough: F must belong to a); suspension with ``F = (F_n + F) / 2``, then ``F`` set to read
    its acceleration a' at t + h. The residual r = a' - a is driven to zero by a <- a + w r with
    Aitken's w_k = -w_{k-1} r_{k-1}.(r_k - r_{k-1}) / |r_k - r_{k-1}|^2 (w_0 = 0.5). At the start
    the loop is first solved without stepping, so F_0 and a_0 belong together.
    """

    def __init__(self, tolerance: float = 1e-8, max_iterations: int = 50) -> None:
        self.tolerance = tolerance
        self.max_iterations = max_iterations
        self.sweeps = 0  # slave steps taken by each slave, for the cost
        self.started = False

    def _consistent_start(self, pendulum: Slave, suspension: Slave) -> None:
        """Solve F = F(pendulum, a), a = a(suspension, F) at the start point (no stepping)."""

        def sweep(a: list[float]) -> list[float]:
            for (_, target), value in zip(MOTION_CONNECTIONS[4:], a):
                pendulum.set_input(target, value)
            write_interface(pendulum, suspension, read_interface(pendulum, suspension)[0], [])
            return [float(suspension.get(source)) for source, _ in MOTION_CONNECTIONS[4:]]

        forces, motion = read_interface(pendulum, suspension)
        write_interface(pendulum, suspension, [], motion)
        self._solve(sweep, list(motion[4:]))
        self.started = True

    def _solve(self, sweep: Any, a: list[float]) -> list[float]:
        """Fixed point a = sweep(a) by Aitken-relaxed iteration; return the a of the last (converged) sweep."""
        w, r_old = 0.5, None
        for _ in range(self.max_iterations):
            r = [new - old for new, old in zip(sweep(a), a)]
            if max(abs(v) for v in r) <= self.tolerance * (1.0 + max(abs(v) for v in a)):
                return a
            if r_old is not None:
                dr = [u - v for u, v in zip(r, r_old)]
                den = sum(d * d for d in dr)
                if den > 0.0:
                    w = -w * sum(u * d for u, d in zip(r_old, dr)) / den
            a = [v + w * d for v, d in zip(a, r)]
            r_old = r
        raise RuntimeError(f"iterative coupling did not converge in {self.max_iterations} iterations")

    def step(self, pendulum: Slave, suspension: Slave, t: float, h: float) -> None:
        if not self.started:
            self._consistent_start(pendulum, suspension)
        forces, motion = read_interface(pendulum, suspension)
        states = (pendulum.get_state(), suspension.get_state())

        def sweep(a_end: list[float]) -> list[float]:
            pendulum.set_state(states[0], validate=False)  # the master's own rollback states
            suspension.set_state(states[1], validate=False)
            mean_a = [0.5 * (a0 + a1) for a0, a1 in zip(motion[4:], a_end)]
            write_interface(pendulum, suspension, [], motion[:4] + mean_a)
            pendulum.do_step(t, h)
            for (_, target), value in zip(MOTION_CONNECTIONS[4:], a_end):
                pendulum.set_input(target, value)
            f_end = [float(pendulum.get(source)) for source, _ in FORCE_CONNECTIONS]
            write_interface(pendulum, suspension, [0.5 * (f0 + f1) for f0, f1 in zip(forces, f_end)], [])
            suspension.do_step(t, h)
            write_interface(pendulum, suspension, f_end, [])
            self.sweeps += 1
            return [float(suspension.get(source)) for source, _ in MOTION_CONNECTIONS[4:]]

        try:
            self._solve(sweep, list(motion[4:]))  # its last sweep left both slaves at t + h, converged
        finally:
            for state in states:
                _free(state)


def _free(state: Any) -> None:
    """Free an FMU state if it is one (in-process states are plain data)."""
    release = getattr(state, "release", None)
    if release is not None:
        release()


def _jacobi_step(pendulum: Slave, suspension: Slave, t: float, h: float) -> None:
    exchange(pendulum, suspension)
    pendulum.do_step(t, h)
    suspension.do_step(t, h)


def _sequential_step(pendulum: Slave, suspension: Slave, t: float, h: float) -> None:
    sequential_exchange(pendulum, suspension)
    pendulum.do_step(t, h)
    suspension.do_step(t, h)


def coupling_energy(row: Mapping[str, float] | np.void) -> float:
    """Energy the coupling has created [J]: W_input (work received by the pendulum) + W_in (done on the mass).

    Through an ideal joint the pendulum receives exactly the work the suspension mass does on it,
    W_input = -W_in, so their sum is what the coupling itself creates (> 0) or destroys (< 0).
    """
    return float(row["W_input"] + row["W_in"])


def run_coupled(
    pendulum: Slave,
    suspension: Slave,
    *,
    stop_time: float,
    macro_step: float,
    scheme: str = "jacobi",
    start_time: float = 0.0,
    pendulum_outputs: Sequence[str] = PENDULUM_OUTPUTS,
    suspension_outputs: Sequence[str] = SUSPENSION_OUTPUTS,
    energy_scale: float = 1.0,
    initial_exchanges: int = 0,
) -> np.ndarray:
    """Step two initialised slaves with a fixed macro step [s]; return the rows at each communication point.

    Columns: ``time``, then :func:`column_names`. The run stops with :class:`CouplingError`
    (message, rows so far) when a slave fails, a value is not finite, or the coupling energy
    :func:`coupling_energy` exceeds ``BLOWUP_FACTOR * energy_scale`` [J] (when ``W_input`` and
    ``W_in`` are among the outputs): an unstable coupling never ends in silent NaN.
    ``initial_exchanges``: exchanges of the scheme's kind before the first step's own, as a
    master may do while initialising (libcosim: 2 with ``jacobi``).
    """
    if scheme not in SCHEMES:
        raise ValueError(f"unknown coupling scheme {scheme!r}; choose one of {SCHEMES}")
    names = column_names(pendulum_outputs, suspension_outputs)
    dtype = [("time", np.float64)] + [(n, np.float64) for n in names]
    stepper = {"jacobi": _jacobi_step, "jacobi_sequential": _sequential_step,
               "extrapolation": _Extrapolation().step, "iterative": _Iterative().step}[scheme]
    for _ in range(initial_exchanges):
        (sequential_exchange if scheme == "jacobi_sequential" else exchange)(pendulum, suspension)
    watch_energy = "W_input" in names and "W_in" in names

    def row(t: float) -> tuple[float, ...]:
        return (t, *(pendulum.get(n) for n in pendulum_outputs), *(suspension.get(n) for n in suspension_outputs))

    rows = [row(start_time)]
    n_steps = int(round((stop_time - start_time) / macro_step))
    for n in range(n_steps):
        t = start_time + n * macro_step
        try:
            stepper(pendulum, suspension, t, macro_step)
        except Exception as error:  # a slave gave up: keep the rows, say where
            raise CouplingError(f"{scheme} coupling, h = {macro_step:g} s: a slave failed at t = {t:.6g} s: "
                                f"{error}", np.array(rows, dtype=dtype)) from error
        rows.append(row(start_time + (n + 1) * macro_step))
        check_row(rows, dtype, scheme, macro_step, watch_energy, energy_scale)
    return np.array(rows, dtype=dtype)


def check_row(rows: list, dtype: list, scheme: str, h: float, watch_energy: bool, energy_scale: float) -> None:
    """Raise :class:`CouplingError` if the last of ``rows`` is not finite or the coupling energy ran away.

    ``rows``: tuples of the ``dtype`` fields; ``scheme`` and ``h`` [s] only name the run in the message.
    """
    last = np.array([rows[-1]], dtype=dtype)[0]
    bad = [n for n in last.dtype.names if not math.isfinite(last[n])]
    if bad:
        raise CouplingError(f"{scheme} coupling, h = {h:g} s: unstable, {', '.join(bad)} not finite at "
                            f"t = {last['time']:.6g} s", np.array(rows[:-1], dtype=dtype))
    if watch_energy and abs(coupling_energy(last)) > BLOWUP_FACTOR * energy_scale:
        raise CouplingError(
            f"{scheme} coupling, h = {h:g} s: unstable, the coupling created {coupling_energy(last):.3g} J "
            f"(> {BLOWUP_FACTOR:g} x {energy_scale:.3g} J) by t = {last['time']:.6g} s",
            np.array(rows, dtype=dtype),
        )


def run_jacobi(pendulum: Slave, suspension: Slave, **kwargs: Any) -> np.ndarray:
    """:func:`run_coupled` with the ``jacobi`` scheme (what libcosim and the container FMU do)."""
    return run_coupled(pendulum, suspension, scheme="jacobi", **kwargs)


class _FmuState:
    """An FMU state (fmi2GetFMUstate) that frees itself on :meth:`release`."""

    def __init__(self, fmu: Any) -> None:
        self.fmu, self.state = fmu, fmu.getFMUstate()

    def release(self) -> None:
        if self.state is not None:
            self.fmu.freeFMUstate(self.state)
            self.state = None


class FmuSlave:
    """An extracted FMU as a :class:`Slave` (fmpy's ``FMU2Slave``), initialised with ``start_values``."""

    def __init__(
        self,
        unzipdir: str,
        model_description: Any,
        start_values: Mapping[str, Any] | None = None,
        instance_name: str | None = None,
        start_time: float = 0.0,
    ) -> None:
        from fmpy.fmi2 import FMU2Slave

        md = model_description
        self.refs = {v.name: v for v in md.modelVariables}
        self.fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=unzipdir,
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=instance_name or md.coSimulation.modelIdentifier,
        )
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=start_time)
        self.fmu.enterInitializationMode()
        for name, value in (start_values or {}).items():
            self._set(name, value)
        self.fmu.exitInitializationMode()

    def _set(self, name: str, value: Any) -> None:
        var = self.refs[name]
        setter = {"Real": self.fmu.setReal, "Integer": self.fmu.setInteger, "Boolean": self.fmu.setBoolean,
                  "String": self.fmu.setString}[var.type]
        setter([var.valueReference], [value])

    def set_input(self, name: str, value: float) -> None:
        self.fmu.setReal([self.refs[name].valueReference], [value])

    def get(self, name: str) -> float:
        return self.fmu.getReal([self.refs[name].valueReference])[0]

    def do_step(self, current_time: float, step_size: float) -> None:
        self.fmu.doStep(currentCommunicationPoint=current_time, communicationStepSize=step_size)

    def get_state(self) -> _FmuState:
        """The FMU's complete state (fmi2GetFMUstate); the master frees it with ``release()``."""
        return _FmuState(self.fmu)

    def set_state(self, state: _FmuState) -> None:
        """Roll the FMU back to ``state`` (fmi2SetFMUstate)."""
        self.fmu.setFMUstate(state.state)

    def close(self) -> None:
        """Terminate and free the instance."""
        self.fmu.terminate()
        self.fmu.freeInstance()
