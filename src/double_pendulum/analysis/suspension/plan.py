"""The sizes of the ``suspension_transfer`` scenario's runs (quick, default, thorough): the map's grids and
masses, the extra fits, and what a null in its summary means (:data:`NULL_MEANS`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from .identification import DEFAULT_SUSPENSION, QUICK_WINDOW_S


@dataclass(frozen=True)
class Plan:
    """Sizes of one run: sweep grids [N/m, N s/m], masses [kg], time window [s], extra fits."""

    k_grid: tuple[float, ...]
    c_grid: tuple[float, ...]
    m_s_main: float
    m_s_extra: tuple[float, ...]
    extra_stride: int
    window_s: float | None
    valley_k_factors: tuple[float, ...]
    resonant_end: bool
    window_checks_s: tuple[float, ...]
    max_workers: int | None


NULL_MEANS = {
    "resonant_end": "not traced: the quick run skips it, or the measured b is not crossed at the map's "
                    "smallest c",
    "k_range_within_N_per_m": "no map cell within the tolerance",
    "c_range_within_N_s_per_m": "no map cell within the tolerance",
    "largest_share_within_per_s": "no map cell within the tolerance",
    "ratio_fmu_to_prediction": "the prediction is zero or undefined in that cell",
    "stiffest_k_reaching_N_per_m": "no k on the map reaches the measured b",
}
"""What a null in ``summary.json`` means, by key (write_json writes non-finite numbers and None as null)."""


def _k_grid(exponents: Sequence[int]) -> tuple[float, ...]:
    """Stiffnesses 2e4 * 10^(n/5) N/m: the default k and steps of 1.585 around it."""
    return tuple(DEFAULT_SUSPENSION.k_x * 10.0 ** (n / 5.0) for n in exponents)


FULL = Plan(
    k_grid=_k_grid(range(-3, 6)),
    c_grid=tuple(float(c) for c in np.geomspace(1.0, 3000.0, 7)),
    m_s_main=DEFAULT_SUSPENSION.M_s,
    m_s_extra=(),
    extra_stride=2,
    window_s=None,
    valley_k_factors=(),
    resonant_end=True,
    window_checks_s=(),
    max_workers=None,
)
THOROUGH = replace(FULL, c_grid=tuple(float(c) for c in np.geomspace(1.0, 3000.0, 9)), m_s_extra=(0.5, 8.0),
                   valley_k_factors=(1.25, 1.5), window_checks_s=(7.0, 14.0))
"""``--thorough``: the main map on 9 x 9 cells (the default: 9 k x 7 c) and coarser ones (every second k and
c) at M_s = 0.5 and 8 kg (50 more runs, the stiffest cells of the light suspension among them: about
2.5 times the map's CPU time), c refitted along the valley at 1.25 k and 1.5 k (the default follows the
valley by its Fisher matrix alone: a refit is a sequential fit of about 12 s of CPU) and c identified
again on the first 7 and 14 s of the record (three more sequential fits)."""
QUICK = Plan(
    k_grid=_k_grid((0, 3)),
    c_grid=(5.0, 200.0),
    m_s_main=DEFAULT_SUSPENSION.M_s,
    m_s_extra=(),
    extra_stride=1,
    window_s=QUICK_WINDOW_S,
    valley_k_factors=(),
    resonant_end=False,
    window_checks_s=(),
    max_workers=1,
)
