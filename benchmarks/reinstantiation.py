"""Re-instantiation cost and memory of FMUs in one fmpy process, side by side, printed as ratios.

    python benchmarks/reinstantiation.py [FMU ...] [--cycles 200] [--host-objects 200000]

One cycle is what a sweep pays per case when it makes a new instance: load the binary (fmpy's
``FMU2Slave``), instantiate, set up, initialise, one 1 ms doStep, terminate, free (which unloads the
binary), from an already extracted folder. The process holds ``--host-objects`` small objects of its
own, as a real host does (the garbage collector walks them). Reported per FMU: the median time of a
cycle after a warm-up (the first instance imports the bundled code, which is not what a sweep
repeats), its ratio to an empty pythonfmu FMU built here, and the growth of the process's resident
memory per cycle. Each FMU runs in a process of its own (what one FMU leaves behind must not slow
or grow another), ``--repeats`` times, the FMUs' processes interleaved so that machine noise hits
them alike: compare the ratios.
``build/DoublePendulum.fmu`` is measured if no FMU is given.
"""

from __future__ import annotations

import argparse
import gc
import json
import statistics
import subprocess
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


def one_fmu(fmu: Path, cycles: int, host_objects: int) -> dict:
    """This process: warm up, then time ``cycles`` cycles of ``fmu`` and measure the memory they add."""
    host = [{"k": k} for k in range(host_objects)]  # the host's own objects
    with tempfile.TemporaryDirectory() as tmp:
        cycler = Cycler(fmu, Path(tmp) / "fmu")
        for _ in range(WARM_UP):
            cycler.cycle()
        gc.collect()
        before = rss_kib()
        times = [cycler.cycle() for _ in range(cycles)]
        gc.collect()
        grown = rss_kib() - before
    return {"cycle_s": statistics.median(times), "kib_per_cycle": grown / cycles, "host_objects": len(host)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmus", nargs="*", type=Path)
    parser.add_argument("--cycles", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--host-objects", type=int, default=200_000)
    parser.add_argument("--one", action="store_true", help=argparse.SUPPRESS)  # a child: one FMU, JSON out
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one_fmu(args.fmus[0], args.cycles, args.host_objects)))
        return
    fmus = args.fmus or [Path("build/DoublePendulum.fmu")]
    with tempfile.TemporaryDirectory() as tmp:
        every = [build_empty_fmu(Path(tmp)), *fmus]
        results: dict[Path, list[dict]] = {fmu: [] for fmu in every}
        for _ in range(args.repeats):
            for fmu in every:
                command = [sys.executable, __file__, "--one", str(fmu), "--cycles", str(args.cycles),
                           "--host-objects", str(args.host_objects)]
                done = subprocess.run(command, capture_output=True, text=True, check=True)
                results[fmu].append(json.loads(done.stdout.strip().splitlines()[-1]))
        reference = statistics.median(r["cycle_s"] for r in results[every[0]])
        print(f"{args.cycles} cycles per process (load, instantiate, initialise, one 1 ms doStep, free), "
              f"{args.repeats} processes per FMU, each holding {args.host_objects} objects, "
              f"Python {sys.version.split()[0]}")
        print(f"{'FMU':44s} {'cycle [ms]':>11s} {'ratio':>6s} {'memory [KiB/cycle]':>19s}")
        for fmu, name in zip(every, ["empty pythonfmu FMU", *map(str, fmus)]):
            median = statistics.median(r["cycle_s"] for r in results[fmu])
            growth = statistics.median(r["kib_per_cycle"] for r in results[fmu])
            print(f"{name:44s} {median * 1e3:11.2f} {median / reference:6.2f} {growth:19.2f}")


if __name__ == "__main__":
    main()
