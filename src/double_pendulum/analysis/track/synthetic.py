"""Camera tracks made by the model: a known pendulum simulated (the FMU's own component in this process, or a given
runner such as the FMU through fmpy), sampled at a camera's frame rate, moved to a pivot and given position noise,
written in the CSV form a user's record takes (:mod:`.user_track`). The tests check that the analysis recovers what
made the track; ``examples/my_track.csv`` and ``examples/my_pendulum.toml`` are made by :func:`main`::

    python -m double_pendulum.analysis.track.synthetic examples/my_track.csv examples/my_pendulum.toml

Lengths in m, times in s, angles in rad.
"""

from __future__ import annotations

import argparse
import csv
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .user_track import DEFAULT_COLUMNS


@dataclass(frozen=True)
class MadeTrack:
    """What a synthetic track is made of: the pendulum (FMU start values: masses, lengths, rods, losses), the start
    state, the pivot's place in the camera's coordinates [m], the frame rate [1/s], the duration [s], the position
    noise [m] (standard deviation of each coordinate) and the noise's random seed."""

    pendulum: Mapping[str, Any]
    start: tuple[float, float, float, float] = (1.2, -0.8, 0.0, 0.0)
    pivot: tuple[float, float] = (0.12, 0.45)
    fps: float = 29.97
    duration_s: float = 20.0
    noise_m: float = 1e-3
    seed: int = 1
    settings: Mapping[str, Any] = field(default_factory=lambda: {"solver": "dop853", "rtol": 1e-9, "atol": 1e-11})

    def run(self, runner: Any = None, outputs: Sequence[str] = ("x1", "y1", "x2", "y2", "E_pendulum")) -> np.ndarray:
        """The simulation on the frame grid: a structured array of ``time`` and ``outputs``."""
        from ...fmu.masters.simulate import simulate  # noqa: PLC0415 - the in-process component

        names = ("phi1_0", "phi2_0", "omega1_0", "omega2_0")
        values = {**self.settings, **self.pendulum, **dict(zip(names, self.start))}
        dt = 1.0 / self.fps
        n = int(round(self.duration_s * self.fps)) + 1
        kwargs = dict(start_time=0.0, stop_time=(n - 1) * dt, output_interval=dt, outputs=tuple(outputs))
        result = runner.simulate(values, **kwargs) if runner is not None else simulate(values, **kwargs)
        return result[:n]

    def positions(self, runner: Any = None) -> np.ndarray:
        """Columns t, x1, y1, x2, y2 per frame: the simulated bobs [m] about the pivot plus the noise."""
        result = self.run(runner)
        n = len(result)
        dt = 1.0 / self.fps
        rng = np.random.default_rng(self.seed)
        t = np.arange(n) * dt
        out = [t]
        for k, name in enumerate(("x1", "y1", "x2", "y2")):
            offset = self.pivot[k % 2]
            out.append(np.asarray(result[name]) + offset + rng.normal(0.0, self.noise_m, n))
        return np.column_stack(out)


def write_track(path: str | Path, table: np.ndarray, *, columns: Mapping[str, str] = DEFAULT_COLUMNS,
                unit_per_m: float = 1.0, decimals: int = 4, frame_column: bool = False) -> Path:  # fmt: skip
    """Write ``table`` (t, x1, y1, x2, y2 per row) as a CSV file with the header ``columns`` (quantity -> name),
    positions times ``unit_per_m`` (100 for cm) with ``decimals`` decimals, time in s with 4."""
    path = Path(path)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow((["frame"] if frame_column else []) + [columns[k] for k in ("t", "x1", "y1", "x2", "y2")])
        for i, row in enumerate(table):
            cells = [f"{row[0]:.4f}", *(f"{v * unit_per_m:.{decimals}f}" for v in row[1:])]
            w.writerow(([str(i)] if frame_column else []) + cells)
    return path


def write_pendulum(path: str | Path, values: Mapping[str, float], comment: str = "") -> Path:
    """Write a pendulum file (TOML) with ``values`` (keys of :data:`.user_track.PENDULUM_FIELDS`)."""
    units = {"m1": "kg", "m2": "kg", "l1": "m", "l2": "m", "g": "m/s^2", "m_rod1": "kg", "m_rod2": "kg",
             "L_rod1": "m", "L_rod2": "m"}  # fmt: skip
    lines = [f"# {line}" for line in comment.splitlines()]
    lines += [f"{k} = {v!r}  # {units[k]}" for k, v in values.items()]
    Path(path).write_text("\n".join(lines) + "\n")
    return Path(path)


EXAMPLE = MadeTrack({"m1": 0.25, "m2": 0.20, "l1": 0.30, "l2": 0.22, "bearing_friction": True, "c_R1": 0.0,
                     "c_R2": 0.0, "b_v1": 4e-4, "b_v2": 4e-4}, start=(1.0, 0.4, 0.0, 0.0), duration_s=10.0)  # fmt: skip
"""The example record: bobs of 250 g and 200 g on rods of 30 cm and 22 cm with viscous joint damping 4e-4
N m s/rad, released from rest at (1.0, 0.4) rad, 10 s at 29.97 fps, 1 mm of noise."""


def main(argv: Sequence[str] | None = None) -> int:
    """Write the example's track and pendulum file (:data:`EXAMPLE`)."""
    parser = argparse.ArgumentParser(description="write a camera track made by the model, and its pendulum file")
    parser.add_argument("track", help="CSV file to write")
    parser.add_argument("pendulum", help="TOML file to write")
    args = parser.parse_args(argv)
    write_track(args.track, EXAMPLE.positions(), frame_column=True)
    p = EXAMPLE.pendulum
    write_pendulum(args.pendulum, {"m1": p["m1"], "m2": p["m2"]},
                   "The pendulum of examples/my_track.csv: the masses (required); the lengths are fitted from the "
                   "track\nwhere not given here (l1, l2 in m), rods optional (m_rod1, m_rod2 in kg, L_rod1, L_rod2 "
                   "in m).")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
