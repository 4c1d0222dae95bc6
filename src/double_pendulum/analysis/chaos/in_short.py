"""The plain summary of the ``chaos`` scenario (``in_short`` in its ``summary.json``): three to five sentences a
student understands, every number from the summary it is written into."""

from __future__ import annotations

from .summary_types import ChaosSummary


def in_short(summary: ChaosSummary) -> str:
    """What was run, what was found, how sure, from the ``chaos`` scenario's ``summary``."""
    lyap, runs, pred, flip = summary["lyapunov"], summary["fmu_runs"], summary["predictability"], summary["flip_map"]
    mm = 1000 * summary["start_uncertainty_m"]
    parted = runs.get("releases_part_by_1cm_at_s")
    horizon = pred.get("horizon_1cm_at_5mm_s")
    sentences = [
        f"The pendulum was released again and again from the seed's start (upper rod at "
        f"{summary['default_start']['phi1_0']:g} rad, lower rod hanging), each time a little differently, as a hand "
        f"that places the upper bob to within {mm:g} mm would.",
        (f"Three such releases keep their lower bobs within 1 cm of each other for only {parted:.2f} s"
         if parted is not None else "Three such releases kept their lower bobs within 1 cm of each other"
         f" for the whole {runs['stop_time_s']:g} s run") + ", as the seed's three photographed runs parted.",
        f"A small difference grows by a factor e about every {1 / lyap['lyapunov_per_s']:.2f} s: the largest Lyapunov "
        f"exponent is {lyap['lyapunov_per_s']:.2f} +- {lyap['lyapunov_sem_per_s']:.2f} 1/s (mean and standard error "
        f"of {lyap['cloud_members'] + 1} estimates).",
        (f"Of {pred['members_per_ensemble']} releases within {mm:g} mm, the spread of the lower bobs exceeds 1 cm "
         f"after {horizon:.2f} s" if horizon is not None else
         f"The spread of {pred['members_per_ensemble']} releases within {mm:g} mm stayed below 1 cm") +
        f"; over a map of start angles, a rod turns over within {flip['t_max_s']:g} s from "
        f"{100 * flip['fraction_flipped']:.0f} % of them.",
    ]
    if summary.get("quick"):
        sentences.append("This is a quick run: small ensembles and short runs, a smoke test, not the figures.")
    return " ".join(sentences)
