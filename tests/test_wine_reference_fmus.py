"""The C hosts' Windows builds under Wine (tests/wine.py) against FMUs that are not the project's: what the tests of
the project's Windows binaries will rely on, shown with FMUs known to work.

These tests run only where DOUBLE_PENDULUM_REFERENCE_FMUS names a folder of modelica/Reference-FMUs models built
from their sources (the project ships neither them nor a way to build them), laid out as extracted FMUs, each with
its Linux and its Windows binary::

    fmi2/<Model>/modelDescription.xml, binaries/linux64/<Model>.so, binaries/win64/<Model>.dll, resources/
    fmi3/<Model>/modelDescription.xml, binaries/x86_64-linux/<Model>.so, binaries/x86_64-windows/<Model>.dll,
        resources/

for the models BouncingBall, VanDerPol, Feedthrough and Resource. They show: the Windows hosts print what the
Linux hosts print for the same FMU (to 1e-9), FMI 2 co-simulation and FMI 3 Model Exchange and co-simulation;
1,000 instantiate/free cycles at flat memory; two instances at once print what two single runs print; an FMU in a
folder named outside ASCII runs, with its input table there too; the resource location reaches the FMU; bad input
gives the error status and the FMU's log line.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from host_binaries import compiled_host
from wine import windows_host, windows_path

VARIABLE = "DOUBLE_PENDULUM_REFERENCE_FMUS"
ROOT = Path(os.environ.get(VARIABLE, "")) if os.environ.get(VARIABLE) else None
pytestmark = pytest.mark.skipif(ROOT is None or not ROOT.is_dir(),
                                reason=f"{VARIABLE} names no folder of Reference-FMUs models (see the docstring)")

AGREE = 1e-9
"""The largest difference between the Windows and the Linux host, relative to the output's largest magnitude (at
least 1): the same C compiled twice, apart from the C runtime's formatting and libm."""
MEMORY_GROWTH_KIB = 64
"""What the last 500 cycles (from the 500th to the 1,000th) may add to the process's private memory: by then the
allocators have settled (the project's DoublePendulum.fmu in the Linux host grows by one step of 1 MiB between
the 100th and the 200th cycle, then not at all; the Reference FMUs by nothing after the first). A build of
BouncingBall leaking 1,000 bytes a cycle fails it on both platforms (measured over 500 cycles: 492 KiB under Wine,
528 KiB on Linux, whose heap grows in steps of 132 KiB)."""
NON_ASCII = "Fmüß-π"

# model: (STEPS, STEP_SIZE) of the runs compared
RUNS = {"BouncingBall": (300, 0.01), "VanDerPol": (300, 0.01), "Feedthrough": (20, 0.1)}


@pytest.fixture(scope="module")
def hosts(tmp_path_factory: pytest.TempPathFactory) -> dict[tuple[str, int], Path]:
    """The hosts by (platform, FMI version): the Linux builds (host_binaries) and the Windows ones (wine)."""
    return {("linux", 2): compiled_host(tmp_path_factory, "fmi2_host"),
            ("linux", 3): compiled_host(tmp_path_factory, "fmi3_host"),
            ("windows", 2): windows_host(tmp_path_factory, "fmi2_host"),
            ("windows", 3): windows_host(tmp_path_factory, "fmi3_host")}


def model(version: int, name: str) -> tuple[Path, object]:
    """The extracted FMU of ``name`` for FMI ``version`` and its model description."""
    from fmpy import read_model_description

    folder = ROOT / f"fmi{version}" / name
    return folder, read_model_description(str(folder))


def arguments(version: int, name: str, folder: Path, method: str, extra: list[str],
              steps: int | None = None) -> list:
    """A host's command line after the program: the FMU, its identifier and token, (FMI 3: METHOD,) the run of
    RUNS, every Float64 output recorded at every step and read at the end, and ``extra``."""
    _, description = model(version, name)
    n, h = RUNS.get(name, (10, 0.1))
    outputs = [v.valueReference for v in description.modelVariables
               if v.causality == "output" and v.type in ("Real", "Float64")]
    identifier = (description.coSimulation or description.modelExchange).modelIdentifier
    return [folder, identifier, description.guid, *([method] if version == 3 else []), str(steps or n), repr(h),
            *(f"O:{vr}" for vr in outputs), *(f"o:{vr}" for vr in outputs), *extra]


def run(wine, hosts, platform: str, version: int, args: list, cwd: Path):
    """Run a host on ``platform`` (Windows under Wine, Linux directly) with ``args``; its CompletedProcess."""
    host = hosts[(platform, version)]
    if platform == "windows":
        return wine.run(host, args, cwd=cwd)
    command = [str(host), *(str(a) for a in args)]
    return subprocess.run(command, capture_output=True, text=True, cwd=cwd, timeout=120,
                          env={"PATH": "/usr/bin:/bin", "HOME": str(cwd)})


