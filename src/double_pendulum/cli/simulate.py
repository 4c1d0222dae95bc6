"""``double-pendulum simulate``: a case of one's own through the FMU (:mod:`double_pendulum.case`)."""

from __future__ import annotations

import argparse
import math
import sys

from .common import PROG, CliError, positive, private_tempdir, writable_folder
from .fmus import FmuChoice, add_fmu_options, choose_fmu, load_fmu


def check_fmi(args: argparse.Namespace, fmu: FmuChoice) -> None:
    """Check ``--fmi`` and ``--me`` against the FMU: a given FMU's FMI version is its own (``--fmi``, if given,
    must match it), and it must have the interface asked for (Model Exchange with ``--me``, else Co-Simulation);
    the project's FMU is FMI 2.0 co-simulation, or with ``--fmi 3`` the FMI 3.0 one with both. A CliError if not."""
    if not fmu.given:
        if args.me and args.fmi != "3":
            raise CliError("--me needs --fmi 3: the project's FMI 2.0 FMU is co-simulation only")
        return
    md = fmu.description
    version = md.fmiVersion.split(".")[0]
    if args.fmi is not None and args.fmi != version:
        raise CliError(f"--fmi {args.fmi} does not match {fmu.path}: it is an FMI {md.fmiVersion} FMU (with --fmu "
                       "the FMU's own version is used: leave --fmi out)")
    if args.me and md.modelExchange is None:
        raise CliError(f"--me needs an FMU with Model Exchange: {fmu.path} (FMI {md.fmiVersion}) is co-simulation "
                       "only")
    if not args.me and md.coSimulation is None:
        raise CliError(f"{fmu.path} (FMI {md.fmiVersion}) is model exchange only: pass --me")


def check_start_angles(settings: list[str]) -> None:
    """Check the start angles among ``--set NAME=VALUE`` by the one rule the FMU and the app apply
    (:func:`~double_pendulum.model.parameters.check_start_angle`), before anything is built or written; a CliError
    naming the angle and its value if one breaks it. A text that is no number is left to the --set checks."""
    from ..model.parameters import START_ANGLES, ParameterError, check_start_angle

    for setting in settings:
        name, _, text = setting.partition("=")
        if name.strip() in START_ANGLES:
            try:
                value = float(text)
            except ValueError:
                continue
            try:
                check_start_angle(name.strip(), value)
            except ParameterError as error:
                raise CliError(f"--set {setting.strip()}: {error}") from None


def cmd_simulate(args: argparse.Namespace) -> int:
    """Run a case of one's own through the FMU (:mod:`double_pendulum.case`): CSV, figure, animation, summary."""
    from fmpy import read_model_description

    from ..case import Case, Estimate, TooLong, run_case, start_state_words
    from ..fmu.running.start_values import StartValueError, parse_start_values

    chosen = choose_fmu(args)  # before --out is made: a given FMU that is missing or unusable changes nothing
    check_fmi(args, chosen)
    check_start_angles(args.set)
    stop, step = positive("--stop", args.stop), positive("--step", args.step)
    if step > stop:
        raise CliError(f"--step {step:g} s is longer than the run (--stop {stop:g} s)")
    max_wall = positive("--max-wall", args.max_wall)
    out = writable_folder(args.out)
    with private_tempdir():
        if chosen.given:
            fmu, md = chosen.path, chosen.description
        else:
            load_fmu(chosen, args.rebuild).close()  # builds the FMUs if they are missing or stale
            fmu = chosen.path if args.fmi != "3" else chosen.folder / "fmi3" / chosen.path.name
            md = read_model_description(str(fmu))
        try:
            values = parse_start_values(args.set, md)
        except StartValueError as error:
            raise CliError(str(error)) from None
        case = Case(fmu, values, stop, step, "ModelExchange" if args.me else "CoSimulation")
        print(f"simulating {case.words()} through {fmu} with fmpy ...", flush=True)

        def tell(estimate: Estimate) -> None:
            print(f"this run takes {estimate.words()}", flush=True)

        try:
            outcome = run_case(case, out, animate=not args.no_animation, max_wall_s=max_wall, on_estimate=tell)
        except TooLong as error:
            raise CliError(f"--stop {stop:g} s would take {error.estimate.words()}: more than --max-wall "
                           f"{max_wall:g} s; stopped after the first {error.estimate.probe_s:.2g} s of it, nothing "
                           f"written (to run it all: --max-wall {math.ceil(1.2 * error.estimate.total_wall_s)})"
                           ) from None
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
    p_sim.add_argument("--fmi", choices=("2", "3"), default=None,
                       help="FMI version of the project's FMU: 2 (the default), or 3 for fmi3/DoublePendulum.fmu in "
                       "the build folder; with --fmu the FMU's own version is used (a --fmi that differs is an error)")
    p_sim.add_argument("--me", action="store_true",
                       help="model exchange: fmpy integrates the FMU with its own solver (the project's FMU: with "
                       "--fmi 3; with --fmu: an FMU that has Model Exchange)")
    p_sim.add_argument("--out", default="results/simulate", help="output folder (default: results/simulate)")
    add_fmu_options(p_sim, "an FMU file of the double pendulum to run instead of the project's (FMI 2.0 or 3.0: "
                    "its own version, read from its modelDescription): read as it is, never built or written (an "
                    "error if it is missing or not usable)")
    p_sim.add_argument("--no-animation", action="store_true", help="write no simulation.gif")
    p_sim.add_argument("--max-wall", type=float, default=3600.0, metavar="SECONDS",
                       help="the longest the run may take [s of wall time] (default: 3600): the first 0.5 s of "
                       "simulated time (and 1 s of wall time) estimate the whole run's time, printed where the run "
                       "goes on beyond them, and a run estimated to take longer stops there, writing nothing")
    p_sim.set_defaults(func=cmd_simulate)
