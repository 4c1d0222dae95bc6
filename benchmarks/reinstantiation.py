"""Re-instantiation cost and memory of FMUs in one fmpy process, side by side, printed as ratios.

    python benchmarks/reinstantiation.py [FMU ...] [--cycles 200] [--host-objects 200000]

One cycle is what a sweep pays per case when it makes a new instance: load the binary (fmpy's
``FMU2Slave``), instantiate, set up, initialise, one 1 ms doStep, terminate, free (which unloads the
binary), from an already extracted folder. The process holds ``--host-objects`` small objects of its
own, as a real host does (the garbage collector walks them). Reported per FMU: the median time of a
cycle after a warm-up (the first instance imports the bundled code, which is not what a sweep
repeats), its ratio to an empty pythonfmu FMU built here (the timed cycles interleave the FMUs, so
machine noise hits them alike; compare the ratios), and the growth of the process's resident memory
per cycle over as many cycles of that FMU alone.
``build/DoublePendulum.fmu`` is measured if no FMU is given.
"""

from __future__ import annotations

import argparse
import gc
import statistics
import sys
import tempfile
import time
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmu_performance import build_empty_fmu

WARM_UP = 5


def rss_kib() -> int:
    """The process's resident memory [KiB]."""
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * 4


class Cycler:
    """One FMU, extracted once, run through full instantiate/free cycles."""

    def __init__(self, fmu: Path, folder: Path) -> None:
        self.fmu = fmu
        self.description = read_model_description(str(fmu))
        self.unzipdir = extract(str(fmu), unzipdir=str(folder))
        self.times: list[float] = []
        self.growth = 0.0  # resident memory per cycle [KiB]

    def cycle(self) -> float:
        md = self.description
        start = time.perf_counter()
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=self.unzipdir, modelIdentifier=md.coSimulation.modelIdentifier,
                        instanceName="cycle")
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=1e-3)
        fmu.terminate()
        fmu.freeInstance()
        return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmus", nargs="*", type=Path)
    parser.add_argument("--cycles", type=int, default=200)
    parser.add_argument("--host-objects", type=int, default=200_000)
    args = parser.parse_args()
    fmus = args.fmus or [Path("build/DoublePendulum.fmu")]
    host = [{"k": k} for k in range(args.host_objects)]  # the host's own objects
    with tempfile.TemporaryDirectory() as tmp:
        empty = build_empty_fmu(Path(tmp))
        cyclers = [Cycler(fmu, Path(tmp) / f"fmu{k}") for k, fmu in enumerate([empty, *fmus])]
        for cycler in cyclers:
            for _ in range(WARM_UP):
                cycler.cycle()
        for _ in range(args.cycles):  # time: interleaved
            for cycler in cyclers:
                cycler.times.append(cycler.cycle())
        for cycler in cyclers:  # memory: one FMU after the other
            gc.collect()
            before = rss_kib()
            for _ in range(args.cycles):
                cycler.cycle()
            gc.collect()
            cycler.growth = (rss_kib() - before) / args.cycles
    reference = statistics.median(cyclers[0].times)
    print(f"{args.cycles} cycles each (load, instantiate, initialise, one 1 ms doStep, free), host holding "
          f"{len(host)} objects, Python {sys.version.split()[0]}")
    print(f"{'FMU':44s} {'cycle [ms]':>11s} {'ratio':>6s} {'memory [KiB/cycle]':>19s}")
    for cycler, name in zip(cyclers, ["empty pythonfmu FMU", *map(str, fmus)]):
        median = statistics.median(cycler.times)
        print(f"{name:44s} {median * 1e3:11.2f} {median / reference:6.2f} {cycler.growth:19.2f}")


if __name__ == "__main__":
    main()
