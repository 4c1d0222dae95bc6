"""Size, file count and start-up time of FMUs, side by side in one run.

    python benchmarks/fmu_footprint.py OLD.fmu NEW.fmu [--repeats 15]

Start-up is instantiate .. exitInitializationMode in a fresh process (CPU time, median over
repeats, the FMUs interleaved so machine noise hits both alike); the first FMU is the reference
of the ratios.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import zipfile
from pathlib import Path

from fmpy import extract
from fmu_performance import startup_time


def footprint(fmu: Path) -> tuple[int, int, int]:
    """Return (FMU size in bytes, files in the archive, Python sources under resources/)."""
    with zipfile.ZipFile(fmu) as archive:
        names = archive.namelist()
    sources = sum(1 for n in names if n.startswith("resources/") and n.endswith(".py"))
    return fmu.stat().st_size, len(names), sources


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmus", nargs="+", type=Path)
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        unzipped = {fmu: extract(str(fmu), unzipdir=str(Path(tmp) / str(i))) for i, fmu in enumerate(args.fmus)}
        times: dict[Path, list[float]] = {fmu: [] for fmu in args.fmus}
        for _ in range(args.repeats):
            for fmu in args.fmus:
                times[fmu].append(startup_time(fmu, unzipped[fmu], 1)[0])
    reference = statistics.median(times[args.fmus[0]])
    print(f"{'FMU':40s} {'size [kB]':>10s} {'files':>6s} {'.py':>5s} {'start-up [ms]':>14s} {'ratio':>6s}")
    for fmu in args.fmus:
        size, files, sources = footprint(fmu)
        median = statistics.median(times[fmu])
        print(f"{str(fmu):40s} {size / 1024:10.0f} {files:6d} {sources:5d} {median * 1e3:14.1f}"
              f" {median / reference:6.2f}")


if __name__ == "__main__":
    main()
