"""Which Python runs the FMU, and that starting one never ends the host (fmu_src/loader/python_runtime.h): one per
process, the host's own where it has one (an older one refused in one line, never a second beside it), else the
one named by DOUBLE_PENDULUM_FMU_PYTHON, else the one the FMU carries; a Python that cannot start, or a damaged
bundle, gives NULL and one line, the host going on. The CPythons this machine has besides the build's (pyenv's
3.9, 3.10, 3.12, 3.13 where installed) show it for real; tests that need one skip, saying which, where none is."""

from __future__ import annotations

import functools
import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from host_binaries import compiled_host

from double_pendulum.fmu.build import loader

LOADER_FOLDER = Path(__file__).resolve().parents[1] / "fmu_src" / "loader"


@functools.cache
def other_pythons() -> dict[tuple[int, int], dict]:
    """CPythons on this machine by (major, minor): python3.X on PATH and pyenv's, each with its libpython (if
    shared), include folder and executable."""
    candidates = []
    for folder in os.environ.get("PATH", "").split(os.pathsep):
        candidates += sorted(Path(folder).glob("python3.[0-9]*")) if folder and Path(folder).is_dir() else []
    pyenv = Path(os.environ.get("PYENV_ROOT", Path.home() / ".pyenv")) / "versions"
    candidates += sorted(pyenv.glob("*/bin/python3.[0-9]*")) if pyenv.is_dir() else []
    query = ("import json, os, sys, sysconfig as c; print(json.dumps({'version': list(sys.version_info[:2]), "
             "'library': os.path.join(c.get_config_var('LIBDIR') or '', c.get_config_var('INSTSONAME') or '') "
             "if c.get_config_var('Py_ENABLE_SHARED') else '', 'include': c.get_paths()['include'], "
             "'executable': sys.executable, 'gil': not c.get_config_var('Py_GIL_DISABLED')}))")
    found: dict[tuple[int, int], dict] = {}
    for candidate in candidates:
        if not candidate.name.replace("python", "").replace(".", "").isdigit() or not os.access(candidate, os.X_OK):
            continue
        try:
            done = subprocess.run([str(candidate), "-I", "-S", "-c", query], capture_output=True, text=True,
                                  timeout=30)
            info = json.loads(done.stdout)
        except (OSError, subprocess.SubprocessError, ValueError):
            continue
        if info["gil"]:
            found.setdefault(tuple(info["version"]), info)
    return found


def python(major: int, minor: int, shared: bool = False) -> dict:
    """The CPython major.minor of this machine, or skip the test saying it is missing."""
    info = other_pythons().get((major, minor))
    if info is None or (shared and not (info["library"] and Path(info["library"]).is_file())):
        pytest.skip(f"no CPython {major}.{minor}{' with a shared libpython' if shared else ''} on this machine "
                    "(pyenv install or python3.X on PATH)")
    return info


@pytest.fixture(scope="module")
def host(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return compiled_host(tmp_path_factory, "fmi2_host")


@pytest.fixture(scope="module")
def extracted(fmu_path: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, object]:
    from fmpy import extract, read_model_description

    return (Path(extract(str(fmu_path), str(tmp_path_factory.mktemp("choice") / "DoublePendulum"))),
            read_model_description(str(fmu_path)))


def run_host(host: Path, folder: Path, description, env: dict[str, str], cwd: Path, *extra: str):
    phi1 = next(v.valueReference for v in description.modelVariables if v.name == "phi1")
    command = [str(host), str(folder), "DoublePendulum", description.guid, "100", "0.01", f"o:{phi1}", *extra]
    return subprocess.run(command, capture_output=True, text=True, env=env, cwd=cwd, timeout=300)


def bare(tmp_path: Path, **extra: str) -> dict[str, str]:
    return {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), **extra}


def log_lines(stdout: str) -> list[str]:
    return [line for line in stdout.splitlines() if line.startswith("log ")]


def fmpy_phi1(fmu_path: Path) -> float:
    from fmpy import simulate_fmu

    return float(simulate_fmu(str(fmu_path), stop_time=1.0, output_interval=0.01, output=["phi1"])["phi1"][-1])


