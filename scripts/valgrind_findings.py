"""Read one valgrind (memcheck) run of scripts/check_memory.sh and say what it found, in plain lines.

    python valgrind_findings.py XML LABEL EXIT_STATUS [FILE ...]

XML: valgrind's ``--xml-file`` (every frame there names its object file, with or without debug info);
EXIT_STATUS: valgrind's (99 for errors, with ``--error-exitcode=99``); FILEs (valgrind's ``--log-file``, say)
are shown when something failed.

Prints every error valgrind reported (not suppressed) as valgrind would, marked ``[FMU]`` when any of its
stacks (where it happened, where the memory was allocated or freed) runs through an FMU's binaries (an
object under ``binaries/<platform>/``), then one line with the counts and how many errors each entry of
the suppression file took away. Exits 1 on any reported error, a fatal signal, a run that valgrind did
not finish or a host that failed; else 0.
"""

from __future__ import annotations

import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

FMU_BINARY = re.compile(r"/binaries/(linux64|linux32|x86_64-linux|aarch64-linux|x86-linux)/")


def text_of(element: ET.Element) -> str:
    """An error's or a note's words: <what>/<auxwhat>, or the <text> of <xwhat>/<xauxwhat>."""
    return (element.findtext("text") if element.tag.startswith("x") else element.text or "").strip()


def frame_line(frame: ET.Element, first: bool) -> str:
    where = frame.findtext("fn") or "???"
    if frame.findtext("file"):
        where += f" ({frame.findtext('file')}:{frame.findtext('line')})"
    return f"{'at' if first else 'by'} {frame.findtext('ip')}: {where} in {frame.findtext('obj') or '?'}"


def describe(error: ET.Element) -> tuple[list[str], bool]:
    """An error as lines (headline, stacks, notes) and whether any stack runs through an FMU's binaries."""
    lines, in_fmu = [], False
    for part in error:
        if part.tag in ("what", "xwhat", "auxwhat", "xauxwhat", "signame"):
            lines.append(text_of(part) if part.tag != "signame" else f"fatal signal {part.text}")
        elif part.tag == "stack":
            frames = part.findall("frame")
            in_fmu |= any(FMU_BINARY.search(f.findtext("obj") or "") for f in frames)
            lines += [f"  {frame_line(frame, k == 0)}" for k, frame in enumerate(frames)]
    return lines, in_fmu


def main(argv: list[str]) -> int:
    xml, label, status = Path(argv[0]), argv[1], int(argv[2])
    extras = [Path(p) for p in argv[3:]]
    try:
        root = ET.parse(xml).getroot()
    except (OSError, ET.ParseError) as why:
        root, problem = None, f"no readable valgrind XML ({why})"
    failed = False
    if root is None or not any(s.findtext("state") == "FINISHED" for s in root.iter("status")):
        print(f"valgrind {label}: FAILED: valgrind did not finish: {problem if root is None else 'no FINISHED status'}")
        failed = True
        root = root if root is not None else ET.Element("valgrindoutput")
    # leak records are no errors here (--errors-for-leak-kinds=none; check_memory.sh does not have them written)
    errors = [e for e in root.findall("error") if not (e.findtext("kind") or "").startswith("Leak_")]
    errors += root.findall("fatal_signal")
    counts = {pair.findtext("unique"): int(pair.findtext("count") or 0) for pair in root.iter("pair")
              if pair.find("unique") is not None}
    suppressed = sorted(((int(pair.findtext("count") or 0), pair.findtext("name") or "?") for pair in
                         root.findall("suppcounts/pair")), reverse=True)
    in_fmu = 0
    for error in errors:
        lines, touches = describe(error)
        in_fmu += touches
        times = counts.get(error.findtext("unique"), 1)
        print(f"valgrind {label}: {'[FMU] ' if touches else ''}{lines[0] if lines else error.tag}"
              f"{f' ({times} times)' if times > 1 else ''}")
        print("\n".join(f"    {line}" for line in lines[1:]))
    if errors:
        total = sum(counts.get(e.findtext("unique"), 1) for e in errors)
        print(f"valgrind {label}: FAILED: {total} errors in {len(errors)} contexts not suppressed, {in_fmu} of these "
              "contexts in the FMU's binaries (each printed above)")
        failed = True
    elif not failed:
        print(f"valgrind {label}: no error in the FMU's binaries or anywhere else")
    rules = ", ".join(f"{count} {name}" for count, name in suppressed if count)
    print(f"valgrind {label}: {sum(c for c, _ in suppressed)} errors suppressed as known false positives outside "
          f"the FMU (scripts/valgrind-python.supp){': ' + rules if rules else ''}")
    if status not in (0, 99) or (status == 99 and not errors):
        print(f"valgrind {label}: FAILED: the host exited with status {status}")
        failed = True
    if failed:
        for path in extras:
            if path.is_file() and path.stat().st_size:
                print(f"valgrind {label}: {path.name}:\n{path.read_text(errors='replace')[-4000:]}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
