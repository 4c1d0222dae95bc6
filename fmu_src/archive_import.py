"""Import the FMU's code, and the standard library of the CPython the FMU carries, from their zips, once read.

The FMU's code is one zip (``resources/python_code.zip``), a carried CPython's standard library another
(``binaries/<platform>/python3X.zip``). zipimport, pure Python, opens the zip, reads and checks a local header and
copies the bytes again for every module: at an FMU's first instantiation, some 150 modules, that made the start of
the FMU in a C host 16 % slower than from files (instructions counted with callgrind). :func:`install` reads a zip
once, keeps its bytes and answers for it from them: each module's bytecode is unmarshalled from a view of those
bytes, checked as PEP 552 says (a checked hash-based .pyc against the source beside it; bytecode of another
Python version is not used: the source is compiled instead).

It is registered only in ``sys.path_importer_cache``, for the zip's own paths (the zip and each folder in it), as
zipimport registers its finders there: a Python host's ``sys.path``, ``sys.meta_path`` and ``sys.path_hooks`` stay
as they are, and only a path inside the zip is answered here. A member it cannot read (compressed where zlib is
missing) is left to zipimport. Standard library only; the loader's bootstrap (``loader/bridge.c``) reads this
module from the zip itself and installs it.
"""

from __future__ import annotations

import importlib.util
import marshal
import os
import struct
import sys
import zipimport
from importlib.machinery import ModuleSpec

MAGIC = importlib.util.MAGIC_NUMBER
STORED, DEFLATED = 0, 8


class Archive:
    """A zip's bytes and its members: ``{name: (offset of the data, size, method)}``."""

    def __init__(self, path: str) -> None:
        self.path = path
        with open(path, "rb") as file:
            self.bytes = file.read()
        data = self.bytes
        end = data.rfind(b"PK\x05\x06")
        if end < 0:
            raise ImportError(f"{path} is not a zip", path=path)
        count, _, at = struct.unpack_from("<HII", data, end + 10)
        self.members: dict[str, tuple[int, int, int]] = {}
        for _ in range(count):
            method, = struct.unpack_from("<H", data, at + 10)
            size, = struct.unpack_from("<I", data, at + 20)
            name_length, extra_length, comment_length = struct.unpack_from("<HHH", data, at + 28)
            local, = struct.unpack_from("<I", data, at + 42)
            name = data[at + 46:at + 46 + name_length].decode("utf-8")
            local_name, local_extra = struct.unpack_from("<HH", data, local + 26)
            self.members[name] = (local + 30 + local_name + local_extra, size, method)
            at += 46 + name_length + extra_length + comment_length
        self.view = memoryview(data)

    def read(self, name: str) -> bytes | memoryview | None:
        """The member's bytes; None if it is not there, or compressed where zlib is missing."""
        if name not in self.members:
            return None
        start, size, method = self.members[name]
        data = self.view[start:start + size]
        if method == STORED:
            return data
        if method != DEFLATED:
            return None
        try:
            import zlib
        except ImportError:
            return None
        return zlib.decompress(data, -15)


def _join(archive: str, folder: str) -> str:
    """The path of ``folder`` (``pkg/sub/``, ``""`` for the top) inside the zip at ``archive``, as a package's
    ``__path__`` names it."""
    return os.path.join(archive, *folder.rstrip("/").split("/")) if folder else archive


class Finder:
    """The finder and loader of one folder of an :class:`Archive` (``prefix``: ``pkg/sub/``, ``""`` at its top).
    Its ``archive`` is the zip's path, as a zipimporter's is."""

    def __init__(self, archive: Archive, prefix: str) -> None:
        self.zip, self.prefix = archive, prefix

    @property
    def archive(self) -> str:
        return self.zip.path

    def find_spec(self, fullname: str, target: object = None) -> ModuleSpec | None:
        name = self.prefix + fullname.rpartition(".")[2]
        members = self.zip.members
        for path, package in ((f"{name}/__init__", True), (name, False)):
            if f"{path}.pyc" in members or f"{path}.py" in members:
                if not self._readable(path):
                    return zipimport.zipimporter(_join(self.zip.path, self.prefix)).find_spec(fullname, target)
                spec = ModuleSpec(fullname, self, origin=f"{_join(self.zip.path, self.prefix)}{os.sep}"
                                  f"{path[len(self.prefix):].replace('/', os.sep)}.py", is_package=package)
                if package:
                    spec.submodule_search_locations = [_join(self.zip.path, name + "/")]
                spec.has_location = True
                spec.loader_state = path
                return spec
        return None

    def _readable(self, path: str) -> bool:
        return all(self.zip.read(f"{path}{suffix}") is not None for suffix in (".pyc", ".py")
                   if f"{path}{suffix}" in self.zip.members)

    def invalidate_caches(self) -> None:
        """Nothing to drop: the zip is read once and does not change."""

    # ------------------------------------------------------------------------------------------ the loader
    def create_module(self, spec: ModuleSpec) -> None:
        return None

    def exec_module(self, module: object) -> None:
        code = self._code(module.__spec__.loader_state, module.__spec__.origin)
        if code is None:
            raise ImportError(f"{module.__name__}: no code in {self.zip.path}", name=module.__name__)
        exec(code, module.__dict__)

    def _code(self, path: str, origin: str) -> object | None:
        """The code object of member ``path`` (without suffix): from its bytecode where that is this Python's and,
        if checked, matches the source; else compiled from the source."""
        compiled, source = self.zip.read(f"{path}.pyc"), self.zip.read(f"{path}.py")
        if compiled is not None and bytes(compiled[:4]) == MAGIC:
            flags = int.from_bytes(compiled[4:8], "little")
            checked = flags & 0b11 == 0b11
            if not checked or source is None or bytes(compiled[8:16]) == importlib.util.source_hash(bytes(source)):
                return marshal.loads(compiled[16:])
        if source is not None:
            return compile(bytes(source), origin, "exec", dont_inherit=True)
        return None

    def get_code(self, fullname: str) -> object | None:
        spec = self.find_spec(fullname)
        return self._code(spec.loader_state, spec.origin) if spec else None

    def get_source(self, fullname: str) -> str | None:
        spec = self.find_spec(fullname)
        source = self.zip.read(f"{spec.loader_state}.py") if spec else None
        return bytes(source).decode("utf-8") if source is not None else None

    def is_package(self, fullname: str) -> bool:
        spec = self.find_spec(fullname)
        return bool(spec and spec.submodule_search_locations is not None)


def install(path: str) -> Finder:
    """Read the zip at ``path`` and register a :class:`Finder` for it and for each folder in it in
    ``sys.path_importer_cache``; return the one of its top."""
    archive = Archive(path)
    folders = {""} | {name[:name.rindex("/") + 1] for name in archive.members if "/" in name}
    top = None
    for folder in sorted(folders):
        finder = Finder(archive, folder)
        sys.path_importer_cache[_join(path, folder)] = finder
        top = top or finder
    return top
