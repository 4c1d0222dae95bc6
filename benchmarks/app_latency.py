"""The app's run path against a bare ``fmpy.simulate_fmu`` call, for a 20 s case (issue 37: within about twice).

The app's path: a run started by :class:`double_pendulum.app.worker.Runs` (a process from its fork server, a new
FMU instance through ``FmuRunner``, every output recorded) and asked after as the browser tab asks, every
:data:`~double_pendulum.app.layout.POLL_MS` ms, until its answer is in. The bare call: ``simulate_fmu`` with the
same start values and output interval, the FMU's default outputs. Printed as a ratio of the medians of
``--repeats`` runs each, measured in one process, alternating (timings only as ratios: the machine is shared).

    python benchmarks/app_latency.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import statistics
import time

from double_pendulum.app.form import OUTPUT_INTERVAL_S, check_form, default_values
from double_pendulum.app.layout import POLL_MS
from double_pendulum.app.worker import Runs
from double_pendulum.fmu.running.runner import ensure_fmu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    from fmpy import simulate_fmu

    fmu = ensure_fmu().resolve()
    checked = check_form({**default_values(), "phi1_0": "2.0", "switches": ["air_drag"], "stop_time": "20"})
    runs = Runs(fmu)
    warm = runs.start("case", checked.start_values, 1.0, OUTPUT_INTERVAL_S)  # the fork server starts once
    while runs.poll(warm)[1] is None:
        time.sleep(0.05)
    app_s, bare_s = [], []
    try:
        for _ in range(args.repeats):
            start = time.perf_counter()
            simulate_fmu(str(fmu), start_values=checked.start_values, stop_time=checked.stop_time,
                         output_interval=OUTPUT_INTERVAL_S)
            bare_s.append(time.perf_counter() - start)
            start = time.perf_counter()
            run_id = runs.start("case", checked.start_values, checked.stop_time, OUTPUT_INTERVAL_S)
            while (polled := runs.poll(run_id)) is not None and polled[1] is None:
                time.sleep(POLL_MS / 1000)
            runs.collect(run_id)  # the tab's second request: the answer itself
            app_s.append(time.perf_counter() - start)
    finally:
        runs.close()
    ratio = statistics.median(app_s) / statistics.median(bare_s)
    print(f"20 s case (phi1_0 = 2 rad, air drag), {args.repeats} runs each: the app's run path takes "
          f"{ratio:.2f} times the bare simulate_fmu call (medians; the goal: about 2 or less)")


if __name__ == "__main__":
    main()
