"""The tests' C hosts (tests/c_host/fmi2_host.c, fmi3_host.c) as Windows programs, run under Wine: what a test of
the FMUs' Windows binaries (binaries/win64, binaries/x86_64-windows) needs on a Linux machine.

- :func:`windows_host` compiles a host for x86_64-windows-gnu with zig (the ``ziglang`` package, else ``zig`` on
  PATH) once per test session, shared by the xdist workers as :mod:`host_binaries` shares the Linux hosts;
- :class:`Wine` is a private Wine prefix, made on first use in a temporary folder of the test process (never in
  $HOME), with an explicit minimal environment: ``WINEDEBUG=-all``, a UTF-8 locale (so that Wine reads a non-ASCII
  argument as UTF-8), a private HOME, and nothing of Python: the prefix is new, so its C: drive has no Python,
  Wine gives the Windows side a bare PATH of its own (C:\\windows\\system32 and the like; the Linux PATH is not
  passed on) and no PYTHONHOME or PYTHONPATH is set; :meth:`Wine.run` runs a host with Linux paths among its
  arguments turned into Wine paths (Z:\\...), under a timeout; :meth:`Wine.stop` ends the prefix's wineserver
  (``wineserver -k``), so that no process is left behind, and removes the prefix (about 700 MB);
- tests/conftest.py's session fixture ``wine`` makes the :class:`Wine` of a test process and stops it at the
  end; it skips, with the reason, where wine64 is missing, and :func:`windows_host` where zig is.

A test::

    from wine import windows_host

    @pytest.fixture(scope="module")
    def host(tmp_path_factory):
        return windows_host(tmp_path_factory, "fmi2_host")

    def test_it(wine, host, tmp_path):
        done = wine.run(host, [fmu_folder, "DoublePendulum", guid, "1000", "0.001", "o:5"], cwd=tmp_path)
        assert done.returncode == 0, done.stdout + done.stderr

Each test process (each xdist worker that asks for it) has a prefix of its own: ``wineserver -k`` at the end of
one worker would otherwise end the hosts another worker still runs in a shared one. Measured here (Debian's
Wine 8.0, 2 cores shared): a new prefix 4 to 10 s, a host run in it 0.1 s (0.9 s where Wine's services have to
start again, 3 s after the last run ended them), stopping it 1 s; zig's first Windows compile on an empty cache
(~/.cache/zig: mingw's C runtime) about 140 s, later ones 1 to 2 s.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import selectors
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path

import pytest
from conftest import session_shared

from double_pendulum.fmu.build import loader

SOURCES = Path(__file__).parent / "c_host"
HOSTS = ("fmi2_host", "fmi3_host")
"""The hosts that build for Windows (the torture hosts are for Linux only)."""

WINE_MISSING = "wine64 is not installed (apt-get install wine64)"
ZIG_MISSING = "zig is not installed (pip install ziglang, or zig on PATH)"
LOADER = Path("/usr/lib/wine/wine64")
"""Where Debian puts Wine's 64-bit loader, which is not always on PATH."""

PREFIX_TIMEOUT_S = 300
"""The longest a new prefix may take (measured 4 to 10 s; a loaded machine is slower)."""

DLL_OVERRIDES = "winemenubuilder.exe=d;mscoree=d;mshtml=d"
"""No desktop menu entries written into HOME, no offer to install Mono or Gecko while the prefix is made."""


def zig() -> list[str] | None:
    """The command of zig: the ``ziglang`` package's (a dependency of the project on Linux), else ``zig`` on PATH;
    None if neither."""
    if importlib.util.find_spec("ziglang") is not None:
        return [sys.executable, "-m", "ziglang"]
    found = shutil.which("zig")
    return [found] if found else None


def wine_loader() -> Path | None:
    """Wine's 64-bit loader: ``wine64`` on PATH, else Debian's :data:`LOADER`; None if neither."""
    found = shutil.which("wine64")
    if found:
        return Path(found)
    return LOADER if os.access(LOADER, os.X_OK) else None


def wineserver(wine64: Path) -> Path | None:
    """The wineserver that goes with the loader ``wine64``: beside it (Debian: /usr/lib/wine/), else on PATH."""
    beside = wine64.resolve().parent / "wineserver"
    if os.access(beside, os.X_OK):
        return beside
    found = shutil.which("wineserver")
    return Path(found) if found else None


