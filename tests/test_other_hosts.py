"""The FMU in an independent FMI importer (libcosim via libcosimpy) gives the same results as fmpy."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest

pytest.importorskip("libcosimpy", reason="libcosimpy (the test extra) is not installed")

CASES = {
    "frictionless": {"phi1_0": 2.0, "phi2_0": 2.0},
    "all_mechanisms": {
        "phi1_0": 1.5,
        "phi2_0": 1.0,
        "air_drag": True,
        "rod_drag": True,
        "bearing_friction": True,
        "suspension": True,
        "k_x": 5e3,
        "solver": "dopri5",
        "rtol": 1e-8,
    },
}
OUTPUTS = ["phi1", "phi2", "omega1", "omega2", "xs", "E_total", "W_air", "energy_residual"]


def _libcosim_result(fmu_path, start, tmp_path) -> dict[str, float]:
    """Run libcosim in its own process (isolated from the fmpy instances of this session)."""
    script = textwrap.dedent(f"""
        import json, os
        from double_pendulum.fmu.running.hosts import simulate_with_libcosim
        values = simulate_with_libcosim({str(fmu_path)!r}, {start!r}, {OUTPUTS!r}, stop_time=3.0, step_size=0.01)
        print(json.dumps(values), flush=True)
        os._exit(0)  # skip teardown, see docs/fmu.md (pythonfmu issue #228)
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("case", list(CASES))
def test_libcosim_gives_the_same_result_as_fmpy(runner, fmu_path, tmp_path, case):
    start = CASES[case]
    cosim = _libcosim_result(fmu_path, start, tmp_path)
    fmpy_result = runner.simulate(start, stop_time=3.0, output_interval=0.01, outputs=OUTPUTS)
    for name in OUTPUTS:
        assert cosim[name] == pytest.approx(float(fmpy_result[name][-1]), rel=1e-12, abs=1e-12), name
