"""The C loader's units in layers with no circle (scripts/check_loader_layers.py), as import-linter keeps the Python
side's: the check passes on the loader, and fails, naming the units, on a copy given a circle or an upward call."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCRIPT = ROOT / "scripts" / "check_loader_layers.py"
LOADER = ROOT / "fmu_src" / "loader"


def check(folder: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(SCRIPT), str(folder)], capture_output=True, text=True, timeout=60)


def test_the_loader_keeps_its_layers():
    done = check(LOADER)
    assert done.returncode == 0, done.stderr
    layers = dict(line.split(": ", 1) for line in done.stdout.splitlines())
    assert layers["layer 1"].startswith("fmi2_guard -> ") and "python_runtime ->" in layers["layer 5"]
    assert "bridge -> guard_base, python_runtime, text" in layers["layer 3"]  # the bridge knows no guard.c


def test_a_call_up_the_layers_is_a_circle_and_named(tmp_path):
    copy = Path(shutil.copytree(LOADER, tmp_path / "loader"))
    # the base's text formatting calling the instance's log: text -> guard_base -> text
    with (copy / "text.c").open("a") as source:
        source.write('\nvoid text_log_too(void *g) { guard_fail(g, "%s", "x"); }\n')
    done = check(copy)
    assert done.returncode == 1
    circle = next(line for line in done.stderr.splitlines() if "a circle: " in line)
    assert "guard_base <-> " in circle and " <-> text:" in circle and "text -> guard_base (guard_fail)" in circle
    assert "text (layer 7) uses guard_base of a higher layer (4): guard_fail" in done.stderr


def test_an_include_of_a_higher_layer_is_named(tmp_path):
    copy = Path(shutil.copytree(LOADER, tmp_path / "loader"))
    source = copy / "python_runtime.c"
    source.write_text(source.read_text().replace('#include "text.h"', '#include "text.h"\n#include "bridge.h"', 1))
    done = check(copy)
    assert done.returncode == 1
    assert 'python_runtime (layer 5) uses bridge of a higher layer (3): #include "bridge.h" (python_runtime.c)' \
        in done.stderr


def test_a_unit_in_no_layer_is_named(tmp_path):
    copy = Path(shutil.copytree(LOADER, tmp_path / "loader"))
    (copy / "extra.c").write_text("int extra_answer(void) { return 42; }\n")
    done = check(copy)
    assert done.returncode == 1 and "extra.c is in no layer" in done.stderr