def compile_windows_host(name: str, folder: Path) -> Path:
    """Compile ``tests/c_host/<name>.c`` for x86_64-windows-gnu with zig into ``folder/<name>.exe``."""
    command = zig()
    if command is None:
        raise RuntimeError(ZIG_MISSING)
    path = folder / f"{name}.exe"
    done = subprocess.run([*command, "cc", "-target", "x86_64-windows-gnu", "-O2", f"-I{loader.fmi_headers()}",
                           "-o", str(path), str(SOURCES / f"{name}.c"), "-lshell32"],
                          capture_output=True, text=True, cwd=folder)
    if done.returncode != 0:
        raise RuntimeError(f"zig could not compile {name}.c for Windows:\n{done.stderr[-4000:]}")
    for leftover in folder.glob(f"{name}.pdb"):  # zig's debug information, not needed to run
        leftover.unlink()
    return path


def windows_host(tmp_path_factory: pytest.TempPathFactory, name: str) -> Path:
    """The Windows host ``name`` (``fmi2_host`` or ``fmi3_host``), compiled once for the test session into a folder
    of the session (conftest's ``session_shared``); skips where zig is missing."""
    if name not in HOSTS:
        raise ValueError(f"{name} is not one of the hosts that build for Windows: {HOSTS}")
    if zig() is None:
        pytest.skip(ZIG_MISSING)

    def make(folder: Path) -> None:
        folder.mkdir()
        compile_windows_host(name, folder)

    return session_shared(tmp_path_factory, f"windows_host_{name}", make) / f"{name}.exe"


def windows_path(path: str | os.PathLike[str]) -> str:
    """``path`` (a Linux path) as Wine sees it: drive Z: is the Linux root in every new prefix."""
    return "Z:" + os.path.abspath(os.fspath(path)).replace("/", "\\")


