"""fmu_src/archive_import.py: the FMU's code and a carried CPython's standard library imported from their zips, read
once. It answers only for the zip's own paths (registered in ``sys.path_importer_cache``, as zipimport's finders
are), honours PEP 552 (a checked .pyc that no longer matches its source is not used; bytecode of another Python is
not used), and leaves a compressed member it cannot read to zipimport."""

from __future__ import annotations

import importlib.util
import sys
import zipfile
from pathlib import Path

import pytest
from double_pendulum.adapters import archive_import

from double_pendulum.fmu.build.bundle import pyc

PACKAGE = "_dp_fmu_test_archive"


def make_zip(path: Path, members: dict[str, bytes], method: int = zipfile.ZIP_STORED) -> Path:
    with zipfile.ZipFile(path, "w", method) as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return path


@pytest.fixture
def clean_modules():
    """Forget the test's modules and the finders it registers, whatever the test did."""
    before = set(sys.path_importer_cache)
    yield
    for name in [n for n in sys.modules if n.startswith(PACKAGE)]:
        del sys.modules[name]
    for key in set(sys.path_importer_cache) - before:
        del sys.path_importer_cache[key]


def import_from(finder: archive_import.Finder, name: str):
    spec = finder.find_spec(name)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def test_a_package_and_its_submodules_come_from_the_zip_through_path_importer_cache_only(tmp_path, clean_modules):
    source = b"VALUE = 'from source'\n"
    path = make_zip(tmp_path / "code.zip", {
        f"{PACKAGE}/__init__.py": b"from . import inner\n",
        f"{PACKAGE}/inner.py": source,
        f"{PACKAGE}/inner.pyc": pyc(source, "inner.py", checked=True),
        f"{PACKAGE}/sub/__init__.py": b"",
        f"{PACKAGE}/sub/leaf.py": b"X = 3\n",
    })
    meta_path, path_hooks, sys_path = list(sys.meta_path), list(sys.path_hooks), list(sys.path)
    top = archive_import.install(str(path))
    package = import_from(top, PACKAGE)
    assert package.inner.VALUE == "from source"
    assert importlib.import_module(f"{PACKAGE}.sub.leaf").X == 3  # through the package's __path__
    assert isinstance(package.__loader__, archive_import.Finder) and package.__loader__.archive == str(path)
    assert (sys.meta_path, sys.path_hooks, sys.path) == (meta_path, path_hooks, sys_path)  # the host's, untouched
    assert set(sys.path_importer_cache) >= {str(path), str(path / PACKAGE), str(path / PACKAGE / "sub")}
    inner = sys.modules[f"{PACKAGE}.inner"]
    assert inner.__loader__.get_source(inner.__name__) == source.decode()  # what linecache asks for a traceback
    assert top.is_package(PACKAGE) and not inner.__loader__.is_package(inner.__name__)


def test_checked_bytecode_that_no_longer_matches_its_source_is_not_used(tmp_path, clean_modules):
    path = make_zip(tmp_path / "code.zip", {
        f"{PACKAGE}.py": b"VALUE = 'edited source'\n",
        f"{PACKAGE}.pyc": pyc(b"VALUE = 'old source'\n", "m.py", checked=True),
    })
    assert import_from(archive_import.install(str(path)), PACKAGE).VALUE == "edited source"


def test_unchecked_bytecode_is_used_as_it_is_and_another_pythons_is_not(tmp_path, clean_modules):
    unchecked = pyc(b"VALUE = 'bytecode'\n", "m.py", checked=False)
    path = make_zip(tmp_path / "a.zip", {f"{PACKAGE}.py": b"VALUE = 'source'\n", f"{PACKAGE}.pyc": unchecked})
    assert import_from(archive_import.install(str(path)), PACKAGE).VALUE == "bytecode"
    del sys.modules[PACKAGE]
    other = b"\x00\x00\r\n" + unchecked[4:]  # another magic number: another Python's bytecode
    path = make_zip(tmp_path / "b.zip", {f"{PACKAGE}.py": b"VALUE = 'source'\n", f"{PACKAGE}.pyc": other})
    assert import_from(archive_import.install(str(path)), PACKAGE).VALUE == "source"


def test_a_deflated_zip_is_read_and_a_missing_module_is_none(tmp_path, clean_modules):
    path = make_zip(tmp_path / "deflated.zip", {f"{PACKAGE}.py": b"VALUE = 7\n" * 50}, zipfile.ZIP_DEFLATED)
    top = archive_import.install(str(path))
    assert import_from(top, PACKAGE).VALUE == 7
    assert top.find_spec("not_there") is None


def test_a_file_that_is_no_zip_is_an_import_error(tmp_path):
    (tmp_path / "x.zip").write_bytes(b"not a zip")
    with pytest.raises(ImportError, match="is not a zip"):
        archive_import.install(str(tmp_path / "x.zip"))
