"""Nothing to install: every FMU ``double-pendulum build`` writes runs where no Python is installed, on x86_64 Linux
and Windows, with the CPython it carries (fmu/build/carried_python.py).

**Linux, no Python anywhere.** The C hosts (tests/c_host) run each FMU in a bubblewrap sandbox whose root holds
only the C libraries, the host and the FMU (tests/sandbox.py): the default experiment gives the FMU's own
reference result (extra/org.fmi-standard.fmi-ls-ref) and fmpy's numbers on this machine to 1e-12 of each output's
scale (Model Exchange: the host's RK4 within its error), debug logging says the FMU's Python is the one it
carries, and one libpython is in the process, the container's two FMUs included. A lean FMU (no CPython of its
own) in the same sandbox finds none and says so: the sandbox has no Python.

**Windows under Wine.** The same hosts, cross-compiled with zig, run the win64 binaries in a Wine prefix with no
Python (tests/wine.py): the default experiment against the reference (a regular case, to 1e-9), the chaotic case
over 1 s against fmpy's Linux run (the C runtimes' libm may differ in the last bits: to 1e-8), 1,000
instantiate/free cycles at flat memory, two instances at once, bad input (fmi2Error and its log line), a folder
named outside ASCII, and the FMI 3 FMU under Model Exchange and Co-Simulation. The container carries fmpy's
Linux binary only (its Windows one could not be run here: fmu/build/container.py), its members their Windows
binaries. (fmusim and the FMI Compliance Checker run the FMUs where they are installed:
tests/test_reference_result.py, tests/test_cross_check.py.)
"""

from __future__ import annotations

import io
import shutil
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import sandbox
from host_binaries import compiled_host

from double_pendulum.fmu.carries.reference_result import FOLDER

CASES = {  # id: (file in the build folder, FMI version, model identifier, host method (FMI 3), bound)
    "fmi2": ("DoublePendulum.fmu", 2, "DoublePendulum", None, 1e-12),
    "suspension": ("Suspension.fmu", 2, "Suspension", None, 1e-12),
    # the container's own time grid sums its macro steps: 1e-13 of the range (tests/test_reference_result.py)
    "container": ("PendulumOnSuspension.fmu", 2, "container_fmu", None, 1e-11),
    "fmi3-cs": ("fmi3/DoublePendulum.fmu", 3, "DoublePendulum", "cs", 1e-12),
    # the host's RK4 at 1 ms against the FMU's integrator at its tolerance: 1.5e-9 of the range measured
    "fmi3-me": ("fmi3/DoublePendulum.fmu", 3, "DoublePendulum", "rk4", 1e-6),
}
ME_STEP = 1e-3  # the host's RK4 step under Model Exchange [s]
CHAOTIC = {"phi1_0": 2.0, "phi2_0": 2.0}  # the chaotic start compared over 1 s under Wine


@dataclass(frozen=True)
class Built:
    """One case's FMU as built, extracted, its model description and its own reference result."""

    case: str
    fmu: Path
    folder: Path
    description: Any
    reference: np.ndarray

    @property
    def outputs(self) -> list[str]:
        return [v.name for v in self.description.modelVariables if v.causality == "output"]

    def arguments(self, start: dict[str, float] | None = None, stop: float | None = None,
                  folder: Path | None = None) -> list[str]:
        """The host's command line after the program: the default experiment (or to ``stop``) at the interval of
        the reference result, every output recorded at every communication point, ``start`` values set."""
        _, version, identifier, method, _ = CASES[self.case]
        times = self.reference["time"]
        step, stop = float(times[1] - times[0]), float(times[-1]) if stop is None else stop
        variables = {v.name: v for v in self.description.modelVariables}
        outputs = [v.valueReference for v in self.description.modelVariables if v.causality == "output"]
        token = self.description.guid if version == 2 else self.description.instantiationToken
        starts = [f"r:{variables[n].valueReference}={v!r}" for n, v in (start or {}).items()]
        head = [str(folder or self.folder), identifier, token, *([method] if method else [])]
        if method == "rk4":  # Model Exchange: RK4 at ME_STEP, a row every output interval
            return [*head, str(round(stop / ME_STEP)), repr(ME_STEP), *starts, *(f"O:{vr}" for vr in outputs),
                    f"e:{round(step / ME_STEP)}"]
        return [*head, str(round(stop / step)), repr(step), *starts, *(f"O:{vr}" for vr in outputs)]


def reference(fmu: Path) -> np.ndarray:
    """The FMU's own reference result: time and every output of its default experiment."""
    with zipfile.ZipFile(fmu) as archive:
        name = next(n for n in archive.namelist() if n.startswith(FOLDER) and n.endswith("_out.csv"))
        return np.genfromtxt(io.StringIO(archive.read(name).decode()), delimiter=",", names=True, deletechars="")


