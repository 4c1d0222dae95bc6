"""``double-pendulum simulate``: a case of one's own through the FMU (:mod:`double_pendulum.case`)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .common import PROG, CliError, positive, private_tempdir, writable_folder
from .fmus import default_fmu_path, load_fmu


def cmd_simulate(args: argparse.Namespace) -> int:
    """Run a case of one's own through the FMU (:mod:`double_pendulum.case`): CSV, figure, animation, summary."""
    from fmpy import read_model_description

    from ..case import Case, run_case, start_state_words
    from ..fmu.running.start_values import StartValueError, parse_start_values

    if args.me and args.fmi != "3":
        raise CliError("--me needs --fmi 3: the FMI 2.0 FMU is co-simulation only")
    stop, step = positive("--stop", args.stop), positive("--step", args.step)
    if step > stop:
        raise CliError(f"--step {step:g} s is longer than the run (--stop {stop:g} s)")
    out = writable_folder(args.out)
    fmu2 = Path(args.fmu) if args.fmu is not None else default_fmu_path(out)
    with private_tempdir():
        load_fmu(str(fmu2), args.rebuild).close()  # builds the FMUs if they are missing or stale
        fmu = fmu2 if args.fmi == "2" else fmu2.parent / "fmi3" / fmu2.name
        try:
            values = parse_start_values(args.set, read_model_description(str(fmu)))
        except StartValueError as error:
            raise CliError(str(error)) from None
        case = Case(fmu, values, stop, step, "ModelExchange" if args.me else "CoSimulation")
        print(f"simulating {case.words()} through {fmu} with fmpy ...", flush=True)
        outcome = run_case(case, out, animate=not args.no_animation)
    names = ", ".join(path.name for path in outcome.files)
    state = f"start state: {start_state_words(outcome.start_state)}"
    if outcome.message is not None:
        print(f"{PROG}: the FMU stopped the run at t = {outcome.summary.get('end_time_s', 0.0):g} s: "
              f"{outcome.message} (wrote {names} in {out}; {state})", file=sys.stderr)
        return 1
    print(f"wrote {names} in {out} ({outcome.summary['rows']} rows, {outcome.summary['wall_time_s']:.1f} s); "
          f"{state}")
    return 0


def add_simulate_parser(sub: argparse._SubParsersAction) -> None:
    """``simulate``'s options: the start values, the run's length and step, the FMU."""
    p_sim = sub.add_parser(
        "simulate",
        help="run a case of your own through the FMU with fmpy: CSV, figure, animation, summary",
        description="Run the FMU once with fmpy, from the start values you give, and write simulation.csv\n"
        "(units in the column names), simulation.png (angles, energies and their budget, the bobs' paths),\n"
        "simulation.gif (the pendulum in real time) and summary.json (with the fmpy call that gives the\n"
        "same numbers) into OUT.",
        epilog="example:\n  double-pendulum simulate --set phi1_0=2 --set air_drag=true --stop 20 --out my_case\n"
        "parameters and their units: double-pendulum variables",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p_sim.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                       help="start value of a parameter of the FMU, by its FMU name (repeatable)")
    p_sim.add_argument("--stop", type=float, default=10.0, metavar="SECONDS", help="stop time (default: 10)")
    p_sim.add_argument("--step", type=float, default=0.01, metavar="SECONDS",
                       help="output interval, also the co-simulation step (default: 0.01)")
    p_sim.add_argument("--fmi", choices=("2", "3"), default="2", help="FMI version of the FMU (default: 2)")
    p_sim.add_argument("--me", action="store_true",
                       help="model exchange (with --fmi 3): fmpy integrates the FMU with its own solver")
    p_sim.add_argument("--out", default="results/simulate", help="output folder (default: results/simulate)")
    p_sim.add_argument("--fmu", default=None,
                       help="the FMI 2.0 FMU, built with the others next to it if missing or older than the sources "
                       "(--fmi 3 uses fmi3/ next to it; default as for run)")
    p_sim.add_argument("--rebuild", action="store_true", help="rebuild the FMUs first")
    p_sim.add_argument("--no-animation", action="store_true", help="write no simulation.gif")
    p_sim.set_defaults(func=cmd_simulate)