# -------------------------------------------------------------------------------------- the configuration

@pytest.mark.parametrize("minor", [11, 12, 13])
def test_the_loaders_mirror_of_pyconfig_is_cpythons(minor, tmp_path):
    """fmu_src/loader/python_config.h against CPython 3.minor's own Python.h: every field the loader sets at
    CPython's offset, every structure of CPython's size (tests/c_host/config_layout.c, which fails to compile
    otherwise). The build's CPython always; 3.12 and 3.13 where installed."""
    info = {"include": __import__("sysconfig").get_paths()["include"]} if sys.version_info[1] == minor else \
        python(3, minor)
    compiler = loader.c_compiler()
    if compiler is None:
        pytest.skip("no C compiler")
    done = subprocess.run([*compiler, f"-I{info['include']}", f"-I{LOADER_FOLDER}", "-o", str(tmp_path / "layout"),
                           str(Path(__file__).parent / "c_host" / "config_layout.c")], capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    assert subprocess.run([str(tmp_path / "layout")]).returncode == 0


@pytest.mark.parametrize("minor", [12, 13])
def test_a_cpython_of_another_minor_version_named_by_the_override_runs_the_fmu(host, extracted, fmu_path, minor,
                                                                              tmp_path):
    """DOUBLE_PENDULUM_FMU_PYTHON naming pyenv's libpython3.12 / 3.13: the loader starts it with that version's
    PyConfig (the bundled bytecode is 3.11's, so it compiles the sources) and the numbers are fmpy's."""
    info = python(3, minor, shared=True)
    folder, description = extracted
    done = run_host(host, folder, description, bare(tmp_path, DOUBLE_PENDULUM_FMU_PYTHON=info["library"]), tmp_path,
                    "l:1")
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert f"DOUBLE_PENDULUM_FMU_PYTHON={info['library']}: CPython 3.{minor}." in done.stdout, done.stdout
    phi1 = float(done.stdout.split("\n")[[k for k, line in enumerate(done.stdout.split("\n"))
                                          if line[:1].isdigit()][0]].split()[1])
    assert phi1 == pytest.approx(fmpy_phi1(fmu_path), rel=1e-12, abs=1e-12)
    assert not list(folder.rglob("__pycache__")), "the FMU's Python wrote bytecode into the FMU's folder"


# ------------------------------------------------------------------------------------ a Python that cannot start

def test_a_cpython_that_cannot_start_gives_null_and_one_line_and_the_host_goes_on(host, extracted, tmp_path):
    """A real libpython with a broken standard library (its encodings package raises): Py_InitializeEx ended the
    host with exit status 1 (defect D1); through PyConfig the start returns a status, the FMU says why in one line
    and the host gets NULL (exit 4: it goes on to report it)."""
    real = Path(loader.python_record().split("library=")[1].splitlines()[0])
    if not real.is_file():
        pytest.skip("the build's CPython has no shared libpython")
    minor = sys.version_info[1]
    home = tmp_path / "broken"
    (home / "lib" / f"python3.{minor}" / "encodings").mkdir(parents=True)
    (home / "lib" / f"python3.{minor}" / "encodings" / "__init__.py").write_text("raise ImportError('broken')\n")
    (home / "lib" / real.name).symlink_to(real)
    folder, description = extracted
    env = bare(tmp_path, DOUBLE_PENDULUM_FMU_PYTHON=str(home / "lib" / real.name))
    done = run_host(host, folder, description, env, tmp_path)
    assert done.returncode == 4, f"exit {done.returncode}\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    logged = log_lines(done.stdout)
    assert len(logged) == 1 and logged[0].startswith("log 3 "), logged
    assert "did not start" in logged[0] and str(home) in logged[0], logged


@pytest.mark.parametrize("missing", ["python3{minor}.zip", "libpython3.{minor}.so.1.0"])
def test_a_damaged_bundle_gives_null_and_one_line_naming_the_missing_file(host, extracted, tmp_path, missing):
    folder, description = extracted
    damaged = Path(shutil.copytree(folder, tmp_path / "damaged"))
    name = missing.format(minor=sys.version_info[1])
    (damaged / "binaries" / "linux64" / name).unlink()
    done = run_host(host, damaged, description, bare(tmp_path), tmp_path)
    assert done.returncode == 4, done.stdout[-3000:] + done.stderr[-3000:]
    logged = log_lines(done.stdout)
    assert len(logged) == 1 and f"is damaged: {damaged}/binaries/linux64/{name} is missing" in logged[0], logged
    assert "extract the whole FMU again" in logged[0]


# ------------------------------------------------------------------------------------ a Python in the process

def test_a_libpython_loaded_but_not_started_is_refused_not_doubled(host, extracted, tmp_path):
    """A host that has a libpython in it but never started it (here: preloaded): the FMU neither starts it nor
    loads its own beside it, and says so in one line."""
    real = Path(loader.python_record().split("library=")[1].splitlines()[0])
    if not real.is_file():
        pytest.skip("the build's CPython has no shared libpython")
    folder, description = extracted
    done = run_host(host, folder, description, bare(tmp_path, LD_PRELOAD=str(real)), tmp_path)
    assert done.returncode == 4, done.stdout[-3000:] + done.stderr[-3000:]
    logged = log_lines(done.stdout)
    assert len(logged) == 1 and "is loaded in this process" in logged[0] and "not started" in logged[0], logged


OLD_HOST = textwrap.dedent("""
    import ctypes, sys
    library = ctypes.CDLL(sys.argv[1], mode=ctypes.RTLD_LOCAL)
    messages = []
    LOGGER = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p,
                              ctypes.c_char_p)
    def log(env, name, status, category, message, argument):
        messages.append(f"{status} {argument.decode() if argument else message.decode()}")
    logger = LOGGER(log)
    class Callbacks(ctypes.Structure):
        _fields_ = [("logger", LOGGER), ("allocate", ctypes.c_void_p), ("free", ctypes.c_void_p),
                    ("step_finished", ctypes.c_void_p), ("environment", ctypes.c_void_p)]
    callbacks = Callbacks(logger, None, None, None, None)
    instantiate = library.fmi2Instantiate
    instantiate.restype = ctypes.c_void_p
    component = instantiate(b"old", 1, sys.argv[2].encode(), sys.argv[3].encode(), ctypes.byref(callbacks), 0, 0)
    print("component", component)
    for message in messages:
        print("log", message)
""")


@pytest.mark.parametrize("minor", [10, 9])
def test_a_python_host_older_than_3_11_gets_one_clear_line(extracted, minor, tmp_path):
    """A Python 3.10 host ran the FMU though its Python side needs 3.11; a 3.9 host said "__import__ not found"
    (defect D6). Now either gets NULL and one line naming its version, and no second Python is loaded."""
    info = python(3, minor)
    folder, description = extracted
    so = folder / "binaries" / "linux64" / "DoublePendulum.so"
    done = subprocess.run([info["executable"], "-I", "-c", OLD_HOST, str(so), description.guid,
                           (folder / "resources").as_uri()], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "component None" in done.stdout, done.stdout
    logged = [line for line in done.stdout.splitlines() if line.startswith("log ")]
    assert len(logged) == 1 and logged[0].startswith("log 3 "), done.stdout
    assert f"this process runs CPython 3.{minor}." in logged[0] and "older than the 3.11" in logged[0], logged
    assert "it carries its own" in logged[0]


def test_in_a_python_host_the_debug_log_says_the_hosts_python_runs_the_fmu(fmu_path):
    from fmpy import simulate_fmu

    messages = []
    simulate_fmu(str(fmu_path), stop_time=0.01, debug_logging=True,
                 logger=lambda *args: messages.append(args[-1].decode() if isinstance(args[-1], bytes) else ""))
    said = [m for m in messages if "the FMU's Python side runs in" in m]
    assert said and f"CPython {sys.version.split()[0]} already running in this process" in said[0], messages[:5]