@pytest.fixture(scope="module")
def built(built_fmus: list[Path], tmp_path_factory: pytest.TempPathFactory) -> dict[str, Built]:
    """Each case, by its id."""
    from fmpy import extract, read_model_description

    folder = built_fmus[0].parent
    root = tmp_path_factory.mktemp("self_contained")
    out = {}
    for case, (name, *_) in CASES.items():
        fmu = folder / name
        out[case] = Built(case, fmu, Path(extract(str(fmu), str(root / case))), read_model_description(str(fmu)),
                          reference(fmu))
    return out


def rows(stdout: str, prefix: str = "") -> np.ndarray:
    """The host's "row T VALUE ..." lines as an array (time first)."""
    lines = [line[len(prefix):].split()[1:] for line in stdout.splitlines() if line.startswith(prefix + "row ")]
    return np.array(lines, dtype=float)


def reported(stdout: str, key: str) -> str:
    return next(line.split(" ", 1)[1] for line in stdout.splitlines() if line.startswith(key + " "))


def assert_matches(result: np.ndarray, expected: np.ndarray, names: list[str], bound: float, what: str) -> None:
    """``result`` (rows of time and outputs) against ``expected`` (a structured array of the same outputs), every
    output to ``bound`` of its scale (its range, or its size where larger)."""
    assert result.shape == (len(expected), 1 + len(names)), (what, result.shape, len(expected))
    np.testing.assert_allclose(result[:, 0], expected["time"], rtol=0, atol=1e-9)
    for column, name in enumerate(names, start=1):
        scale = max(float(np.ptp(expected[name])), float(np.max(np.abs(expected[name]))), 1e-300)
        difference = float(np.max(np.abs(result[:, column] - expected[name])))
        assert difference <= bound * scale, f"{what} {name}: {difference:.3g} > {bound:g} x {scale:.3g}"


# ------------------------------------------------------------------------------------------- Linux, no Python

needs_sandbox = pytest.mark.skipif(sandbox.unavailable() is not None, reason=str(sandbox.unavailable()))


@pytest.fixture(scope="module")
def linux_hosts(tmp_path_factory: pytest.TempPathFactory) -> dict[int, Path]:
    return {2: compiled_host(tmp_path_factory, "fmi2_host"), 3: compiled_host(tmp_path_factory, "fmi3_host")}


@needs_sandbox
@pytest.mark.parametrize("case", list(CASES))
def test_in_a_root_without_python_each_fmu_gives_its_reference_and_fmpys_numbers(built, linux_hosts, case):
    from fmpy import simulate_fmu

    it = built[case]
    _, version, _, method, bound = CASES[case]
    done = sandbox.run(linux_hosts[version], it.folder, [*it.arguments(), "l:1"])
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    result = rows(done.stdout)
    assert_matches(result, it.reference, it.outputs, bound, f"{case} against its reference")
    assert "the CPython this FMU carries" in done.stdout  # the debug log: which Python runs, and why
    assert reported(done.stdout, "pythons-loaded") == "1"  # one libpython in the process (two FMUs: the container)
    assert reported(done.stdout, "host-unchanged") == "1"
    if method != "rk4":  # fmpy on this machine, with the host's Python, gets the same numbers
        times = it.reference["time"]
        expected = simulate_fmu(str(it.fmu), output_interval=float(times[1] - times[0]), fmi_type="CoSimulation")
        assert_matches(result, expected, it.outputs, 1e-12, f"{case} against fmpy")


@needs_sandbox
def test_a_lean_fmu_in_the_same_root_finds_no_python_and_says_so(built, linux_hosts, tmp_path):
    """The negative control: built --lean, the FMU has no CPython of its own, and the sandbox has none to find
    (not the build's, whose path it records, nor a python3 on PATH): NULL and one line saying what it looked for."""
    from fmpy import extract

    from double_pendulum.fmu.build.fmi2 import build_fmu

    lean = build_fmu(tmp_path / "lean" / "DoublePendulum.fmu", lean=True)
    folder = Path(extract(str(lean), str(tmp_path / "extracted")))
    from fmpy import read_model_description

    it = Built("fmi2", lean, folder, read_model_description(str(lean)), built["fmi2"].reference)
    done = sandbox.run(linux_hosts[2], folder, it.arguments(stop=0.1))
    assert done.returncode == 4, done.stdout + done.stderr  # fmi2Instantiate returned NULL
    logged = [line for line in done.stdout.splitlines() if line.startswith("log ")]
    assert len(logged) == 1 and "no usable Python to run this FMU" in logged[0], logged
    assert "the build's Python" in logged[0] and "python3 on PATH" in logged[0], logged


# ----------------------------------------------------------------------------------------- Windows under Wine

@pytest.fixture(scope="module")
def windows_hosts(tmp_path_factory: pytest.TempPathFactory) -> dict[int, Path]:
    from wine import windows_host

    return {2: windows_host(tmp_path_factory, "fmi2_host"), 3: windows_host(tmp_path_factory, "fmi3_host")}


