"""Size, file count, start-up time and the cost of a plain ``simulate_fmu`` call of FMUs, side by side in one run.

    python benchmarks/fmu_footprint.py OLD.fmu NEW.fmu [--repeats 15] [--c-host] [--simulate]

Start-up is loading the binary, instantiate .. the first 1 ms doStep, in a fresh process (CPU time,
median over repeats, the FMUs interleaved so machine noise hits both alike); the first FMU is the
reference of the ratios. ``--c-host`` also times each FMU in the C host of the tests
(``tests/c_host/fmi2_host.c``, compiled here), started with a bare environment: an FMU whose Linux
binary is pythonfmu's own (no loader, e.g. one built before the loader) gets what it needs there,
``LD_PRELOAD`` of libpython and ``PYTHONHOME``, so both can be compared; a self-contained FMU starts the CPython
it carries there, a lean one the CPython it was built with. ``--simulate`` also times
``fmpy.simulate_fmu("X.fmu", ...)`` on the work-precision case (a chaotic start over 3 s, dop853 at rtol 1e-12,
a row every 10 ms; wall time, median, in this process after one warm-up call), which extracts the whole FMU anew
every call, and that extraction alone (``fmpy.extract`` and removing the folder).
"""

from __future__ import annotations

import argparse
import io
import shutil
import statistics
import subprocess
import sys
import sysconfig
import tempfile
import time
import zipfile
from pathlib import Path

from fmpy import extract, read_model_description, simulate_fmu
from fmu_performance import startup_time

from double_pendulum.fmu.build import loader

HOST_SOURCE = Path(__file__).resolve().parents[1] / "tests" / "c_host" / "fmi2_host.c"


def footprint(fmu: Path) -> tuple[int, int, int]:
    """Return (FMU size in bytes, files in the archive, Python sources under resources/, those in its code archive
    included)."""
    with zipfile.ZipFile(fmu) as archive:
        names = archive.namelist()
        sources = sum(1 for n in names if n.startswith("resources/") and n.endswith(".py"))
        if "resources/python_code.zip" in names:
            with zipfile.ZipFile(io.BytesIO(archive.read("resources/python_code.zip"))) as code:
                sources += sum(1 for n in code.namelist() if n.endswith(".py"))
    return fmu.stat().st_size, len(names), sources


def c_host_startup(host: Path, fmu: Path, unzipdir: str, home: str) -> float:
    """CPU seconds from loading the FMU's binary to the end of its first doStep, in the C host."""
    md = read_model_description(str(fmu))
    env = {"PATH": "/usr/bin:/bin", "HOME": home}
    if not (Path(unzipdir) / "resources" / "identity.cfg").is_file():  # pythonfmu's own binary, not the loader
        libdir, soname = sysconfig.get_config_var("LIBDIR"), sysconfig.get_config_var("INSTSONAME")
        env |= {"LD_PRELOAD": f"{libdir}/{soname}", "PYTHONHOME": sys.base_prefix}
    command = [str(host), unzipdir, md.coSimulation.modelIdentifier, md.guid, "1", "0.001"]
    out = subprocess.run(command, capture_output=True, text=True, env=env, check=True).stdout
    return float(next(line.split()[1] for line in out.splitlines() if line.startswith("startup-cpu-seconds")))


WORK_PRECISION = {"phi1_0": 2.0, "phi2_0": 2.0, "solver": "dop853", "rtol": 1e-12}  # 3 s, a row every 10 ms


def simulate_time(fmu: Path) -> float:
    """Wall seconds of one ``simulate_fmu`` call from the .fmu file on the work-precision case."""
    start = time.perf_counter()
    simulate_fmu(str(fmu), stop_time=3.0, output_interval=0.01, start_values=WORK_PRECISION, output=["phi1"])
    return time.perf_counter() - start


def extract_time(fmu: Path) -> float:
    """Wall seconds of fmpy's extraction of the FMU into a new folder and its removal."""
    start = time.perf_counter()
    shutil.rmtree(extract(str(fmu)))
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmus", nargs="+", type=Path)
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--c-host", action="store_true", help="also time each FMU in the C host (bare environment)")
    parser.add_argument("--simulate", action="store_true", help="also time simulate_fmu from the .fmu file and the "
                        "extraction alone")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        unzipped = {fmu: extract(str(fmu), unzipdir=str(Path(tmp) / str(i))) for i, fmu in enumerate(args.fmus)}
        host = None
        if args.c_host:
            host = Path(tmp) / "fmi2_host"
            subprocess.run([*loader.c_compiler(), "-O2", f"-I{loader.fmi_headers()}", "-o", str(host),
                            str(HOST_SOURCE), "-ldl"], check=True)
        times: dict[Path, list[float]] = {fmu: [] for fmu in args.fmus}
        c_times: dict[Path, list[float]] = {fmu: [] for fmu in args.fmus}
        calls: dict[Path, list[float]] = {fmu: [] for fmu in args.fmus}
        unpacks: dict[Path, list[float]] = {fmu: [] for fmu in args.fmus}
        for fmu in args.fmus if args.simulate else ():
            simulate_time(fmu)  # the warm-up: fmpy's imports, the FMU's code imported once in this process
        for _ in range(args.repeats):
            for fmu in args.fmus:
                times[fmu].append(startup_time(fmu, unzipped[fmu], 1)[0])
                if host:
                    c_times[fmu].append(c_host_startup(host, fmu, unzipped[fmu], tmp))
                if args.simulate:
                    calls[fmu].append(simulate_time(fmu))
                    unpacks[fmu].append(extract_time(fmu))
    reference = statistics.median(times[args.fmus[0]])
    c_reference = statistics.median(c_times[args.fmus[0]]) if host else 1.0
    call_reference = statistics.median(calls[args.fmus[0]]) if args.simulate else 1.0
    header = f"{'FMU':40s} {'size [kB]':>10s} {'files':>6s} {'.py':>5s} {'fmpy start-up [ms]':>19s} {'ratio':>6s}"
    print(header + (f" {'C-host start-up [ms]':>21s} {'ratio':>6s}" if host else "")
          + (f" {'simulate_fmu [ms]':>18s} {'ratio':>6s} {'extract [ms]':>13s}" if args.simulate else ""))
    for fmu in args.fmus:
        size, files, sources = footprint(fmu)
        median = statistics.median(times[fmu])
        line = (f"{str(fmu):40s} {size / 1024:10.0f} {files:6d} {sources:5d} {median * 1e3:19.1f}"
                f" {median / reference:6.2f}")
        if host:
            c_median = statistics.median(c_times[fmu])
            line += f" {c_median * 1e3:21.1f} {c_median / c_reference:6.2f}"
        if args.simulate:
            call = statistics.median(calls[fmu])
            line += f" {call * 1e3:18.1f} {call / call_reference:6.2f} {statistics.median(unpacks[fmu]) * 1e3:13.1f}"
        print(line)


if __name__ == "__main__":
    main()
