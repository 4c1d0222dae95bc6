r"""The pivot's motion from the host's samples: position-only driving, and a warning for it.

The model needs the pivot's acceleration (it drives the angles) and its velocity (bob velocities,
drag, energies, :mod:`double_pendulum.model.inputs`). An FMI tool most often wires only a position
signal. The parameter ``pivot_input`` (:class:`~double_pendulum.component.settings.InputSettings`)
says which the host sends:

* ``acceleration`` (default): the host sends position, velocity and acceleration, used as given.
  If positions change while all four velocities and accelerations stay 0 in a direction the pivot
  is prescribed in, the pendulum would not swing with the pivot: the component says so once
  (:data:`POSITION_ONLY_WARNING`, through the FMU's log and stderr).
* ``position``: the host sends ``pivot_x, pivot_y``; at each communication point :math:`t_n` the
  component takes the parabola through the last three samples
  :math:`(t_{n-2}, x_{n-2}), (t_{n-1}, x_{n-1}), (t_n, x_n)` (divided differences
  :math:`d_1 = (x_n - x_{n-1})/(t_n - t_{n-1})`, :math:`d_0 = (x_{n-1} - x_{n-2})/(t_{n-1} - t_{n-2})`):

  .. math::

      a_n = \frac{2 (d_1 - d_0)}{t_n - t_{n-2}},\qquad v_n = d_1 + \tfrac12 a_n (t_n - t_{n-1}),

  and holds the quadratic :math:`x_n + v_n\tau + \tfrac12 a_n\tau^2` over the step (the parabola
  itself, extrapolated). The position is the host's at every communication point; the velocity is
  second-order accurate, :math:`O(h^2)`; the acceleration is the true one at about :math:`t_{n-1}`,
  so it lags by one communication step :math:`h` (first order, relative error about
  :math:`\omega h` for a motion of angular frequency :math:`\omega`). The velocities and
  accelerations the host sets are ignored. Before three samples exist the missing ones are those
  of a pivot at rest before the first sample (velocity and acceleration 0 until then).
"""

from __future__ import annotations

from collections.abc import Sequence

POSITION_ONLY_WARNING = (
    "pivot_x/pivot_y change while pivot_vx, pivot_vy, pivot_ax and pivot_ay stay 0: with pivot_input = "
    "acceleration only the pivot's acceleration drives the angles, so the pendulum does not swing with the "
    "pivot. Send the velocities and accelerations too, or set pivot_input = position."
)


def parabola_rates(t: Sequence[float], x: Sequence[float]) -> tuple[float, float]:
    """Velocity and acceleration at ``t[2]`` of the parabola through three samples ``(t[i], x[i])``.

    Times strictly increasing [s], positions [m]; returns ``(v [m/s], a [m/s2])``.
    """
    d1 = (x[2] - x[1]) / (t[2] - t[1])
    d0 = (x[1] - x[0]) / (t[1] - t[0])
    a = 2.0 * (d1 - d0) / (t[2] - t[0])
    return d1 + 0.5 * a * (t[2] - t[1]), a


class PositionSamples:
    """The pivot positions at the last three communication points (``pivot_input = position``)."""

    def __init__(self, samples: Sequence[Sequence[float]] = ()) -> None:
        self.samples: list[tuple[float, float, float]] = [(float(t), float(x), float(y)) for t, x, y in samples]

    def rates_at(self, t: float, x: float, y: float) -> tuple[float, float, float, float]:
        """Record the sample ``(x, y)`` [m] at ``t`` [s]; return ``(vx, vy, ax, ay)`` there (see the module).

        A sample at or before the last one's time replaces the later ones (a repeated step after a
        rollback). With one or two earlier samples missing the pivot is taken at rest before the
        first sample, one step of the same length earlier.
        """
        samples = [s for s in self.samples if s[0] < t][-2:]
        samples.append((t, x, y))
        self.samples = samples
        while len(samples) < 3:
            first = samples[0]
            step = samples[1][0] - first[0] if len(samples) > 1 else 1.0
            samples = [(first[0] - step, first[1], first[2]), *samples]
        times = [s[0] for s in samples]
        vx, ax = parabola_rates(times, [s[1] for s in samples])
        vy, ay = parabola_rates(times, [s[2] for s in samples])
        return vx, vy, ax, ay


class PositionOnlyWatch:
    """Watches for position-only wiring in ``pivot_input = acceleration`` mode (warns once)."""

    def __init__(self, prescribed_x: bool, prescribed_y: bool) -> None:
        self.prescribed = (prescribed_x, prescribed_y)  # directions without a suspension state
        self.last: tuple[float, float] | None = None
        self.warned = False

    def check(self, u: Sequence[float]) -> str | None:
        """The warning, the first time the positions ``u[0:2]`` move while ``u[2:6]`` are all 0, else None."""
        x, y = u[0], u[1]
        last, self.last = self.last, (x, y)
        if self.warned or last is None or u[2] or u[3] or u[4] or u[5]:
            return None
        moved_x = x != last[0] and self.prescribed[0]
        moved_y = y != last[1] and self.prescribed[1]
        if not (moved_x or moved_y):
            return None
        self.warned = True
        return POSITION_ONLY_WARNING