@pytest.mark.parametrize("case", [case for case in CASES if case != "container"])
def test_under_wine_each_fmu_gives_its_reference(wine, windows_hosts, built, case, tmp_path):
    """The regular default experiment to 1e-9 of each output's scale (Model Exchange: the host's RK4, as on
    Linux), run by the CPython the FMU carries for Windows. (The container is Linux's only: fmpy's Windows
    container binary links bcryptprimitives.dll, which Wine 8 lacks; fmu/build/container.py.)"""
    it = built[case]
    _, version, _, method, bound = CASES[case]
    done = wine.run(windows_hosts[version], [*it.arguments(), "l:1"], cwd=tmp_path)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert_matches(rows(done.stdout), it.reference, it.outputs, max(bound, 1e-9), case)
    assert "the CPython this FMU carries" in done.stdout and "python3" in done.stdout
    assert reported(done.stdout, "pythons-loaded") == "1"
    assert reported(done.stdout, "host-unchanged") == "1"


def test_under_wine_the_chaotic_case_follows_linux_over_a_second(wine, windows_hosts, built, tmp_path):
    from fmpy import simulate_fmu

    it = built["fmi2"]
    done = wine.run(windows_hosts[2], it.arguments(CHAOTIC, stop=1.0), cwd=tmp_path)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    expected = simulate_fmu(str(it.fmu), start_values=CHAOTIC, stop_time=1.0, output_interval=0.01)
    assert_matches(rows(done.stdout), expected, it.outputs, 1e-8, "chaotic start under Wine")


def test_under_wine_a_thousand_instantiate_free_cycles_keep_memory_flat(wine, windows_hosts, built, tmp_path):
    """1,000 cycles of instantiate, one step, free, after a warm-up of 700, in one process with the library loaded
    once: the private memory grows by less than 0.2 KiB a cycle (the bound of the Linux hosts' soak). The warm-up:
    the memory rises over the first 500 cycles and takes one more allocator block of about 400 KiB once, between
    cycles 500 and 600 in every run seen, then stays flat to the last KiB."""
    done = wine.run(windows_hosts[2], [*built["fmi2"].arguments(stop=0.01), "c:1700"], cwd=tmp_path, timeout=600)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    memory = {int(c): int(kib) for _, c, kib in (line.split() for line in done.stdout.splitlines()
                                                   if line.startswith("memory-kib "))}
    assert sorted(memory) == [1, *range(100, 1701, 100)] and min(memory.values()) > 0, memory
    print(f"memory under Wine over 1,700 cycles (KiB): {memory}")
    assert (memory[1700] - memory[700]) / 1000 < 0.2, memory


def test_under_wine_two_instances_at_once_give_two_single_runs(wine, windows_hosts, built, tmp_path):
    it = built["fmi2"]
    first, second = it.arguments({"phi1_0": 1.5}, stop=0.5), it.arguments({"phi1_0": 0.5}, stop=0.5)
    both = wine.run(windows_hosts[2], [*first, "+", *second[5:]], cwd=tmp_path)  # the second's own values
    assert both.returncode == 0, both.stdout[-3000:] + both.stderr[-3000:]
    for k, arguments in ((1, first), (2, second)):
        alone = wine.run(windows_hosts[2], arguments, cwd=tmp_path)
        assert alone.returncode == 0, alone.stdout[-3000:] + alone.stderr[-3000:]
        assert np.array_equal(rows(both.stdout, f"instance {k} "), rows(alone.stdout)), k
    assert not np.array_equal(rows(both.stdout, "instance 1 "), rows(both.stdout, "instance 2 "))
    assert reported(both.stdout, "pythons-loaded") == "1"


@pytest.mark.parametrize("value", ["nan", "-0.3"])
def test_under_wine_bad_input_is_an_error_with_its_log_line(wine, windows_hosts, built, tmp_path, value):
    it = built["fmi2"]
    m1 = next(v.valueReference for v in it.description.modelVariables if v.name == "m1")
    arguments = it.arguments(stop=0.1)
    done = wine.run(windows_hosts[2], [*arguments[:5], f"r:{m1}={value}", *arguments[5:]], cwd=tmp_path)
    assert done.returncode == 5, done.stdout[-3000:] + done.stderr[-3000:]  # a call failed, the host went on
    assert "failed with status 3" in done.stderr  # fmi2Error
    logged = [line for line in done.stdout.splitlines() if line.startswith("log 3 ")]
    assert logged and "m1" in logged[0], done.stdout


def test_under_wine_an_fmu_in_a_folder_named_outside_ascii_runs(wine, windows_hosts, built, tmp_path):
    it = built["fmi3-cs"]
    moved = Path(shutil.copytree(it.folder, tmp_path / "Fmüß-π €" / "DoublePendulum"))
    done = wine.run(windows_hosts[3], it.arguments(stop=1.0, folder=moved), cwd=tmp_path)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert_matches(rows(done.stdout), it.reference[:101], it.outputs, 1e-9, "non-ASCII folder")
