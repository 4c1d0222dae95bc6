"""What a sweep pays per case, and its memory, with the FMU's instance reused or made anew each case.

    python benchmarks/sweep_cost.py [--fmu build/DoublePendulum.fmu] [--reference OLD.fmu] [--cases 1000]

Each case is a 0.1 s run (10 steps of 10 ms, start value phi1_0 drawn per case) through
:class:`double_pendulum.fmu.running.runner.FmuRunner`, as :func:`double_pendulum.analysis.sweep.run_sweep`
runs it in a worker. Measured, each in a fresh process: the FMU with its instance reused (reset
between cases, the default), the same FMU with a new instance per case (``reuse_instance=False``, as
every case paid before), and optionally a reference FMU (an older build) with a new instance per
case. Reported: the median wall time per case (after 150 warm-up cases), its ratio to the first
line, and the growth of resident memory over ``--cases`` cases after the warm-up. Compare ratios.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import textwrap
from pathlib import Path

WORKER = textwrap.dedent("""
    import json, statistics, sys, time
    from double_pendulum.analysis.sweep import random_cases
    from double_pendulum.fmu.running.runner import FmuRunner

    fmu, reuse, n = sys.argv[1], sys.argv[2] == "1", int(sys.argv[3])
    def rss_kib():
        with open("/proc/self/statm") as statm:
            return int(statm.read().split()[1]) * 4
    cases = random_cases(n + 150, seed=11, uniform={"phi1_0": (0.5, 2.5)})
    times = []
    with FmuRunner(fmu, reuse_instance=reuse) as runner:
        for case in cases[:150]:
            runner.simulate(case, stop_time=0.1, output_interval=0.01)
        before = rss_kib()
        for case in cases[150:]:
            start = time.perf_counter()
            runner.simulate(case, stop_time=0.1, output_interval=0.01)
            times.append(time.perf_counter() - start)
        grown = rss_kib() - before
    print(json.dumps({"case_s": statistics.median(times), "grown_kib": grown}))
""")


def measure(fmu: Path, reuse: bool, cases: int) -> dict:
    done = subprocess.run([sys.executable, "-c", WORKER, str(fmu), "1" if reuse else "0", str(cases)],
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--fmu", type=Path, default=Path("build/DoublePendulum.fmu"))
    parser.add_argument("--reference", type=Path, help="an older build, run with a new instance per case")
    parser.add_argument("--cases", type=int, default=1000)
    args = parser.parse_args()
    runs = [(f"{args.fmu}, instance reused", args.fmu, True), (f"{args.fmu}, new instance per case", args.fmu, False)]
    if args.reference:
        runs.append((f"{args.reference}, new instance per case", args.reference, False))
    results = [(label, measure(fmu, reuse, args.cases)) for label, fmu, reuse in runs]
    first = results[0][1]["case_s"]
    print(f"{args.cases} cases of 0.1 s (10 steps) each, one process per line")
    print(f"{'run':64s} {'per case [ms]':>14s} {'ratio':>6s} {'memory [MB per 1000 cases]':>27s}")
    for label, result in results:
        per_1000 = result["grown_kib"] / 1024 * 1000 / args.cases
        print(f"{label:64s} {result['case_s'] * 1e3:14.2f} {result['case_s'] / first:6.2f} {per_1000:27.2f}")


if __name__ == "__main__":
    main()
