"""The Wine harness (tests/wine.py) itself: the C hosts' Windows builds run under Wine in a private prefix that shows
them no Python, read a non-ASCII folder from their command line, look for the FMU's binary where FMI puts the
Windows one, and leave no process behind. No FMU is needed here (tests/test_wine_reference_fmus.py runs independent
FMUs where they are at hand); where wine64 or zig is missing the tests that need them skip, saying which."""

from __future__ import annotations

from pathlib import Path

import pytest
from wine import LOADER, WINE_MISSING, Wine, windows_host, windows_path

NON_ASCII = "Fmüß-π"
"""A folder name outside ASCII and outside every ANSI code page (π), which a host reading its command line in the
code page would get wrong."""


@pytest.fixture(scope="module")
def hosts(tmp_path_factory: pytest.TempPathFactory) -> dict[int, Path]:
    """The Windows builds of tests/c_host/fmi2_host.c and fmi3_host.c by FMI version (compiled once a session)."""
    return {2: windows_host(tmp_path_factory, "fmi2_host"), 3: windows_host(tmp_path_factory, "fmi3_host")}


def test_a_linux_path_becomes_its_wine_path(tmp_path, monkeypatch):
    assert windows_path(Path("/tmp/a b/Fmüß-π/x.dll")) == "Z:\\tmp\\a b\\Fmüß-π\\x.dll"
    monkeypatch.chdir(tmp_path)
    assert windows_path("rel") == "Z:" + str(tmp_path).replace("/", "\\") + "\\rel"  # relative to the cwd


def test_the_environment_is_minimal_and_has_no_python(tmp_path):
    """What a Wine process gets: nothing of the test process's environment, a Linux PATH for Wine's own helpers
    only, a UTF-8 locale, Wine's settings, HOME in the harness's folder, and no PYTHON* variable."""
    env = Wine(tmp_path, LOADER, LOADER.parent / "wineserver").environment({"EXTRA": "1"})
    assert set(env) == {"PATH", "HOME", "LANG", "WINEPREFIX", "WINEDEBUG", "WINEDLLOVERRIDES", "EXTRA"}
    assert env["PATH"] == "/usr/bin:/bin" and env["LANG"] == "C.UTF-8" and env["WINEDEBUG"] == "-all"
    assert env["HOME"] == str(tmp_path / "home") and env["WINEPREFIX"] == str(tmp_path / "prefix")
    assert "winemenubuilder.exe=d" in env["WINEDLLOVERRIDES"]  # no menu entries written into a HOME


def test_the_windows_side_sees_a_bare_path_and_no_python(wine, tmp_path):
    done = wine.run("cmd", ["/c", "set"], cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    variables = dict(line.split("=", 1) for line in done.stdout.splitlines() if "=" in line)
    assert not [name for name in variables if name.upper().startswith("PYTHON")]
    path = variables["PATH"].lower().split(";")
    assert path and all(entry.startswith("c:\\windows") for entry in path), path  # Wine's own, not Linux's PATH
    drive_c = wine.prefix / "drive_c"
    assert not [p for p in drive_c.rglob("python*") if p.suffix.lower() in (".exe", ".dll")]


@pytest.mark.parametrize(("version", "binary"), [(2, "win64"), (3, "x86_64-windows")])
def test_a_host_reads_a_non_ascii_folder_and_looks_for_the_windows_binary(wine, hosts, tmp_path, version, binary):
    """Given an extracted FMU's folder by a non-ASCII name (here without a binary), the host gets the name whole
    from its command line and looks for binaries/win64/ID.dll (FMI 3: binaries/x86_64-windows/ID.dll) in it: exit
    status 3 (library not loaded), naming the path it tried."""
    folder = tmp_path / NON_ASCII
    folder.mkdir()
    arguments = [folder, "Model", "{token}", *(["cs"] if version == 3 else []), "1", "0.1"]
    done = wine.run(hosts[version], arguments, cwd=tmp_path)
    assert done.returncode == 3, done.stdout + done.stderr
    assert done.stderr.startswith(f"cannot load {windows_path(folder)}\\binaries\\{binary}\\Model.dll: error "), \
        done.stderr


@pytest.mark.parametrize("version", [2, 3])
def test_bad_usage_and_a_path_too_long_are_refused(wine, hosts, tmp_path, version):
    method = ["cs"] if version == 3 else []
    done = wine.run(hosts[version], ["only", "two"], cwd=tmp_path)
    assert done.returncode == 2 and "usage:" in done.stderr, done.stderr
    long = tmp_path / ("x" * 250) / ("y" * 250) / ("z" * 250) / ("w" * 250) / ("v" * 250)  # > 1,000 characters
    done = wine.run(hosts[version], [long, "Model" * 700, "{token}", *method, "1", "0.1"], cwd=tmp_path)
    assert done.returncode == 2 and "the FMU's path is too long" in done.stderr, done.stderr
    done = wine.run(hosts[version], [tmp_path, "Model", "{token}", *method, "1", "0.1", "q:1"], cwd=tmp_path)
    assert done.returncode == 2 and "bad argument q:1" in done.stderr, done.stderr


def test_ending_the_prefix_leaves_no_process_and_a_later_run_starts_it_again(wine, hosts, tmp_path):
    done = wine.run(hosts[2], [tmp_path, "Model", "{guid}", "1", "0.1"], cwd=tmp_path)
    assert done.returncode == 3, done.stdout + done.stderr
    wine.end_processes()
    assert wine.processes() == []
    assert wine.run(hosts[2], [tmp_path, "Model", "{guid}", "1", "0.1"], cwd=tmp_path).returncode == 3


def test_the_skip_reason_names_the_package(monkeypatch, tmp_path_factory):
    """Without wine64 the fixture skips, saying what to install."""
    import wine as harness

    monkeypatch.setattr(harness, "wine_loader", lambda: None)
    with pytest.raises(pytest.skip.Exception, match="wine64 is not installed"):
        next(Wine.session(tmp_path_factory))
    assert WINE_MISSING == "wine64 is not installed (apt-get install wine64)"
