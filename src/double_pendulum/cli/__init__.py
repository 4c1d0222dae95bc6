"""Command line: build the FMU, run scenarios through it, list them, print the FMU's variables.

One module a command or a group of them (``build`` and ``cross-check``: :mod:`.build`; ``run``: :mod:`.run`;
``simulate``: :mod:`.simulate`; ``list`` and ``variables``: :mod:`.info`), each adding its own part of the
parser; what they share is in :mod:`.common` (errors, the output folder, the temporary folder), :mod:`.fmus`
(the FMUs a command uses) and :mod:`.catalogue` (the scenarios by name). This module puts the parser together
and runs a command.

Misuse and failures end with one line on stderr and a non-zero exit code, never a traceback:
2 for a bad command line or unusable files, 1 if a scenario failed, 130 on Ctrl-C, 141 when the reader of
the output went away (``double-pendulum variables | head -1``).

A run keeps its temporary files (the FMUs fmpy extracts, in this process, its workers and its child
processes) in a folder of its own under ``$TMPDIR`` and removes it when it ends, however it ends
(:func:`~double_pendulum.cli.common.private_tempdir`).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys

from .. import __version__
from ..app.server import add_app_command
from ..runs.interrupts import ends_the_process, handling_interrupts
from .build import add_build_parser, add_cross_check_parser
from .common import PROG, CliError
from .info import add_list_parser, add_variables_parser
from .run import add_run_parser
from .simulate import add_simulate_parser

COMMANDS = (add_build_parser, add_run_parser, add_cross_check_parser, add_simulate_parser, add_list_parser,
            add_variables_parser, add_app_command)
"""Each command's part of the parser, in the order ``--help`` lists the commands."""


def build_parser() -> argparse.ArgumentParser:
    """The argument parser: plain-text help, the scenarios listed under ``run --help``."""
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="A planar double pendulum as an FMI 2.0 co-simulation FMU (and an FMI 3.0 Model Exchange "
        "and Co-Simulation FMU): build them, run the scenarios through fmpy, print the variables.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    parser.command_parsers = sub.choices  # type: ignore[attr-defined]  # main() reports unknown options by command
    for add_command in COMMANDS:
        add_command(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Parse ``argv`` and run the command; return the exit code (errors as one line on stderr)."""
    parser = build_parser()
    args, unknown = parser.parse_known_args(argv)
    if unknown:  # the command's own usage, not the top level's: the options that command takes
        parser.command_parsers[args.command].error(f"unrecognized arguments: {' '.join(unknown)}")
    try:
        with handling_interrupts():
            return args.func(args)
    except CliError as error:
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as interrupt:  # simulate's says what it kept (double_pendulum.case.Interrupted)
        kept = str(interrupt) or ("nothing was written" if args.command == "simulate"
                                  else "finished scenarios are kept, unfinished ones are discarded")
        print(f"{PROG}: interrupted; {kept}", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader of stdout went away: say nothing more there
        _stdout_to_devnull()
        return 141


def _stdout_to_devnull() -> None:
    """Point stdout at /dev/null, so that flushing what is left of it cannot fail again."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    with contextlib.suppress(OSError, ValueError):
        os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)


def entry() -> None:
    """Console-script entry point: run :func:`main` and exit with its code, through the interpreter's
    ordinary teardown (the FMUs' binary is safe through exit: scripts/check_memory.sh). The process ends with the
    run, so a Ctrl-C after an interrupted run's clean-up is ignored through its exit (:func:`ends_the_process`)."""
    ends_the_process()
    try:
        code = main()
    except KeyboardInterrupt:  # Ctrl-C while parsing or importing
        print(f"{PROG}: interrupted", file=sys.stderr)
        code = 130
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        _stdout_to_devnull()
        code = code or 141
    sys.stderr.flush()
    raise SystemExit(code)
