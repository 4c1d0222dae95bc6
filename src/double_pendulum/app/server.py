"""``double-pendulum app``: the local web app, served on 127.0.0.1 (:func:`main`; :func:`add_app_command` adds the
command to the ``double-pendulum`` command line).

The app is Dash (Plotly's web framework, the one FMPy's own web app uses): the page is Dash's components, the plots
Plotly's, the runs :mod:`.worker`'s processes. Dash and Plotly are the ``app`` extra (``pip install -e ".[app]"``);
without them the command says so in one line.

The port: ``--port N``, or a free one the system gives (not a fixed default: FMPy's own web app, ``python -m
fmpy.webapp``, takes 8050, and both must run side by side); the address is printed. The app listens before it builds
the FMU, so a port in use is said at once, in one line. What the app caches (the fits of *against the measured
track*) goes to the result cache (:func:`~double_pendulum.runs.result_cache.cache_root`): ``.cache/`` in the
project's folder, elsewhere a temporary folder removed when the app ends, unless ``$DOUBLE_PENDULUM_CACHE`` names
one: nothing is written where the app is started.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import logging
import os
import signal
import socket
import sys
from pathlib import Path
from typing import Any

HOST = "127.0.0.1"
FMPY_WEBAPP_PORT = 8050
"""The port ``python -m fmpy.webapp`` takes: the app's is another, a free one unless ``--port`` names it."""


def create_app(fmu: Path) -> tuple[Any, Any]:
    """The Dash app for the FMU file ``fmu`` and its :class:`~.worker.Runs` (close them when the server ends)."""
    from dash import Dash

    from .callbacks import register
    from .layout import INDEX, page
    from .worker import Runs

    app = Dash(__name__, title="Double pendulum: the app")
    app.index_string = INDEX
    app.layout = page()
    runs = Runs(fmu)
    register(app, runs)
    return app, runs


def add_app_command(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``app`` to the command line's subcommands (``subparsers`` of :mod:`argparse`)."""
    parser = subparsers.add_parser("app", help="a local web app: change the pendulum and watch what happens",
                                   description="Serve the interactive app on 127.0.0.1 and print its address.")
    parser.add_argument("--port", type=int, default=None,
                        help=f"the port (default: a free one, printed with the address; FMPy's web app takes "
                        f"{FMPY_WEBAPP_PORT})")
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


def listening_socket(port: int | None) -> socket.socket:
    """A socket listening on ``HOST``:``port`` (None: a free port the system chooses); a port in use or not allowed
    is an :class:`AppError` naming it."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    # As werkzeug's own server: a port the app left a moment ago (its connections in TIME_WAIT) is free again; a
    # port another socket listens on stays refused.
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((HOST, port or 0))
        sock.listen(128)
    except OSError as error:
        sock.close()
        if error.errno == errno.EADDRINUSE:
            raise AppError(f"--port {port}: the port is in use (another program listens on it, perhaps an app "
                           "started before); give another, or leave --port out to take a free one") from None
        raise AppError(f"--port {port}: cannot listen on it ({error.strerror or error})") from None
    return sock


def app_cache(stack: contextlib.ExitStack) -> None:
    """Point the result cache (``$DOUBLE_PENDULUM_CACHE``) at a temporary folder that ``stack`` removes, unless it
    is set or the app runs in the project's folder (then ``.cache/`` there, as the scenarios')."""
    import tempfile

    from ..fmu.running.choice import is_project_folder
    from ..runs.result_cache import CACHE_ENV

    if not os.environ.get(CACHE_ENV) and not is_project_folder(Path.cwd()):
        os.environ[CACHE_ENV] = stack.enter_context(tempfile.TemporaryDirectory(prefix="double-pendulum-app-cache-"))


def cmd_app(args: argparse.Namespace) -> int:
    """Serve the app until interrupted; 2 when Dash is not installed, the port is not usable or the FMU is not
    (:func:`app_fmu`)."""
    try:
        import dash  # noqa: F401
        import plotly  # noqa: F401
    except ImportError as error:
        print(f"double-pendulum app: needs Dash and Plotly ({error}): pip install -e \".[app]\"", file=sys.stderr)
        return 2
    if args.port is not None and not 1 <= args.port <= 65535:
        print(f"double-pendulum app: --port {args.port} is no port (1 to 65535)", file=sys.stderr)
        return 2
    with contextlib.ExitStack() as stack:  # the socket, a temporary build and cache folder: closed, removed at the end
        try:
            sock = stack.enter_context(listening_socket(args.port))
            fmu = app_fmu(args, stack)
        except AppError as error:
            print(f"double-pendulum app: {error}", file=sys.stderr)
            return 2
        app_cache(stack)
        serve(fmu, sock)
    print("double-pendulum app: ended", file=sys.stderr)
    return 0


def serve(fmu: Path, sock: socket.socket) -> None:
    """Serve the app for the FMU file ``fmu`` on the listening socket ``sock`` until interrupted (Ctrl-C or
    SIGTERM), then end its runs."""
    from werkzeug.serving import make_server

    app, runs = create_app(fmu)
    port = sock.getsockname()[1]
    server = make_server(HOST, port, app.server, threaded=True, fd=sock.fileno())
    print(f"double-pendulum app: open http://{HOST}:{port}/ in a browser (Ctrl-C ends it)", flush=True)
    previous = signal.signal(signal.SIGTERM, _interrupt)  # `kill` ends it as Ctrl-C does: runs and files cleaned
    # The server's log of every request (a tab asks for its run's progress ten times a second) would bury the
    # address above; its warnings and errors still show.
    logging.getLogger("werkzeug").setLevel(logging.WARNING)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()
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
