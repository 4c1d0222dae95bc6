"""Command line: ``double-pendulum build | run SCENARIO | list | variables``."""

from __future__ import annotations

import argparse
import importlib
import sys
import time
from pathlib import Path

from .fmu.build import DEFAULT_FMU_PATH, build_all


def _scenario_names() -> tuple[str, ...]:
    from .scenarios import SCENARIOS

    return SCENARIOS


def _load_scenario(name: str):
    if name not in _scenario_names():
        raise SystemExit(f"unknown scenario {name!r}; available: {', '.join(_scenario_names())}")
    return importlib.import_module(f"double_pendulum.scenarios.{name}")


def cmd_build(args: argparse.Namespace) -> int:
    for path in build_all(args.output):
        print(f"built {path}")
    return 0


def cmd_list(args: argparse.Namespace) -> int:
    for name in _scenario_names():
        print(f"{name:24s} {_load_scenario(name).DESCRIPTION}")
    return 0


def cmd_variables(args: argparse.Namespace) -> int:
    """Print the FMU's variables as the Markdown table used in the README."""
    from .component.variables import fmu_variables

    print("| name | causality | type | unit | start | description |")
    print("|---|---|---|---|---|---|")
    for v in fmu_variables():
        text = v.description.rsplit(" [", 1)[0] if v.unit else v.description
        start = "" if v.start is None else v.start
        print(f"| `{v.name}` | {v.causality} | {v.fmi_type} | {v.unit or '-'} | {start} | {text} |")
    return 0


def cmd_run(args: argparse.Namespace) -> int:
    from .fmu.runner import FmuRunner, ensure_fmu

    names = _scenario_names() if args.scenario == "all" else (args.scenario,)
    modules = [_load_scenario(n) for n in names]
    fmu = ensure_fmu(args.fmu, rebuild=args.rebuild)
    failed = []
    with FmuRunner(fmu) as runner:
        for name, module in zip(names, modules):
            out_dir = Path(args.out) / name
            out_dir.mkdir(parents=True, exist_ok=True)
            start = time.perf_counter()
            try:
                module.run(runner, out_dir, quick=args.quick)
            except Exception as error:  # report, keep what was written, go on with the next
                failed.append(name)
                print(f"{name}: FAILED: {error}", file=sys.stderr)
                continue
            print(f"{name}: wrote {out_dir} in {time.perf_counter() - start:.1f} s")
    return 1 if failed else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="double-pendulum", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)

    p_build = sub.add_parser("build", help="build DoublePendulum.fmu and, next to it, Suspension.fmu")
    p_build.add_argument("-o", "--output", default=str(DEFAULT_FMU_PATH), help="DoublePendulum FMU path or folder")
    p_build.set_defaults(func=cmd_build)

    p_run = sub.add_parser("run", help="run a scenario (or 'all') through the FMU with fmpy")
    p_run.add_argument("scenario", help="scenario name, or 'all'")
    p_run.add_argument("--out", default="results", help="output folder (default: results/)")
    p_run.add_argument("--fmu", default=str(DEFAULT_FMU_PATH), help="FMU to use; built if missing or stale")
    p_run.add_argument("--rebuild", action="store_true", help="rebuild the FMU first")
    p_run.add_argument("--quick", action="store_true", help="short runs, for smoke tests")
    p_run.set_defaults(func=cmd_run)

    p_list = sub.add_parser("list", help="list the scenarios")
    p_list.set_defaults(func=cmd_list)

    p_vars = sub.add_parser("variables", help="print the FMU's variables (Markdown table)")
    p_vars.set_defaults(func=cmd_variables)

    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    raise SystemExit(main())


def entry() -> None:
    """Console-script entry point: run :func:`main` and leave without interpreter teardown.

    pythonfmu (<= 0.7.0, upstream issue NTNU-IHB/PythonFMU#228) can corrupt the heap during
    process teardown after its FMUs were used, turning a finished run into an abort. All results
    are written by the time :func:`main` returns, so the process exits directly with its code.
    """
    import os

    code = main()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
