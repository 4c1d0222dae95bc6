"""What a Linux shared library asks of the system it loads on: the libraries it links and the symbol versions
it needs.

An ELF library built against glibc and libstdc++ records, per library it links (``libc.so.6``,
``libstdc++.so.6``, ...), the symbol versions it needs (``GLIBC_2.32``, ``GLIBCXX_3.4.30``) in its
``.gnu.version_r`` section; the dynamic loader refuses it on a system whose libraries lack one. Read
here without any tool (no readelf on the target), for the build (the loader's message says what
pythonfmu's binary needs), the docs and the test that keeps the loader's own needs old
(tests/test_loader_symbols.py).
"""

from __future__ import annotations

import re
import struct

SHT_GNU_VERNEED = 0x6FFFFFFE
SHT_DYNAMIC = 6
DT_NEEDED = 1
# The oldest GCC whose libstdc++ has each GLIBCXX version (GCC's ABI policy, libstdc++ manual, "ABI").
GLIBCXX_GCC = {"3.4.19": "4.8", "3.4.20": "4.9", "3.4.21": "5", "3.4.22": "6", "3.4.23": "7", "3.4.24": "7.2",
               "3.4.25": "8", "3.4.26": "9", "3.4.27": "9.2", "3.4.28": "10", "3.4.29": "11", "3.4.30": "12",
               "3.4.31": "13", "3.4.32": "14", "3.4.33": "15"}


def _sections(data: bytes) -> list[tuple[int, ...]]:
    """The section headers of a 64-bit little-endian ELF file (name, type, flags, address, offset, size, link,
    info, alignment, entry size)."""
    if data[:4] != b"\x7fELF" or data[4] != 2 or data[5] != 1:
        raise ValueError("not a 64-bit little-endian ELF file")
    shoff, = struct.unpack_from("<Q", data, 0x28)
    shentsize, shnum = struct.unpack_from("<HH", data, 0x3A)
    return [struct.unpack_from("<IIQQQQIIQQ", data, shoff + k * shentsize) for k in range(shnum)]


def needed_libraries(data: bytes) -> list[str]:
    """The libraries a 64-bit little-endian ELF file links by name (its ``DT_NEEDED`` entries), in order."""
    sections = _sections(data)
    names = []
    for _, kind, _, _, offset, size, link, _, _, _ in sections:
        if kind != SHT_DYNAMIC:
            continue
        strings = sections[link][4]
        for at in range(offset, offset + size, 16):
            tag, value = struct.unpack_from("<qQ", data, at)
            if tag == DT_NEEDED:
                names.append(data[strings + value:data.index(b"\0", strings + value)].decode())
    return names


def version_needs(data: bytes) -> dict[str, list[str]]:
    """The symbol versions a 64-bit little-endian ELF file needs, by library: ``{"libc.so.6": [...]}``."""
    sections = _sections(data)
    needs: dict[str, list[str]] = {}
    for _, kind, _, _, offset, _, link, count, _, _ in sections:
        if kind != SHT_GNU_VERNEED:
            continue
        strings = sections[link][4]

        def text(at: int, strings: int = strings) -> str:
            return data[strings + at:data.index(b"\0", strings + at)].decode()

        entry = offset
        for _ in range(count):
            _, n_aux, file_name, aux, following = struct.unpack_from("<HHIII", data, entry)
            names = needs.setdefault(text(file_name), [])
            at = entry + aux
            for _ in range(n_aux):
                _, _, _, name, next_aux = struct.unpack_from("<IHHII", data, at)
                names.append(text(name))
                at += next_aux
            entry += following
    return {library: sorted(set(names), key=version_key) for library, names in needs.items()}


def version_key(name: str) -> tuple:
    """Sort key of a version name: ``GLIBC_2.9`` before ``GLIBC_2.17``."""
    prefix, _, number = name.partition("_")
    return (prefix, *(int(part) for part in re.findall(r"\d+", number)))


def newest(needs: dict[str, list[str]], prefix: str) -> str | None:
    """The newest needed version that starts with ``prefix_`` (``GLIBC``, ``GLIBCXX``), or None."""
    names = [name for versions in needs.values() for name in versions if name.startswith(prefix + "_")]
    names = [name for name in names if re.fullmatch(rf"{prefix}_[\d.]+", name)]
    return max(names, key=version_key) if names else None


def describe(data: bytes) -> str:
    """What the library needs in words: ``glibc >= 2.32 and libstdc++ with GLIBCXX_3.4.30 (GCC 12 or newer)``."""
    needs = version_needs(data)
    parts = []
    glibc = newest(needs, "GLIBC")
    if glibc:
        parts.append(f"glibc >= {glibc.partition('_')[2]}")
    glibcxx = newest(needs, "GLIBCXX")
    if glibcxx:
        gcc = GLIBCXX_GCC.get(glibcxx.partition("_")[2])
        parts.append(f"libstdc++ with {glibcxx}" + (f" (GCC {gcc} or newer)" if gcc else ""))
    return " and ".join(parts) or "nothing versioned"
