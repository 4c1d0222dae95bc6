"""The misuse probes of the torture hosts, each in a process of its own, for FMUs side by side.

    python benchmarks/probe_table.py OLD.fmu NEW.fmu [--fmi 2|3]

Compiles ``tests/c_host/fmi2_torture.c`` (or ``fmi3_torture.c``), takes the list of probes from the
last FMU given, and runs every probe alone with a bare environment (``env -i PATH=/usr/bin:/bin``)
against every FMU, so that a crash or a hang costs only that probe. Prints a Markdown table: the
status each FMU gave (0 OK, 1 Warning, 2 Discard, 3 Error, 4 Fatal; for fmiXInstantiate probes 0
means NULL, 1 an instance), "crash (SIGSEGV)" and the like, "hang" after 60 s, and whether the call
logged a line. What the standard asks is in ``tests/test_guard.py``.
"""

from __future__ import annotations

import argparse
import signal
import subprocess
import tempfile
from pathlib import Path

from fmpy import extract, read_model_description

from double_pendulum.fmu.build import loader

HOSTS = Path(__file__).resolve().parents[1] / "tests" / "c_host"
NAMES = ("phi1_0", "m1", "l1", "solver", "phi1", "pivot_ax", "air_drag", "fixed_step", "omega2_0")


def command(host: Path, folder: str, fmu: Path, version: int, *mode: str) -> list[str]:
    md = read_model_description(str(fmu))
    refs = {v.name: v.valueReference for v in md.modelVariables}
    identifier = (md.coSimulation or md.modelExchange).modelIdentifier
    token = md.guid if version == 2 else md.instantiationToken
    return [str(host), folder, identifier, token, *(f"{n}={refs[n]}" for n in NAMES if n in refs), *mode]


def outcome(cmd: list[str], home: str) -> str:
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, env={"PATH": "/usr/bin:/bin", "HOME": home},
                              timeout=60)
    except subprocess.TimeoutExpired:
        return "hang"
    if done.returncode < 0:
        return f"crash ({signal.Signals(-done.returncode).name})"
    lines = [line for line in done.stdout.splitlines() if line.startswith("probe ")]
    if done.returncode != 0 or not lines:
        return f"exit {done.returncode}"
    logged = any(line.startswith("  log ") for line in done.stdout.splitlines())
    return lines[0].split()[2] + (", logged" if logged else "")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmus", nargs="+", type=Path)
    parser.add_argument("--fmi", type=int, choices=(2, 3), default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        host = Path(tmp) / "torture"
        subprocess.run([*loader.c_compiler(), "-O2", f"-I{loader.fmi_headers()}", "-o", str(host),
                        str(HOSTS / f"fmi{args.fmi}_torture.c"), "-ldl", "-lpthread", "-lm"], check=True)
        folders = {fmu: extract(str(fmu), str(Path(tmp) / f"fmu{k}")) for k, fmu in enumerate(args.fmus)}
        listing = subprocess.run(command(host, folders[args.fmus[-1]], args.fmus[-1], args.fmi, "probes"),
                                 capture_output=True, text=True, env={"PATH": "/usr/bin:/bin", "HOME": tmp})
        probes = [line.split()[1] for line in listing.stdout.splitlines() if line.startswith("probe ")]
        print("| probe | " + " | ".join(str(fmu) for fmu in args.fmus) + " |")
        print("|---|" + "---|" * len(args.fmus))
        for probe in probes:
            cells = [outcome(command(host, folders[fmu], fmu, args.fmi, "probes", probe), tmp) for fmu in args.fmus]
            print(f"| {probe} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
