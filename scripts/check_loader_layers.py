"""The C loader's units in layers, with no circle: what import-linter is to the Python side (docs/architecture.md).

A unit is a source ``X.c`` with its header ``X.h`` (a header without a source, such as ``glibc_compat.h``, holds
types or macros only and is left out). Unit A uses unit B where A's source or header includes ``B.h``, or names a
function that B's source defines (its non-static functions: every identifier is counted, so a call through a
macro or a function pointer is one too; comments and string literals are not read).

The check fails, naming the units and what links them, where

* the units use each other in a circle (a strongly connected component of more than one unit, or a unit
  outside :data:`LAYERS`), or
* a unit uses a unit of a higher layer.

Usage: ``python scripts/check_loader_layers.py [FOLDER]`` (default ``fmu_src/loader``); exit status 1 on a
violation, 0 with the layers printed otherwise. Standard library only.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

LAYERS: tuple[tuple[str, ...], ...] = (
    ("fmi2_guard", "fmi3_guard"),  # the FMI functions of each version: state machines, argument checks
    ("guard", "fmu_state"),  # what both versions share: instances, instantiation, strings, the FMU states
    ("bridge",),  # calls into the Python side with the GIL, its answers and messages
    ("guard_base",),  # what every layer above knows of an instance: its struct, statuses, its log
    ("python_runtime",),  # which CPython runs, started once per process
    ("python_start",),  # starting a CPython through its configuration API
    ("pointer_set", "platform", "text", "identity"),  # the base: live pointers, the OS, text, the FMU's identity
)
"""The loader's layers, top to bottom: a unit may use units of its own layer (without a circle) or lower ones."""

_COMMENT = re.compile(r"/\*.*?\*/|//[^\n]*", re.S)
_STRING = re.compile(r'"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'')
_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)\.h"', re.M)
_IDENTIFIER = re.compile(r"\b[A-Za-z_]\w*\b")
# a function definition at the start of a line: its type, its name, its parameters, then the body's brace
_DEFINITION = re.compile(r"^(?!static\b)(?!#)[A-Za-z_][\w \t\*]*?\b([A-Za-z_]\w*)\s*\(([^;{}]|\n)*?\)\s*\{", re.M)


def _code(text: str) -> str:
    """``text`` without comments and string or character literals (their places kept blank)."""
    text = _COMMENT.sub(" ", text)
    return _STRING.sub('""', text)


def units(folder: Path) -> dict[str, list[Path]]:
    """Each unit's files: ``X.c`` and, if there is one, ``X.h``."""
    return {source.stem: [source, *([header] if (header := source.with_suffix(".h")).exists() else [])]
            for source in sorted(folder.glob("*.c"))}


def uses(folder: Path) -> dict[str, dict[str, list[str]]]:
    """For each unit, the units it uses and why (``#include "B.h"``, or the names of B's functions it names)."""
    files = units(folder)
    sources = {name: _code(paths[0].read_text(encoding="utf-8")) for name, paths in files.items()}
    defined = {name: {match.group(1) for match in _DEFINITION.finditer(code)} for name, code in sources.items()}
    owner = {function: name for name, functions in defined.items() for function in functions}
    graph: dict[str, dict[str, list[str]]] = {}
    for name, paths in files.items():
        edges: dict[str, list[str]] = {}
        for path in paths:
            raw = path.read_text(encoding="utf-8")
            for included in _INCLUDE.findall(_COMMENT.sub(" ", raw)):
                if included in files and included != name:
                    edges.setdefault(included, []).append(f'#include "{included}.h" ({path.name})')
            for identifier in sorted(set(_IDENTIFIER.findall(_code(raw)))):
                other = owner.get(identifier)
                if other is not None and other != name:
                    edges.setdefault(other, []).append(identifier)
        graph[name] = edges
    return graph


def circles(graph: dict[str, dict[str, list[str]]]) -> list[list[str]]:
    """The strongly connected components of more than one unit (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(unit: str) -> None:
        index[unit] = low[unit] = len(index)
        stack.append(unit)
        on_stack.add(unit)
        for other in graph.get(unit, {}):
            if other not in index:
                visit(other)
                low[unit] = min(low[unit], low[other])
            elif other in on_stack:
                low[unit] = min(low[unit], index[other])
        if low[unit] == index[unit]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == unit:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for unit in sorted(graph):
        if unit not in index:
            visit(unit)
    return found


def violations(folder: Path) -> list[str]:
    """What breaks the layering of the units in ``folder``, one line each (none: the layering holds)."""
    graph = uses(folder)
    layer = {unit: depth for depth, members in enumerate(LAYERS) for unit in members}
    problems = [f"{unit}.c is in no layer of scripts/check_loader_layers.py (LAYERS)" for unit in graph
                if unit not in layer]
    for component in circles(graph):
        links = "; ".join(f"{a} -> {b} ({', '.join(graph[a][b][:3])})" for a in component for b in graph[a]
                          if b in component)
        problems.append(f"a circle: {' <-> '.join(component)}: {links}")
    for unit, edges in sorted(graph.items()):
        for other, why in sorted(edges.items()):
            if unit in layer and other in layer and layer[other] < layer[unit]:
                problems.append(f"{unit} (layer {layer[unit] + 1}) uses {other} of a higher layer "
                                f"({layer[other] + 1}): {', '.join(why[:3])}")
    return problems


def main(argv: list[str]) -> int:
    folder = Path(argv[1]) if len(argv) > 1 else Path(__file__).resolve().parent.parent / "fmu_src" / "loader"
    if not folder.is_dir():
        print(f"check_loader_layers: {folder} is not a folder", file=sys.stderr)
        return 2
    problems = violations(folder)
    if problems:
        print(f"check_loader_layers: the loader's units in {folder} break their layers:", file=sys.stderr)
        for problem in problems:
            print(f"  {problem}", file=sys.stderr)
        return 1
    graph = uses(folder)
    for depth, members in enumerate(LAYERS, 1):
        print(f"layer {depth}: " + ", ".join(f"{unit} -> {', '.join(sorted(graph.get(unit, {}))) or '-'}"
                                             for unit in members if unit in graph))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
