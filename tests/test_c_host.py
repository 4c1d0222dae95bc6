"""The FMUs in a host that is not Python: a minimal C host (tests/c_host/fmi2_host.c), started with a
bare environment, loads each FMU that ``double-pendulum build`` writes through its C loader
(``fmu_src/loader/``, :mod:`double_pendulum.fmu.build.loader`), runs it as fmpy does and gets fmpy's numbers;
without a usable Python the FMU refuses to instantiate and says why in one line. The FMI 3.0 FMU runs
in tests/c_host/fmi3_host.c: Model Exchange integrated by the host (RK4, FMI 3 event handling, strict
out-arguments) and Co-Simulation."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from host_binaries import compiled_host

from double_pendulum.fmu.build import loader

STEPS, STEP_SIZE = 1000, 1e-3
RUNS = 10  # C-host runs of each FMU

CASES = {  # file: (start values, inputs held at these values, outputs compared)
    "DoublePendulum.fmu": (
        {"phi1_0": 2.0, "phi2_0": 2.0, "air_drag": True, "bearing_friction": True, "solver": "dopri5", "rtol": 1e-8},
        {"tau1": 0.02, "pivot_ax": 0.3},
        ["phi1", "phi2", "omega1", "omega2", "E_total", "W_input", "F_pivot_x"],
    ),
    "Suspension.fmu": (
        {"k_x": 5e3, "c_y": 5.0},
        {"F_x": 1.0, "F_y": -7.0},
        ["x", "y", "vx", "vy", "E_suspension", "W_in"],
    ),
    "PendulumOnSuspension.fmu": (
        {"DoublePendulum.phi1_0": 1.5, "Suspension.k_x": 5e3},
        {},
        ["DoublePendulum.phi1", "DoublePendulum.phi2", "DoublePendulum.F_pivot_x", "Suspension.x", "Suspension.y"],
    ),
}


def _shared_libpython_here() -> bool:
    record = dict(line.split("=", 1) for line in loader.python_record().splitlines() if "=" in line)
    return bool(record["library"]) and Path(record["library"]).is_file()


pytestmark = [
    pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the C loader and this C host are for Linux"),
    pytest.mark.skipif(loader.c_compiler() is None, reason="no C compiler ($CC, cc, gcc or clang) to build the C host"),
    pytest.mark.skipif(not _shared_libpython_here(),
                       reason="this Python has no shared libpython, which the FMU needs in a host without Python"),
]


@pytest.fixture(scope="module")
def host(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The C host (tests/c_host/fmi2_host.c), compiled once for the test session (host_binaries)."""
    return compiled_host(tmp_path_factory, "fmi2_host")


@pytest.fixture(scope="module")
def fmus(built_fmus: list[Path]) -> dict[str, Path]:
    """Every FMU ``double-pendulum build`` writes (the session's build), by path in the build folder
    (``fmi3/DoublePendulum.fmu``)."""
    folder = built_fmus[0].parent
    return {str(path.relative_to(folder)): path for path in built_fmus if path.suffix == ".fmu"}


@pytest.fixture(scope="module")
def extracted(fmus: dict[str, Path], tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, object]]:
    """Each FMU extracted, with its model description."""
    from fmpy import extract, read_model_description

    folder = tmp_path_factory.mktemp("extracted")
    return {name: (Path(extract(str(path), str(folder / name))), read_model_description(str(path)))
            for name, path in fmus.items()}


def bare_environment(home: Path, **extra: str) -> dict[str, str]:
    """What ``env -i PATH=/usr/bin:/bin HOME=...`` gives a process: no LD_PRELOAD, PYTHONHOME or PYTHONPATH."""
    return {"PATH": "/usr/bin:/bin", "HOME": str(home), **extra}


