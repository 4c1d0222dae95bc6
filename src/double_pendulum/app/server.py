"""``double-pendulum app``: the local web app, served on 127.0.0.1 (:func:`main`; :func:`add_app_command` adds the
command to the ``double-pendulum`` command line).

The app is Dash (Plotly's web framework, the one FMPy's own web app uses): the page is Dash's components, the plots
Plotly's, the runs :mod:`.worker`'s processes. Dash and Plotly are the ``app`` extra (``pip install -e ".[app]"``);
without them the command says so in one line.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import signal
import sys
from pathlib import Path
from typing import Any

HOST = "127.0.0.1"
DEFAULT_PORT = 8050


def create_app(fmu: Path) -> tuple[Any, Any]:
    """The Dash app for the FMU file ``fmu`` and its :class:`~.worker.Runs` (close them when the server ends)."""
    from dash import Dash

    from .callbacks import register
    from .layout import page
    from .worker import Runs

    app = Dash(__name__, title="Double pendulum: the app")
    app.layout = page()
    runs = Runs(fmu)
    register(app, runs)
    return app, runs


def add_app_command(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``app`` to the command line's subcommands (``subparsers`` of :mod:`argparse`)."""
    parser = subparsers.add_parser("app", help="a local web app: change the pendulum and watch what happens",
                                   description="Serve the interactive app on 127.0.0.1 and print its address.")
    parser.add_argument("--port", type=int, default=DEFAULT_PORT, help=f"the port (default {DEFAULT_PORT})")
    parser.add_argument("--fmu", default=None, metavar="PATH",
                        help="an FMI 2.0 FMU file of the double pendulum to run instead of the project's: read as it "
                        "is, never built or written (an error if it is missing or not usable)")
    parser.add_argument("--build-dir", default=None, metavar="DIR",
                        help="the folder the project's DoublePendulum.fmu is built and kept in, built there when "
                        "missing or older than the sources (default: build/ in the project's folder, elsewhere a "
                        "temporary folder removed when the app ends); not with --fmu")
    parser.set_defaults(func=cmd_app)
    return parser


class AppError(Exception):
    """A problem with the app's command line the user can fix, said in one line."""


def app_fmu(args: argparse.Namespace, stack: contextlib.ExitStack) -> Path:
    """The FMU file the app runs (absolute): ``--fmu``'s, checked to be a usable FMU of the double pendulum and
    never built or written; else the project's ``DoublePendulum.fmu``, built when missing or stale in ``--build-dir``,
    in ``build/`` of the project's folder, or elsewhere in a temporary folder that ``stack`` removes when the app
    ends. Misuse and a build that fails are an :class:`AppError`."""
    import tempfile

    from ..fmu.build.fmi2 import DEFAULT_FMU_PATH, fmu_is_current
    from ..fmu.build.loader import LoaderUnavailable
    from ..fmu.running.choice import FmuPathError, is_project_folder, option_fmu
    from ..fmu.running.runner import ensure_fmu

    if args.fmu is not None:
        try:
            path, _ = option_fmu(args.fmu, args.build_dir, builds="FMU")
        except FmuPathError as error:
            raise AppError(str(error)) from None
        return path.resolve()
    note = "missing or older than the sources"
    if args.build_dir is not None:
        if not args.build_dir.strip():
            raise AppError("--build-dir needs a folder name (got an empty one)")
        folder = Path(args.build_dir)
    elif is_project_folder(Path.cwd()):
        folder = DEFAULT_FMU_PATH.parent
    else:
        folder = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="double-pendulum-app-")))
        note = "a temporary folder, removed when the app ends; --build-dir DIR keeps the FMU in DIR"
    fmu = folder / DEFAULT_FMU_PATH.name
    if not fmu_is_current(fmu):
        print(f"double-pendulum app: building the FMU in {folder} ({note}) ...", flush=True)
    try:
        return ensure_fmu(fmu).resolve()
    except LoaderUnavailable as error:
        raise AppError(f"cannot build the FMU: {error}") from None
    except OSError as error:
        raise AppError(f"cannot build the FMU in {folder}: {error.strerror or error} (pass --build-dir DIR to "
                       "build it elsewhere)") from None


def cmd_app(args: argparse.Namespace) -> int:
    """Serve the app until interrupted; 2 when Dash is not installed, the port is not usable or the FMU is not
    (:func:`app_fmu`)."""
    try:
        import dash  # noqa: F401
        import plotly  # noqa: F401
    except ImportError as error:
        print(f"double-pendulum app: needs Dash and Plotly ({error}): pip install -e \".[app]\"", file=sys.stderr)
        return 2
    if not 1 <= args.port <= 65535:
        print(f"double-pendulum app: --port {args.port} is no port (1 to 65535)", file=sys.stderr)
        return 2
    with contextlib.ExitStack() as stack:  # a temporary build folder (app_fmu) is removed when the app ends
        try:
            fmu = app_fmu(args, stack)
        except AppError as error:
            print(f"double-pendulum app: {error}", file=sys.stderr)
            return 2
        serve(fmu, args.port)
    print("double-pendulum app: ended", file=sys.stderr)
    return 0


def serve(fmu: Path, port: int) -> None:
    """Serve the app for the FMU file ``fmu`` on ``port`` until interrupted (Ctrl-C or SIGTERM), then end its runs."""
    app, runs = create_app(fmu)
    print(f"double-pendulum app: open http://{HOST}:{port}/ in a browser (Ctrl-C ends it)", flush=True)
    previous = signal.signal(signal.SIGTERM, _interrupt)  # `kill` ends it as Ctrl-C does: runs and files cleaned
    # The server's log of every request (a tab asks for its run's progress ten times a second) would bury the
    # address above; its warnings and errors still show.
    logging.getLogger("werkzeug").setLevel(logging.WARNING)
    try:
        app.run(host=HOST, port=port, debug=False)
    except KeyboardInterrupt:
        pass
    finally:
        runs.close()
        signal.signal(signal.SIGTERM, previous)


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt


def main(argv: list[str] | None = None) -> int:
    """``double-pendulum app [--port N] [--fmu PATH | --build-dir DIR]`` on its own
    (``python -m double_pendulum.app.server``)."""
    parser = argparse.ArgumentParser(prog="double-pendulum")
    add_app_command(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["app", *(sys.argv[1:] if argv is None else argv)])
    return args.func(args)


if __name__ == "__main__":
    raise SystemExit(main())
