"""The session's own $TMPDIR (conftest): every process of the session writes its temporary files there, and what is
left in it at the end fails the session."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

from conftest import TEMPROOT, session_leftovers


def test_the_session_and_its_subprocesses_use_a_temporary_folder_of_their_own(tmp_path):
    folder = Path(tempfile.gettempdir())
    assert folder.name.startswith("double-pendulum-tests-") and os.environ["TMPDIR"] == str(folder)
    child = subprocess.run([sys.executable, "-c", "import tempfile; print(tempfile.gettempdir())"],
                           capture_output=True, text=True, check=True).stdout.strip()
    assert child == str(folder)
    assert not tmp_path.is_relative_to(folder) and os.environ[TEMPROOT] == str(folder.parent)  # pytest's own


def test_leftovers_are_named_with_their_size(tmp_path):
    (tmp_path / "fmpy-extract").mkdir()
    (tmp_path / "fmpy-extract" / "binary.so").write_bytes(b"x" * 2_000_000)
    (tmp_path / "note.txt").write_text("")
    assert session_leftovers(tmp_path) == ["fmpy-extract (2.0 MB)", "note.txt (0.0 MB)"]
    assert session_leftovers(tmp_path / "fmpy-extract") == ["binary.so (2.0 MB)"]