def host_arguments(name: str, description) -> list[str]:
    """The C host's arguments for CASES[name]: start values, inputs and outputs by value reference."""
    start, inputs, outputs = CASES[name]
    variables = {v.name: v for v in description.modelVariables}
    args = []
    for variable, value in start.items():
        kind = {"Boolean": "b", "String": "s"}.get(variables[variable].type, "r")
        args.append(f"{kind}:{variables[variable].valueReference}={int(value) if kind == 'b' else value}")
    args += [f"i:{variables[n].valueReference}={value!r}" for n, value in inputs.items()]
    return args + [f"o:{variables[n].valueReference}" for n in outputs]


def run_host(host: Path, folder: Path, description, args: list[str], env: dict[str, str], cwd: Path):
    identifier = description.coSimulation.modelIdentifier
    command = [str(host), str(folder), identifier, description.guid, str(STEPS), repr(STEP_SIZE), *args]
    return subprocess.run(command, capture_output=True, text=True, env=env, cwd=cwd, timeout=120)


def parse_outputs(stdout: str) -> dict[int, float]:
    rows = [line.split() for line in stdout.splitlines() if line[:1].isdigit()]
    return {int(vr): float(value) for vr, value in rows}


def fmpy_outputs(path: Path, name: str) -> list[float]:
    """The same run through fmpy's simulate_fmu (inputs held at their values), its last row."""
    from fmpy import simulate_fmu

    start, inputs, outputs = CASES[name]
    signal = None
    if inputs:
        signal = np.array([(0.0, *inputs.values()), (1.0, *inputs.values())],
                          dtype=[("time", float), *((n, float) for n in inputs)])
    result = simulate_fmu(str(path), start_values=start, stop_time=STEPS * STEP_SIZE, output_interval=STEP_SIZE,
                          input=signal, output=outputs)
    return [float(result[n][-1]) for n in outputs]


@pytest.mark.parametrize("name", list(CASES))
def test_every_fmu_runs_in_a_c_host_with_a_bare_environment_as_in_fmpy(host, fmus, extracted, tmp_path, name):
    folder, description = extracted[name]
    expected = fmpy_outputs(fmus[name], name)
    args = host_arguments(name, description)
    for run in range(RUNS):
        done = run_host(host, folder, description, args, bare_environment(tmp_path), tmp_path)
        assert done.returncode == 0, f"run {run}: exit {done.returncode}\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}"
        assert "host-unchanged 1" in done.stdout, "the FMU changed the host's environment or signal handlers"
        got = list(parse_outputs(done.stdout).values())
        assert got == pytest.approx(expected, rel=1e-10, abs=1e-10), f"run {run}"
    assert not os.listdir(tmp_path), "the FMU left files in the host's working folder"


@pytest.mark.parametrize("override", ["/nonexistent/python3", "/bin/true"])
def test_without_a_usable_python_instantiate_returns_null_and_says_why_in_one_line(host, extracted, tmp_path, override):
    folder, description = extracted["DoublePendulum.fmu"]
    env = bare_environment(tmp_path, **{loader.OVERRIDE_VARIABLE: override})
    done = run_host(host, folder, description, [], env, tmp_path)
    assert done.returncode == 4, done.stdout + done.stderr  # fmi2Instantiate returned NULL: no crash, no hang
    logged = [line for line in done.stdout.splitlines() if line.startswith("log ")]
    assert len(logged) == 1 and logged[0].startswith("log 3 ")  # one fmi2Error line through the host's logger
    assert "no usable Python to run this FMU" in logged[0] and f"{loader.OVERRIDE_VARIABLE}={override}" in logged[0]
    assert "CPython >= 3.11 with a shared libpython" in logged[0]  # what it needs and how to point it there


QUERY_TIMEOUT_S = 2
"""The loader's wait for a candidate interpreter in the test below: compiled in smaller than the FMU's 20 s
(``QUERY_TIMEOUT_MS`` in fmu_src/loader/python_runtime.c, a macro with that default) so that the test does not
sleep 20 s."""