def numbers(stdout: str, prefix: str = "") -> dict[str, np.ndarray]:
    """The rows ("row T V ...") and the outputs ("VR V") a host printed (those prefixed by ``prefix``), as arrays."""
    lines = [line[len(prefix):].split() for line in stdout.splitlines() if line.startswith(prefix)]
    rows = np.array([[float(v) for v in line[1:]] for line in lines if line[0] == "row"])
    outputs = {line[0]: float(line[1]) for line in lines if line[0].isdigit() and len(line) == 2}
    return {"rows": rows, **{f"vr {vr}": np.array([value]) for vr, value in outputs.items()}}


def deviation(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> float:
    """The largest difference of ``a`` and ``b`` (the same keys and shapes), relative to each column's magnitude."""
    assert a.keys() == b.keys() and all(a[k].shape == b[k].shape for k in a), (a.keys(), b.keys())
    worst = 0.0
    for key in a:
        x, y = np.atleast_2d(a[key]), np.atleast_2d(b[key])
        if x.size:
            scale = np.maximum(1.0, np.max(np.abs(x), axis=0))
            worst = max(worst, float(np.max(np.abs(x - y) / scale)))
    return worst


def ok(done: subprocess.CompletedProcess[str]) -> str:
    """The stdout of a clean run (exit 0, the host's environment unchanged); fails the test with what it printed
    otherwise."""
    assert done.returncode == 0, f"exit {done.returncode}\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}"
    assert "host-unchanged 1" in done.stdout
    return done.stdout


CASES = [(2, name, "cs") for name in RUNS] + [(3, name, method) for name in RUNS for method in ("cs", "rk4")]


@pytest.mark.parametrize(("version", "name", "method"), CASES, ids=[f"fmi{v}-{n}-{m}" for v, n, m in CASES])
def test_the_windows_host_prints_what_the_linux_host_prints(wine, hosts, tmp_path, version, name, method):
    folder, _ = model(version, name)
    extra = ["i:7=0.5"] if name == "Feedthrough" else []  # a continuous input (FMI 3 sets a discrete one in Event Mode)
    linux = ok(run(wine, hosts, "linux", version, arguments(version, name, folder, method, extra), tmp_path))
    windows = ok(run(wine, hosts, "windows", version, arguments(version, name, folder, method, extra), tmp_path))
    got = deviation(numbers(windows), numbers(linux))
    print(f"fmi{version} {name} {method}: {len(numbers(linux)['rows'])} rows, largest relative difference {got:.2g}")
    assert len(numbers(linux)["rows"]) == RUNS[name][0] + 1
    assert got <= AGREE
    if version == 3:  # the same event handling: the same counts
        counts = [line for line in linux.splitlines() if line.startswith(("events", "event-it", "derivative"))]
        assert counts and all(line in windows.splitlines() for line in counts), counts


@pytest.mark.parametrize("platform", ["windows", "linux"])
@pytest.mark.parametrize(("version", "method"), [(2, "cs"), (3, "cs"), (3, "rk4")])
def test_a_thousand_instantiate_free_cycles_keep_memory_flat(wine, hosts, tmp_path, platform, version, method):
    folder, _ = model(version, "BouncingBall")
    done = run(wine, hosts, platform, version, arguments(version, "BouncingBall", folder, method, ["c:1000"], 1),
               tmp_path)
    out = ok(done)
    memory = {int(c): int(kib) for _, c, kib in (line.split() for line in out.splitlines()
                                                   if line.startswith("memory-kib "))}
    assert sorted(memory) == [1, *range(100, 1001, 100)], memory
    assert min(memory.values()) > 0, memory  # a measure, not a placeholder
    print(f"{platform} fmi{version} {method}: memory over 1,000 cycles (KiB) {memory}")
    assert memory[1000] - memory[500] <= MEMORY_GROWTH_KIB, memory
    assert numbers(out)["vr 1"].size == 1  # the outputs printed once, after the last cycle


@pytest.mark.parametrize("platform", ["windows", "linux"])
@pytest.mark.parametrize(("version", "method"), [(2, "cs"), (3, "cs"), (3, "rk4")])
def test_two_instances_at_once_print_what_two_single_runs_print(wine, hosts, tmp_path, platform, version, method):
    """Two BouncingBalls alive together, stepped alternately, each with start values of its own (and so bounces,
    events under Model Exchange, of its own)."""
    folder, _ = model(version, "BouncingBall")
    first, second = ["r:1=1.5", "r:6=0.8"], ["r:1=0.7", "r:6=0.6", "r:3=1"]

    def single(start: list[str]) -> str:
        return ok(run(wine, hosts, platform, version, arguments(version, "BouncingBall", folder, method, start),
                      tmp_path))

    one, two = single(first), single(second)
    own = 6 if version == 3 else 5  # the arguments before the ARGs
    args = [*arguments(version, "BouncingBall", folder, method, first), "+",
            *arguments(version, "BouncingBall", folder, method, second)[own:]]
    both = ok(run(wine, hosts, platform, version, args, tmp_path))
    assert deviation(numbers(both, "instance 1 "), numbers(one)) == 0.0
    assert deviation(numbers(both, "instance 2 "), numbers(two)) == 0.0
    assert deviation(numbers(one), numbers(two)) > 0.1  # the start values made two different runs
    assert [line for line in both.splitlines() if line.startswith("row")] == []  # every line of an instance prefixed
    if version == 3:  # and the counts of events, each its own
        for k, alone in ((1, one), (2, two)):
            counts = [line for line in alone.splitlines() if line.startswith(("events", "event-it", "derivative"))]
            assert counts and all(f"instance {k} {line}" in both.splitlines() for line in counts), (counts, both)


@pytest.mark.parametrize(("version", "method"), [(2, "cs"), (3, "cs"), (3, "rk4")])
def test_an_fmu_and_its_input_table_in_a_folder_named_outside_ascii(wine, hosts, tmp_path, version, method):
    """Feedthrough copied into tmp/Fmüß-π/, its inputs from a table beside it (f:Z:\\...\\Fmüß-π\\in.csv): the same
    numbers as from its own folder with the table elsewhere."""
    folder, _ = model(version, "Feedthrough")
    table = "time,7\n0,0\n1,2\n2,0\n"
    (tmp_path / "in.csv").write_text(table)
    plain = ok(wine.run(hosts[("windows", version)],
                        arguments(version, "Feedthrough", folder, method, [f"f:{windows_path(tmp_path / 'in.csv')}"]),
                        cwd=tmp_path))
    moved = tmp_path / NON_ASCII / "Feedthrough"
    shutil.copytree(folder, moved)
    (moved.parent / "in.csv").write_text(table)
    args = arguments(version, "Feedthrough", moved, method, [f"f:{windows_path(moved.parent / 'in.csv')}"])
    there = ok(wine.run(hosts[("windows", version)], args, cwd=tmp_path))
    assert deviation(numbers(there), numbers(plain)) == 0.0
    assert np.ptp(numbers(there)["rows"][:, 1]) > 1  # the table's inputs reached the outputs


@pytest.mark.parametrize("version", [2, 3])
def test_the_resource_location_reaches_the_fmu(wine, hosts, tmp_path, version):
    """Resource reads resources/y.txt at initialisation from the location the host gives it (FMI 2 a file URI, FMI 3
    a path); where it cannot, it logs an error and fails. (Its Windows code reads the location in the ANSI code page,
    so it is run from an ASCII folder: tests/test_wine.py shows the hosts reading a non-ASCII one.)"""
    folder, description = model(version, "Resource")
    method = ["cs"] if version == 3 else []
    done = wine.run(hosts[("windows", version)], [folder, "Resource", description.guid, *method, "2", "1.0"],
                    cwd=tmp_path)
    ok(done)
    assert "log " not in done.stdout
    broken = tmp_path / "Resource"
    shutil.copytree(folder, broken)
    (broken / "resources" / "y.txt").unlink()  # what a wrong location would look like
    done = wine.run(hosts[("windows", version)], [broken, "Resource", description.guid, *method, "2", "1.0"],
                    cwd=tmp_path)
    assert done.returncode == 5 and "Failed to open resource file" in done.stdout, done.stdout + done.stderr


@pytest.mark.parametrize("platform", ["windows", "linux"])
@pytest.mark.parametrize(("version", "method"), [(2, "cs"), (3, "cs"), (3, "rk4")])
def test_bad_input_gives_the_error_status_and_the_fmus_log_line(wine, hosts, tmp_path, platform, version, method):
    """A start value for a value reference the FMU does not have: fmi2Error / fmi3Error (3) from the set call, the
    FMU's error through the host's logger, and the host's exit status 5."""
    folder, _ = model(version, "BouncingBall")
    done = run(wine, hosts, platform, version, arguments(version, "BouncingBall", folder, method, ["r:99=1"]),
               tmp_path)
    assert done.returncode == 5, done.stdout + done.stderr
    assert "log 3 logStatusError: Unexpected value reference: 99." in done.stdout.splitlines(), done.stdout
    assert done.stderr.strip().endswith("failed with status 3"), done.stderr
