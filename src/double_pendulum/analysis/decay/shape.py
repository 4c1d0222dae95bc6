"""The decay's rate and shape on one reconstruction, for the tilted and the untilted track side by side
(``energy_decay``'s ``tilt`` entry): b with its AR(1) and block-bootstrap errors, the halves, the decay models
re-fitted under AR(1) (:mod:`.ar1_models`) and the free exponent p.

Units: t [s], E [J], b [1/s], p [1].
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..ar1 import ar1_coefficient
from ..track.measurement import Reconstruction
from ..track.tilt import RecordGeometry
from .ar1_models import compare, exponent
from .error_budget import halves
from .fit import calibrate_error_model, exponential
from .noise import noise_model


def decay_shape(rec: Reconstruction) -> dict[str, Any]:
    """The main recipe of ``energy_decay`` on ``rec`` (calibrated errors, the frames after the release): b and its
    statistical errors, the energy's scatter about the exponential, the halves, the AR(1) model comparison, p."""
    m = rec.free_motion
    t, e = rec.t[m], rec.energy[m]
    sigma = calibrate_error_model(t, e, rec.sigma_energy[m], rec.momentum[m]).sigma
    noise = noise_model(t, e, sigma)
    resid = e - exponential(t, noise["a_J"], noise["b_per_s"])
    return {"tilt_deg": math.degrees(rec.geometry.tilt), "b_per_s": noise["b_per_s"],
            "b_stderr_ar1_per_s": noise["ar1"]["b_per_s_stderr"],
            "b_stderr_bootstrap_per_s": noise["bootstrap"]["b_per_s_stderr"], "rho": noise["rho"],
            "energy_scatter_rms_J": float(np.sqrt(np.mean(resid**2))), "energy_scatter_lag_one": ar1_coefficient(resid),
            "halves": halves(t, e, sigma), "ar1_models": compare(t, e, sigma),
            "exponent": exponent(t, e, sigma)}  # fmt: skip


def tilt_effect(geometry: RecordGeometry, tilted: Reconstruction, untilted: Reconstruction) -> dict[str, Any]:
    """The record geometry and :func:`decay_shape` of the tilted (the main) and the untilted track, with a sentence
    on what the tilt changes."""
    a, b = decay_shape(tilted), decay_shape(untilted)
    ha, hb = a["halves"], b["halves"]
    xa, xb = a["exponent"], b["exponent"]
    text = (f"The camera's tilt against gravity, from the energy: {geometry.as_dict()['tilt_deg']:.2f} +- "
            f"{math.degrees(geometry.tilt_stderr):.2f} deg. Turned back by it, the energy's scatter about the "
            f"exponential falls from {1e3 * b['energy_scatter_rms_J']:.1f} to {1e3 * a['energy_scatter_rms_J']:.1f} mJ "
            f"and its lag-one correlation from {b['energy_scatter_lag_one']:.2f} to {a['energy_scatter_lag_one']:.2f}; "
            f"b moves from {b['b_per_s']:.4f} to {a['b_per_s']:.4f} 1/s. The halves differ by "
            f"{hb['difference_in_sigma_ar1']:.1f} sigma (AR(1); bootstrap {hb['difference_in_sigma_bootstrap']:.1f}) "
            f"untilted and {ha['difference_in_sigma_ar1']:.1f} ({ha['difference_in_sigma_bootstrap']:.1f}) tilted. "
            f"The free exponent p is {xb['p']:.2f} +- {xb['p_stderr']:.2f} untilted and {xa['p']:.2f} +- "
            f"{xa['p_stderr']:.2f} tilted (AR(1) likelihood; p = 1 is {xa['delta_neg2_log_l_at_p_1']:.1f} worse in "
            f"-2 ln L, untilted {xb['delta_neg2_log_l_at_p_1']:.1f}).")  # fmt: skip
    return {"record_geometry": geometry.as_dict(), "tilted": a, "untilted": b, "text": text,
            "definitions": {"tilted": "the track turned back by the fitted tilt (the main analysis)",
                            "untilted": "the track as the camera saw it (same pivot and lengths): the named variant "
                                        "before the correction"}}  # fmt: skip