def test_an_interpreter_that_never_answers_is_given_up_in_bounded_time_and_leaves_no_process(host, extracted,
                                                                                            tmp_path):
    """A python3 that is a shell script hanging in a child of its own (no exec): the loader gives it up after
    its time (the FMU's loader recompiled with 2 s for its 20 s: the same code path), says so in one line, and
    kills its whole process group (the child is not left orphaned)."""
    marker = f"{os.getpid()}.{time.monotonic_ns() % 10**6}"
    script = tmp_path / "bin" / "python3"
    script.parent.mkdir()
    script.write_text(f"#!/bin/sh\nsleep 3{marker}\necho never\n")
    script.chmod(0o755)
    extracted_folder, description = extracted["DoublePendulum.fmu"]
    folder = Path(shutil.copytree(extracted_folder, tmp_path / "fmu"))
    binary = folder / "binaries" / loader.PLATFORMS[2] / "DoublePendulum.so"
    binary.write_bytes(loader.compiled_loader(2, {"MODEL_IDENTIFIER": "DoublePendulum", "FMU_GUID": description.guid,
                                                  "N_VARIABLES": str(len(description.modelVariables)),
                                                  "QUERY_TIMEOUT_MS": str(QUERY_TIMEOUT_S * 1000)}))
    env = bare_environment(tmp_path, **{loader.OVERRIDE_VARIABLE: str(script)})
    started = time.monotonic()
    done = run_host(host, folder, description, [], env, tmp_path)
    took = time.monotonic() - started
    assert done.returncode == 4, done.stdout + done.stderr
    logged = [line for line in done.stdout.splitlines() if line.startswith("log ")]
    assert len(logged) == 1 and f"did not answer within {QUERY_TIMEOUT_S} s" in logged[0], logged
    assert QUERY_TIMEOUT_S - 0.1 < took < 2 * QUERY_TIMEOUT_S + 10, took
    left = subprocess.run(["pgrep", "-f", f"sleep 3{marker}"], capture_output=True, text=True).stdout.split()
    assert not left, f"the interpreter's child was left behind: {left}"


def test_the_hosts_python_variables_do_not_reach_the_fmus_interpreter(host, extracted, tmp_path):
    """PYTHONHOME and PYTHONPATH set for some other Python (here: broken ones) leave the FMU unmoved."""
    poisoned = tmp_path / "poisoned"
    poisoned.mkdir()
    (poisoned / "json.py").write_text("raise ImportError('the host PYTHONPATH reached the FMU')\n")
    folder, description = extracted["DoublePendulum.fmu"]
    args = host_arguments("DoublePendulum.fmu", description)
    clean = run_host(host, folder, description, args, bare_environment(tmp_path), tmp_path)
    env = bare_environment(tmp_path, PYTHONPATH=str(poisoned), PYTHONHOME="/nonexistent")
    polluted = run_host(host, folder, description, args, env, tmp_path)
    assert polluted.returncode == 0, polluted.stdout[-2000:] + polluted.stderr[-2000:]
    assert parse_outputs(polluted.stdout) == parse_outputs(clean.stdout)


def test_an_interpreter_with_nothing_installed_runs_the_fmu(host, extracted, tmp_path):
    """Named by the override, a fresh virtual environment without even pip gives the same numbers."""
    venv = tmp_path / "empty"
    subprocess.run([getattr(sys, "_base_executable", sys.executable), "-m", "venv", "--without-pip", str(venv)],
                   check=True, capture_output=True)
    folder, description = extracted["DoublePendulum.fmu"]
    args = host_arguments("DoublePendulum.fmu", description)
    recorded = run_host(host, folder, description, args, bare_environment(tmp_path), tmp_path)
    env = bare_environment(tmp_path, **{loader.OVERRIDE_VARIABLE: str(venv / "bin" / "python")})
    empty = run_host(host, folder, description, args, env, tmp_path)
    assert empty.returncode == 0, empty.stdout[-2000:] + empty.stderr[-2000:]
    assert parse_outputs(empty.stdout) == parse_outputs(recorded.stdout)


