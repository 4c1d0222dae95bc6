"""Property tests (hypothesis): random valid scenes, including extreme ones, behave physically.

CI runs a fixed, derandomised set of examples; for a larger local run use
``HYPOTHESIS_PROFILE=thorough python -m pytest tests/test_properties.py`` (500 examples).
"""

from __future__ import annotations

import math
import os

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from double_pendulum.fmu.masters.simulate import simulate

settings.register_profile(
    "ci", max_examples=30, derandomize=True, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.register_profile(
    "thorough", max_examples=500, derandomize=False, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


def log_uniform(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0**e)


scenes = st.fixed_dictionaries(
    {
        "m1": log_uniform(1e-3, 5.0),
        "m2": log_uniform(1e-3, 5.0),
        "l1": log_uniform(0.01, 2.0),
        "l2": log_uniform(0.01, 2.0),
        "phi1_0": st.floats(-math.pi, math.pi),
        "phi2_0": st.floats(-math.pi, math.pi),
        "omega1_0": st.floats(-10.0, 10.0),
        "omega2_0": st.floats(-20.0, 20.0),
        "air_drag": st.booleans(),
        "rod_drag": st.booleans(),
        "cw": st.floats(0.0, 2.0),
        "bearing_friction": st.booleans(),
        "c_R1": log_uniform(1e-5, 1e-2),
        "c_R2": log_uniform(1e-5, 1e-2),
        "omega_reg": log_uniform(1e-3, 1.0),
        "bearing_drag": st.booleans(),
        "tau_b_fraction": log_uniform(1e-5, 1e-2),  # drag torque as a fraction of (m1 + m2) g l1
        "m_rod1": st.sampled_from([0.0, 0.01, 0.07, 1.0]),
        "m_rod2": st.sampled_from([0.0, 0.01, 0.07, 1.0]),
        "L_rod1": log_uniform(0.01, 2.0),
        "suspension": st.booleans(),
        "M_s": log_uniform(0.05, 10.0),
        "k_x": log_uniform(1e2, 1e6),
        "k_y": log_uniform(1e2, 1e6),
        "c_x": st.floats(0.0, 100.0),
        "c_y": st.floats(0.0, 100.0),
    }
)


@given(scene=scenes)
def test_random_valid_scenes_run_and_keep_the_energy_budget(scene):
    scene = dict(scene)
    scene["tau_b1"] = scene.pop("tau_b_fraction") * (scene["m1"] + scene["m2"]) * 9.81 * scene["l1"]
    r = simulate({**scene, "rtol": 1e-8, "atol": 1e-10}, stop_time=1.0, output_interval=0.01)
    assert r["time"][-1] == 1.0
    for name in r.dtype.names:
        assert np.all(np.isfinite(r[name])), name
    for name in ("W_air", "W_bearing", "W_bearing_drag", "W_suspension"):
        assert np.all(np.diff(r[name]) >= 0.0), name
    mass = scene["m1"] + scene["m2"] + scene["m_rod1"] + scene["m_rod2"]
    scale = max(r["E_total"][0], mass * 9.81 * (scene["l1"] + scene["l2"]))
    assert np.max(np.abs(r["energy_residual"])) <= 1e-5 * scale
