"""``double-pendulum app``: the local web app, served on 127.0.0.1 (:func:`main`; :func:`add_app_command` adds the
command to the ``double-pendulum`` command line).

The app is Dash (Plotly's web framework, the one FMPy's own web app uses): the page is Dash's components, the plots
Plotly's, the runs :mod:`.worker`'s processes. Dash and Plotly are the ``app`` extra (``pip install -e ".[app]"``);
without them the command says so in one line.
"""

from __future__ import annotations

import argparse
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
    parser.add_argument("--fmu", default=None, help="the FMI 2.0 FMU, built first if missing or older than the "
                                                    "sources (default build/DoublePendulum.fmu)")
    parser.set_defaults(func=cmd_app)
    return parser


def cmd_app(args: argparse.Namespace) -> int:
    """Serve the app until interrupted; 2 when Dash is not installed or the port is not usable."""
    try:
        import dash  # noqa: F401
        import plotly  # noqa: F401
    except ImportError as error:
        print(f"double-pendulum app: needs Dash and Plotly ({error}): pip install -e \".[app]\"", file=sys.stderr)
        return 2
    if not 1 <= args.port <= 65535:
        print(f"double-pendulum app: --port {args.port} is no port (1 to 65535)", file=sys.stderr)
        return 2
    from ..fmu.build.fmi2 import DEFAULT_FMU_PATH
    from ..fmu.running.runner import ensure_fmu

    fmu = ensure_fmu(Path(args.fmu) if args.fmu else DEFAULT_FMU_PATH).resolve()
    app, runs = create_app(fmu)
    print(f"double-pendulum app: open http://{HOST}:{args.port}/ in a browser (Ctrl-C ends it)", flush=True)
    previous = signal.signal(signal.SIGTERM, _interrupt)  # `kill` ends it as Ctrl-C does: runs and files cleaned
    # The server's log of every request (a tab asks for its run's progress ten times a second) would bury the
    # address above; its warnings and errors still show.
    logging.getLogger("werkzeug").setLevel(logging.WARNING)
    try:
        app.run(host=HOST, port=args.port, debug=False)
    except KeyboardInterrupt:
        pass
    finally:
        runs.close()
        signal.signal(signal.SIGTERM, previous)
    print("double-pendulum app: ended", file=sys.stderr)
    return 0


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt


def main(argv: list[str] | None = None) -> int:
    """``double-pendulum app [--port N] [--fmu PATH]`` on its own (``python -m double_pendulum.app.server``)."""
    parser = argparse.ArgumentParser(prog="double-pendulum")
    add_app_command(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["app", *(sys.argv[1:] if argv is None else argv)])
    return args.func(args)


if __name__ == "__main__":
    raise SystemExit(main())