# ---------------------------------------------------------------------------------------------- FMI 3.0
FMI3 = "fmi3/DoublePendulum.fmu"
# Model Exchange case: CASES' pendulum with constant torques (held the same way by the co-simulation's hold
# and by continuous inputs; a constant pivot acceleration is not: the hold ramps the pivot velocity in each step)
ME_INPUTS = {"tau1": 0.02, "tau2": -0.01}


@pytest.fixture(scope="module")
def host3(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The FMI 3 C host (tests/c_host/fmi3_host.c: Model Exchange with Euler or RK4 and FMI 3 event handling, or
    Co-Simulation), compiled once for the test session (host_binaries)."""
    return compiled_host(tmp_path_factory, "fmi3_host")


def run_host3(host: Path, folder: Path, description, method: str, args: list[str], env: dict[str, str], cwd: Path):
    command = [str(host), str(folder), description.modelExchange.modelIdentifier, description.guid, method,
               str(STEPS), repr(STEP_SIZE), *args]
    return subprocess.run(command, capture_output=True, text=True, env=env, cwd=cwd, timeout=120)


def reported(stdout: str, key: str) -> int:
    return int(next(line.split()[1] for line in stdout.splitlines() if line.startswith(key + " ")))


@pytest.fixture(scope="module")
def fmi2_reference(fmus) -> list[float]:
    """CASES' DoublePendulum (friction, drag) with the torques ME_INPUTS through the FMI 2 FMU at tight
    tolerances (dop853, rtol 1e-12): the outputs after 1 s."""
    from fmpy import simulate_fmu

    start, _, outputs = CASES["DoublePendulum.fmu"]
    inputs = ME_INPUTS
    signal = np.array([(0.0, *inputs.values()), (1.0, *inputs.values())],
                      dtype=[("time", float), *((n, float) for n in inputs)])
    result = simulate_fmu(str(fmus["DoublePendulum.fmu"]), start_values={**start, "solver": "dop853", "rtol": 1e-12,
                          "atol": 1e-14}, stop_time=STEPS * STEP_SIZE, output_interval=0.1, input=signal,
                          output=outputs)
    return [float(result[n][-1]) for n in outputs]


def test_fmi3_model_exchange_runs_and_terminates_in_a_c_host_with_a_bare_environment(host3, extracted, fmi2_reference,
                                                                                       tmp_path):
    """RK4 at 1 ms with the host's event handling (strict out-arguments) gives the FMI 2 FMU's motion."""
    folder, description = extracted[FMI3]
    refs = {v.name: v.valueReference for v in description.modelVariables}
    args = [a for a in host_arguments("DoublePendulum.fmu", description) if not a.startswith("i:")]
    args += [f"i:{refs[name]}={value!r}" for name, value in ME_INPUTS.items()]
    for run in range(3):
        done = run_host3(host3, folder, description, "rk4", args, bare_environment(tmp_path), tmp_path)
        assert done.returncode == 0, f"run {run}: exit {done.returncode}\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}"
        assert "host-unchanged 1" in done.stdout
        # no event indicators, no step events: the one event iteration is the initial one, and it ends
        assert reported(done.stdout, "events") == 0 and reported(done.stdout, "event-iterations") == 1
        assert reported(done.stdout, "derivative-evaluations") == 4 * STEPS
        got = list(parse_outputs(done.stdout).values())
        # RK4's own error at 1 ms: below 1e-6 rad in the angles, 1e-5 rad/s in the rates
        assert got[:2] == pytest.approx(fmi2_reference[:2], abs=1e-6)
        assert got[2:4] == pytest.approx(fmi2_reference[2:4], abs=1e-5)
    assert not os.listdir(tmp_path)


def test_fmi3_co_simulation_in_a_c_host_gives_the_fmi2_numbers(host3, fmus, extracted, tmp_path):
    folder, description = extracted[FMI3]
    done = run_host3(host3, folder, description, "cs", host_arguments("DoublePendulum.fmu", description),
                     bare_environment(tmp_path), tmp_path)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    expected = fmpy_outputs(fmus["DoublePendulum.fmu"], "DoublePendulum.fmu")
    assert list(parse_outputs(done.stdout).values()) == pytest.approx(expected, rel=1e-10, abs=1e-10)


def test_an_input_jump_in_event_mode_is_booked_into_w_input(host3, extracted, tmp_path):
    """The pivot's velocity jumps from 0 to 0.5 m/s at 0.5 s (Event Mode): the kinetic energy jumps with it,
    W_input books the jump and the energy budget still closes to the integration error."""
    folder, description = extracted[FMI3]
    refs = {v.name: v.valueReference for v in description.modelVariables}
    args = [f"r:{refs['phi1_0']}=2.0", f"r:{refs['phi2_0']}=2.0", f"i:{refs['pivot_vx']}=0.0",
            f"j:{refs['pivot_vx']}=0.5@0.5", *(f"o:{refs[n]}" for n in ("energy_residual", "W_input", "E_kin"))]
    done = run_host3(host3, folder, description, "rk4", args, bare_environment(tmp_path), tmp_path)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    residual, w_input, _ = parse_outputs(done.stdout).values()
    assert reported(done.stdout, "events") == 1 and reported(done.stdout, "event-iterations") == 2
    assert abs(w_input) > 0.05  # the jump: 1/2 M v^2 plus v times the pendulum's momentum, about 0.4 J here
    assert abs(residual) < 1e-8 * max(1.0, abs(w_input))


def test_the_loader_answers_for_out_arguments_pythonfmu3_leaves_unwritten(host3, extracted, tmp_path):
    """With pythonfmu3's own result of fmi3UpdateDiscreteStates (two of its attributes misspelt, so its
    C++ layer writes neither discreteStatesNeedUpdate nor nominalsOfContinuousStatesChanged), a strict
    host that initialised discreteStatesNeedUpdate = true iterated Event Mode forever (pythonfmu3's
    own binary in fmusim). The loader initialises them: one event iteration, and the run ends."""
    import shutil
    import zipfile

    folder, description = extracted[FMI3]
    patched = tmp_path / "patched"
    shutil.copytree(folder, patched)
    archive = patched / "resources" / "python_code.zip"
    with zipfile.ZipFile(archive) as code:
        members = {name: code.read(name) for name in code.namelist()}
    (adapter,) = [name for name in members if name.endswith("_adapters/DoublePendulumFmi3.py")]
    members[adapter] += (b"\nDoublePendulum.update_discrete_states = lambda self: importlib.import_module(\n"
                         b"    f'{_library}.modelexchange').Fmi3UpdateDiscreteStatesResult()\n")
    del members[adapter + "c"]  # its bytecode, checked against the source, would not match
    with zipfile.ZipFile(archive, "w") as code:
        for name, data in members.items():
            code.writestr(name, data)
    refs = {v.name: v.valueReference for v in description.modelVariables}
    done = run_host3(host3, patched, description, "rk4", [f"o:{refs['phi1']}"], bare_environment(tmp_path), tmp_path)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert reported(done.stdout, "event-iterations") == 1


def test_fmi3_without_a_usable_python_instantiate_returns_null_and_says_why(host3, extracted, tmp_path):
    folder, description = extracted[FMI3]
    env = bare_environment(tmp_path, **{loader.OVERRIDE_VARIABLE: "/nonexistent/python3"})
    done = run_host3(host3, folder, description, "rk4", [], env, tmp_path)
    assert done.returncode == 4, done.stdout + done.stderr
    logged = [line for line in done.stdout.splitlines() if line.startswith("log ")]
    assert len(logged) == 1 and logged[0].startswith("log 3 ")  # one fmi3Error line
    assert "no usable Python to run this FMU" in logged[0] and "CPython >= 3.11" in logged[0]
