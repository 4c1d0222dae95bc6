"""Trajectory-steps per second of the NumPy batch RK4 against the same RK4 loop in compiled C.

Usage: ``python benchmarks/batch_vs_c.py [--batch 10000] [--steps 500] [--repeats 3] [--flip-map 200]``

Both integrate the same batch (seeded random release angles in (-pi, pi)^2 from rest, the seed
pendulum, h = 1 ms) with the classic RK4 in the same stage order: the batch integrator
(:func:`double_pendulum.analysis.chaos.ensemble.rk4_step` on
:func:`~double_pendulum.analysis.chaos.ensemble.pendulum_field`,
vectorised over the batch) and a plain C loop over trajectories and steps, compiled at run time
with the system ``cc -O2`` into a temporary folder and called through ctypes. The C source
restates the equations of :mod:`double_pendulum.model.dynamics` only for this comparison; the script
checks that both end in the same states. Figures are CPU times (``time.process_time``), the
median of ``--repeats`` runs, printed side by side with their ratio (the issue's target: within
3 times for batches of 10,000). ``--flip-map N`` also times an N x N flip-time map over 10 s on
all cores (wall time).
"""

from __future__ import annotations

import argparse
import ctypes
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from double_pendulum.analysis.chaos.ensemble import initial_states, pendulum_field, rk4_step
from double_pendulum.analysis.chaos.flips import flip_time_map
from double_pendulum.model.parameters import PendulumParameters

C_SOURCE = r"""
#include <math.h>

/* dy/dt of the double pendulum, the closed-form 2x2 solve of double_pendulum.model.dynamics */
static void field(const double *y, double *d, double m1, double m2, double l1, double l2, double g) {
    double delta = y[0] - y[1], s_d = sin(delta), c_d = cos(delta), m12 = m1 + m2;
    double a11 = m12 * l1 * l1, a12 = m2 * l1 * l2 * c_d, a22 = m2 * l2 * l2;
    double b1 = -m2 * l1 * l2 * y[3] * y[3] * s_d - m12 * g * l1 * sin(y[0]);
    double b2 = m2 * l1 * l2 * y[2] * y[2] * s_d - m2 * g * l2 * sin(y[1]);
    double det = a11 * a22 - a12 * a12;
    d[0] = y[2];
    d[1] = y[3];
    d[2] = (b1 * a22 - a12 * b2) / det;
    d[3] = (a11 * b2 - a12 * b1) / det;
}

/* classic RK4 with the batch integrator's operation order; Y laid out like the NumPy batch: 4 rows of n */
void rk4_batch(double *Y, long n, long steps, double h,
               double m1, double m2, double l1, double l2, double g) {
    for (long i = 0; i < n; i++) {
        double y[4] = {Y[i], Y[n + i], Y[2 * n + i], Y[3 * n + i]};
        double k1[4], k2[4], k3[4], k4[4], tmp[4];
        for (long s = 0; s < steps; s++) {
            field(y, k1, m1, m2, l1, l2, g);
            for (int c = 0; c < 4; c++) tmp[c] = y[c] + (0.5 * h) * k1[c];
            field(tmp, k2, m1, m2, l1, l2, g);
            for (int c = 0; c < 4; c++) tmp[c] = y[c] + (0.5 * h) * k2[c];
            field(tmp, k3, m1, m2, l1, l2, g);
            for (int c = 0; c < 4; c++) tmp[c] = y[c] + h * k3[c];
            field(tmp, k4, m1, m2, l1, l2, g);
            for (int c = 0; c < 4; c++)
                y[c] = y[c] + (h * (1.0 / 6.0)) * k1[c] + (h * (1.0 / 3.0)) * k2[c]
                       + (h * (1.0 / 3.0)) * k3[c] + (h * (1.0 / 6.0)) * k4[c];
        }
        Y[i] = y[0]; Y[n + i] = y[1]; Y[2 * n + i] = y[2]; Y[3 * n + i] = y[3];
    }
}
"""
C_FLAGS = ["-O2", "-shared", "-fPIC"]


def compile_c(folder: Path) -> ctypes.CDLL:
    """Compile :data:`C_SOURCE` with the system ``cc`` and load it."""
    compiler = shutil.which("cc")
    if compiler is None:
        raise SystemExit("no C compiler 'cc' on PATH")
    source, library = folder / "rk4.c", folder / "rk4.so"
    source.write_text(C_SOURCE)
    subprocess.run([compiler, *C_FLAGS, "-o", str(library), str(source), "-lm"], check=True)
    lib = ctypes.CDLL(str(library))
    lib.rk4_batch.argtypes = [ctypes.c_void_p, ctypes.c_long, ctypes.c_long] + [ctypes.c_double] * 6
    lib.rk4_batch.restype = None
    return lib


def run_numpy(y0: np.ndarray, steps: int, h: float, params: PendulumParameters) -> tuple[np.ndarray, float]:
    """The batch integrator on ``y0``: final states and CPU seconds."""
    field = pendulum_field(params)
    y = y0.copy()
    start = time.process_time()
    for n in range(steps):
        y = rk4_step(field, n * h, y, h)
    return y, time.process_time() - start


def run_c(lib: ctypes.CDLL, y0: np.ndarray, steps: int, h: float, params: PendulumParameters):
    """The C loop on ``y0``: final states and CPU seconds."""
    y = np.ascontiguousarray(y0.copy())
    p = params
    start = time.process_time()
    lib.rk4_batch(y.ctypes.data, y.shape[1], steps, h, p.m1, p.m2, p.l1, p.l2, p.g)
    return y, time.process_time() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--batch", type=int, default=10_000, help="trajectories per batch")
    parser.add_argument("--steps", type=int, default=500, help="RK4 steps of 1 ms per run")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--flip-map", type=int, default=0, metavar="N", help="also time an N x N flip map, 10 s")
    args = parser.parse_args()
    params, h = PendulumParameters(), 1e-3
    rng = np.random.default_rng(2024)
    y0 = initial_states(rng.uniform(-np.pi, np.pi, args.batch), rng.uniform(-np.pi, np.pi, args.batch))
    work = args.batch * args.steps
    with tempfile.TemporaryDirectory(prefix="batch-vs-c-") as folder:
        lib = compile_c(Path(folder))
        numpy_runs = [run_numpy(y0, args.steps, h, params) for _ in range(args.repeats)]
        c_runs = [run_c(lib, y0, args.steps, h, params) for _ in range(args.repeats)]
    numpy_rate = work / statistics.median(t for _, t in numpy_runs)
    c_rate = work / statistics.median(t for _, t in c_runs)
    difference = float(np.max(np.abs(numpy_runs[0][0] - c_runs[0][0])))
    print(
        f"batch of {args.batch} trajectories, {args.steps} RK4 steps of {h * 1e3:g} ms, median of {args.repeats} runs"
    )
    print(f"  NumPy batch integrator : {numpy_rate / 1e6:8.2f} M trajectory-steps/s")
    print(f"  C loop (cc {C_FLAGS[0]})        : {c_rate / 1e6:8.2f} M trajectory-steps/s")
    print(f"  ratio C / NumPy        : {c_rate / numpy_rate:8.2f}  (target: <= 3)")
    print(f"  largest state difference after the run: {difference:.1e} (rad, rad/s)")
    if args.flip_map:
        fmap = flip_time_map(args.flip_map, args.flip_map, params, t_max=10.0, h=h, max_workers=None)
        n = args.flip_map
        print(f"flip map {n} x {n}, 10 s, h = 1 ms, {fmap.workers} processes: {fmap.wall_time:.1f} s wall")


if __name__ == "__main__":
    main()
