r"""Phase-space pictures of the chaos (built on :mod:`.chaos`): the flip-time map and Poincare sections.

**Flip map.** For every release from rest on a grid of :math:`(\varphi_{1,0}, \varphi_{2,0})` the time to
the first flip; :func:`flip_bound_violations` counts starts that flipped a rod although
:math:`E_0 < V(\pi, 0) = 2 (m_1+m_2) g l_1` (rod 1) or :math:`E_0 < V(0, \pi) = 2 m_2 g l_2` (rod 2),
which energy conservation forbids (:func:`.chaos.flip_energy_bounds`): it must be 0.

**Poincare sections** :math:`\varphi_1 = 0,\ \omega_1 > 0` at a fixed energy :math:`E` [J]: starts
spread over :math:`\varphi_2` within the reach :math:`V(0, \varphi_2) < E` (:func:`phi2_reach`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ...model.parameters import PendulumParameters
from ...runs.results_io import table_from_columns
from . import flips, poincare
from .ensemble import BatchField, batch_energy, batch_potential_energy, initial_states

ENERGY_BOUND_TEXT = (
    "a rod can flip only if E >= V at its upright position; V is smallest there with the other "
    "rod hanging: rod 1 needs E >= V(pi, 0) = 2 (m1+m2) g l1, rod 2 E >= V(0, pi) = 2 m2 g l2"
)


# ---------------------------------------------------------------------------- flip map
def flip_bound_violations(fmap: flips.FlipMap, params: PendulumParameters) -> int:
    """Number of starts where rod 1 flipped with ``E_0 < V(pi, 0)`` or rod 2 with ``E_0 < V(0, pi)``."""
    bound1, bound2 = flips.flip_energy_bounds(params)
    return int(
        np.count_nonzero(((fmap.rod == 1) & (fmap.energy < bound1)) | ((fmap.rod == 2) & (fmap.energy < bound2)))
    )


def flip_map_table(fmap: flips.FlipMap) -> tuple[np.ndarray, dict[str, str]]:
    """One row per start: ``phi1_0``, ``phi2_0`` [rad], ``E_0`` [J], ``flip_time`` [s], ``flipped_rod``."""
    g1, g2 = np.meshgrid(fmap.phi1, fmap.phi2)
    table = table_from_columns(phi1_0=g1, phi2_0=g2, E_0=fmap.energy, flip_time=fmap.time, flipped_rod=fmap.rod)
    return table, {"phi1_0": "rad", "phi2_0": "rad", "E_0": "J", "flip_time": "s"}


def flip_map_summary(fmap: flips.FlipMap, params: PendulumParameters) -> dict:
    """Grid, fraction of starts that flipped, the energetic bounds [J] and the check against them."""
    bound1, bound2 = flips.flip_energy_bounds(params)
    return {
        "grid": [fmap.time.shape[1], fmap.time.shape[0]],
        "t_max_s": fmap.t_max,
        "rk4_step_s": fmap.h,
        "wall_time_s": fmap.wall_time,
        "workers": fmap.workers,
        "fraction_flipped": float(np.mean(fmap.rod > 0)),
        "energy_bound": ENERGY_BOUND_TEXT,
        "E_flip_rod1_J": bound1,
        "E_flip_rod2_J": bound2,
        "starts_below_bound": int(np.count_nonzero(fmap.energy < fmap.threshold)),
        "bound_violations": flip_bound_violations(fmap, params),
    }


# ---------------------------------------------------------------------------- Poincare sections
def rest_energy(phi1: float, phi2: float, params: PendulumParameters) -> float:
    """Energy [J] of a release from rest at (phi1, phi2) [rad]: ``E = V(phi1, phi2)``, the kinetic energy being 0."""
    return float(batch_energy(initial_states(phi1, phi2), params)[0])


def phi2_reach(energy: float, params: PendulumParameters, *, margin: float = 0.95) -> float:
    """Largest |phi2| [rad] on the section phi1 = 0 at rest with energy ``energy`` [J], times ``margin``.

    The largest ``phi2`` in [0, pi] (grid of 2001 points) with ``V(0, phi2) < energy``.
    """
    grid = np.linspace(0.0, math.pi, 2001)
    allowed = grid[batch_potential_energy(0.0, grid, params) < energy]
    return margin * float(allowed.max())


@dataclass(frozen=True)
class Section:
    """Crossings of one energy surface: ``points`` ``(m, 4)`` on phi1 = 0, ``owner`` ``(m,)`` the start of each."""

    energy: float
    starts: np.ndarray
    points: np.ndarray
    owner: np.ndarray


def poincare_at_energy(
    field: BatchField, energy: float, n_starts: int, params: PendulumParameters, *, t_end: float, h: float
) -> Section:
    """Section phi1 = 0, omega1 > 0 of ``n_starts`` starts at energy ``energy`` [J].

    The starts have phi2 evenly spread over +-:func:`phi2_reach`, omega2 = 0 and omega1 > 0 from the
    energy (:func:`.chaos.section_starts`); RK4 step ``h`` [s] up to ``t_end`` [s] (:func:`.chaos.poincare_section`).
    """
    return poincare_at_energies(field, (energy,), n_starts, params, t_end=t_end, h=h)[0]


def poincare_at_energies(
    field: BatchField, energies: Sequence[float], n_starts: int, params: PendulumParameters, *, t_end: float,
    h: float,
) -> list[Section]:
    """:func:`poincare_at_energy` for each of ``energies`` [J], all starts integrated as one batch (the
    per-step overhead of a small batch dominates; each start's points are those of its own run)."""
    starts = [poincare.section_starts(e, np.linspace(-1.0, 1.0, n_starts) * phi2_reach(e, params), 0.0, params)
              for e in energies]  # fmt: skip
    points, owner = poincare.poincare_section(field, np.concatenate(starts, axis=1), t_end, h=h)
    sections, offset = [], 0
    for energy, own in zip(energies, starts):
        width = own.shape[1]
        mine = (owner >= offset) & (owner < offset + width)
        sections.append(Section(energy, own, points[mine], owner[mine] - offset))
        offset += width
    return sections


def section_summary(section: Section, params: PendulumParameters) -> dict:
    """Energy [J], number of starts and points, and the largest relative energy error of the starts."""
    error = np.max(np.abs(batch_energy(section.starts, params) - section.energy)) / section.energy
    return {
        "energy_J": section.energy,
        "starts": int(section.starts.shape[1]),
        "points": int(section.points.shape[0]),
        "start_energy_relative_error": float(error),
    }


def section_points(sections: Mapping[str, Section]) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """``(phi2 [rad], omega2 [rad/s], owner)`` of each labelled section, labelled with its energy, for plotting."""
    return {f"{label}: E = {s.energy:.3f} J": (s.points[:, 1], s.points[:, 3], s.owner)
            for label, s in sections.items()}
