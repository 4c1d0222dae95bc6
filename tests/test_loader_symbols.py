"""What the FMUs' Linux binaries ask of a target machine, read from the built binaries (docs/fmu.md,
"What a target machine needs"): each FMU's loader asks only for glibc 2.17 symbol versions and the C libraries (so
it loads on older systems and can say what is missing); the CPython it carries asks for what the building one
was built against."""

from __future__ import annotations

import importlib.util
import sys
import zipfile
from pathlib import Path

import pytest

from double_pendulum.fmu.build import loader
from double_pendulum.fmu.carries import elf_needs

DOCS = Path(__file__).resolve().parents[1] / "docs" / "fmu.md"
GLIBC_FLOOR = "GLIBC_2.17"  # CentOS 7, manylinux2014
C_LIBRARIES = {"libc.so.6", "libdl.so.2", "libpthread.so.0", "libm.so.6"}

pytestmark = [
    pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the loader is for Linux"),
    pytest.mark.skipif(loader.c_compiler() is None, reason="no C compiler: the FMUs cannot be built"),
]


def binaries(fmu_path: Path) -> dict[str, bytes]:
    """Every FMU's Linux loader (its binary named after the model: ``binaries/<platform>/<Model>.so``; the CPython
    it carries beside it is not the loader's), by ``<FMU>/<file>``."""
    out = {}
    for fmu in (fmu_path, fmu_path.parent / "Suspension.fmu", fmu_path.parent / "fmi3" / "DoublePendulum.fmu"):
        with zipfile.ZipFile(fmu) as archive:
            for name in archive.namelist():
                if name.startswith("binaries/") and name.endswith((f"/{fmu.stem}.so", "/Suspension.so")):
                    out[f"{fmu.parent.name}/{fmu.name}/{name}"] = archive.read(name)
    return out


def test_the_carried_pythons_glibc_floor_is_read_from_its_files_and_stated(fmu_path):
    """The carried Linux CPython asks for what the building interpreter was built against: the FMU's page states
    the newest glibc version any of its Linux files needs, and docs/fmu.md the one of the build these docs were
    made with (CPython 3.11.7 of pyenv on Debian 12: glibc 2.35)."""
    import re

    with zipfile.ZipFile(fmu_path) as archive:
        files = {n: archive.read(n) for n in archive.namelist() if n.startswith("binaries/linux64/")}
        page = archive.read("documentation/index.html").decode()
    floors = [elf_needs.newest(elf_needs.version_needs(d), "GLIBC") for d in files.values() if d[:4] == b"\x7fELF"]
    floor = max((f for f in floors if f), key=elf_needs.version_key).partition("_")[2]
    row = re.search(r"<tr><td><code>binaries/linux64/</code></td>(.*?)</tr>", page).group(1)
    assert f"glibc &gt;= {floor}<" in row, row
    if sys.version.startswith("3.11.7 ") and "pyenv" in sys.base_prefix:
        assert f"glibc {floor}" in DOCS.read_text() and floor == "2.35"


def test_the_loader_asks_only_for_old_glibc_symbol_versions_and_the_c_libraries(fmu_path):
    loaders = binaries(fmu_path)
    assert len(loaders) == 3 and all(name.endswith("/DoublePendulum.so") or name.endswith("/Suspension.so")
                                     for name in loaders), sorted(loaders)  # no FMI library's binary beside it
    for name, data in loaders.items():
        needs = elf_needs.version_needs(data)
        assert set(needs) <= C_LIBRARIES, f"{name} links {set(needs) - C_LIBRARIES}"  # no libstdc++, no libpython
        newest = elf_needs.newest(needs, "GLIBC")
        assert elf_needs.version_key(newest) <= elf_needs.version_key(GLIBC_FLOOR), f"{name} needs {newest}"


def test_the_docs_state_what_the_binary_needs(fmu_path):
    """docs/fmu.md names the glibc floor the loader is held to."""
    assert "glibc 2.17" in DOCS.read_text()


def test_the_version_reader_reads_what_the_loader_was_built_with(fmu_path):
    data = next(data for name, data in binaries(fmu_path).items() if name.endswith("linux64/DoublePendulum.so"))
    needs = elf_needs.version_needs(data)
    assert "GLIBC_2.2.5" in needs["libc.so.6"] or "GLIBC_2.17" in needs["libc.so.6"]
    assert elf_needs.describe(data).startswith("glibc >= 2.")
    with pytest.raises(ValueError, match="not a 64-bit"):
        elf_needs.version_needs(b"#!/bin/sh\n")


@pytest.mark.skipif(importlib.util.find_spec("ziglang") is None, reason="the ziglang package is not installed")
def test_zigs_compiler_builds_a_loader_that_runs_like_the_system_compilers(fmu_path, tmp_path, monkeypatch):
    """Where a machine has no C compiler, Zig's (from pip) builds the FMUs: the same floor of glibc symbol
    versions, the same C libraries, the same numbers."""
    from fmpy import simulate_fmu

    from double_pendulum.fmu.build.fmi2 import build_fmu

    monkeypatch.setenv("CC", f"{sys.executable} -m ziglang cc")
    assert "ziglang" in " ".join(loader.c_compiler())
    built = build_fmu(tmp_path / "DoublePendulum.fmu")
    with zipfile.ZipFile(built) as archive:
        data = archive.read("binaries/linux64/DoublePendulum.so")
    needs = elf_needs.version_needs(data)
    assert set(needs) <= C_LIBRARIES
    assert elf_needs.version_key(elf_needs.newest(needs, "GLIBC")) <= elf_needs.version_key(GLIBC_FLOOR)
    runs = [simulate_fmu(str(path), stop_time=0.2, output_interval=0.1, start_values={"phi1_0": 1.0},
                         output=["phi1"])["phi1"][-1] for path in (built, fmu_path)]
    assert runs[0] == runs[1]