class Wine:
    """A private Wine prefix at ``folder/prefix`` with a HOME of its own at ``folder/home``, made by :meth:`start`
    (the session fixture ``wine`` in tests/conftest.py makes one per test process and stops it at the end)."""

    def __init__(self, folder: Path, wine64: Path, server: Path) -> None:
        self.prefix, self.home = folder / "prefix", folder / "home"
        self.wine64, self.wineserver = wine64, server
        self.started = False

    @classmethod
    def session(cls, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Wine]:
        """The body of the session fixture ``wine``: skip where wine64 is missing, else make a prefix, yield it and
        stop it at the end."""
        wine64 = wine_loader()
        server = wineserver(wine64) if wine64 else None
        if wine64 is None or server is None:
            pytest.skip(WINE_MISSING)
        wine = cls(tmp_path_factory.mktemp("wine"), wine64, server)
        try:
            wine.start()
            yield wine
        finally:
            wine.stop()

    def environment(self, extra: Mapping[str, str] | None = None) -> dict[str, str]:
        """The whole environment of a Wine process here (nothing of the test process's; ``extra`` added). Wine hands
        these variables on to the Windows program, with a PATH of its own for the Linux PATH."""
        return {
            "PATH": "/usr/bin:/bin",
            "HOME": str(self.home),
            "LANG": "C.UTF-8",
            "WINEPREFIX": str(self.prefix),
            "WINEDEBUG": "-all",
            "WINEDLLOVERRIDES": DLL_OVERRIDES,
            **(extra or {}),
        }

    def start(self) -> None:
        """Make the prefix (``wineboot --init``); RuntimeError if Wine fails to."""
        self.home.mkdir(parents=True, exist_ok=True)
        self.started = True  # from here on stop() has processes to end
        done = self._wine(["wineboot", "--init"], cwd=self.home, timeout=PREFIX_TIMEOUT_S, env=self.environment())
        if done.returncode != 0:
            raise RuntimeError(f"Wine could not make the prefix {self.prefix} (exit {done.returncode}):\n"
                               f"{done.stdout[-2000:]}\n{done.stderr[-2000:]}")
        drive = self.prefix / "dosdevices" / "z:"
        if not drive.is_symlink() or os.readlink(drive) != "/":
            raise RuntimeError(f"drive Z: of the new prefix is not / ({drive}): Linux paths would not reach Windows")

    def run(self, program: str | os.PathLike[str], arguments: Sequence[str | os.PathLike[str]], *, cwd: Path,
            timeout: float = 120, env: Mapping[str, str] | None = None) -> subprocess.CompletedProcess[str]:
        """Run the Windows program ``program`` (a path, or the name of one of Wine's, such as ``cmd``) with
        ``arguments`` (each a str as it is, or a path, which becomes its Wine path) in ``cwd``, with
        :meth:`environment` (plus ``env``): its exit status, stdout and stderr (UTF-8). On a timeout the prefix's
        processes are ended (the next run starts a new wineserver) and subprocess.TimeoutExpired is raised."""
        if not self.started:
            raise RuntimeError("the Wine prefix is not started (or already stopped)")
        command = [a if isinstance(a, str) else windows_path(a) for a in (program, *arguments)]
        return self._wine(command, cwd=cwd, timeout=timeout, env=self.environment(env))

    def _wine(self, command: list[str], *, cwd: Path, timeout: float,
              env: dict[str, str]) -> subprocess.CompletedProcess[str]:
        # stdout and stderr are pipes, read while the program runs and drained once it has ended: the Windows
        # services a run starts (services.exe, winedevice.exe, ...) inherit them and live on for a few seconds
        # after the program, so reading them to their end would wait for those too (about 1.5 s a run). Pipes,
        # not files: under Wine a Windows program whose standard handle is a regular file cannot use it as a
        # stream (CPython, starting, stops with "init_sys_streams: OSError: [WinError 6] Invalid handle";
        # /dev/null, pipes and terminals work)
        process = subprocess.Popen([str(self.wine64), *command], cwd=cwd, env=env, stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, start_new_session=True)
        chunks: dict[int, list[bytes]] = {process.stdout.fileno(): [], process.stderr.fileno(): []}
        deadline = time.monotonic() + timeout
        with selectors.DefaultSelector() as selector:
            for stream in (process.stdout, process.stderr):
                selector.register(stream, selectors.EVENT_READ)
            try:
                while selector.get_map():
                    ended = process.poll() is not None
                    if not ended and time.monotonic() > deadline:
                        raise subprocess.TimeoutExpired(command, timeout)
                    ready = selector.select(timeout=0.05 if ended else 0.1)
                    if ended and not ready:
                        break  # the program has ended and written everything; only Wine's services hold the pipes
                    for key, _ in ready:
                        data = os.read(key.fd, 1 << 16)
                        if data:
                            chunks[key.fd].append(data)
                        else:
                            selector.unregister(key.fileobj)
            except subprocess.TimeoutExpired:
                self.end_processes()
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(process.pid, signal.SIGKILL)
                process.wait()
                raise
            finally:
                process.stdout.close()
                process.stderr.close()
        code = process.wait()
        out, err = (b"".join(chunks[f]).decode("utf-8", "replace") for f in chunks)
        return subprocess.CompletedProcess(process.args, code, out, err)

    def processes(self) -> list[int]:
        """The ids of the live processes of this prefix: those with its WINEPREFIX in their environment (Wine's
        programs, its wineserver and the hosts), zombies not counted."""
        mark = f"WINEPREFIX={self.prefix}".encode()
        found = []
        for entry in Path("/proc").iterdir():
            if not entry.name.isdigit():
                continue
            try:
                state = (entry / "stat").read_text().rpartition(")")[2].split()[0]
                if state != "Z" and mark in (entry / "environ").read_bytes().split(b"\0"):
                    found.append(int(entry.name))
            except (OSError, IndexError):  # gone meanwhile, or not ours to read
                continue
        return found

    def end_processes(self, wait_s: float = 10.0) -> None:
        """``wineserver -k``: end every process of the prefix and its wineserver; wait until they are gone, and
        kill what is left after ``wait_s`` (only processes of this prefix, by their ids). A later run starts a new
        wineserver."""
        subprocess.run([str(self.wineserver), "-k"], env=self.environment(), capture_output=True, timeout=60)
        deadline = time.monotonic() + wait_s
        while self.processes() and time.monotonic() < deadline:
            time.sleep(0.1)
        for pid in self.processes():
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)

    def stop(self) -> None:
        """End the prefix's processes and wineserver (:meth:`end_processes`) and remove the prefix."""
        if self.started:
            self.end_processes()
            self.started = False
        shutil.rmtree(self.prefix, ignore_errors=True)

