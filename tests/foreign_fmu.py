"""A pythonfmu FMU of another author that uses this project's names, for the neighbour tests.

Its model identifier is ``DoublePendulum`` or ``Suspension``, and besides its adapter it bundles a
module ``slave_common`` and a package ``double_pendulum`` of its own (and pythonfmu's copy, as every
pythonfmu FMU does): every public name this project's FMUs could collide with. Its one output ``x``
starts at ``START`` and grows by ``RATE`` per second.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

START, RATE = 7.0, 2.0

ADAPTER = '''
from pythonfmu import Fmi2Causality, Fmi2Slave, Real

import slave_common
from double_pendulum import growth


class {model}(Fmi2Slave):
    """Someone else's FMU with this project's model identifier."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.x = slave_common.START
        self.register_variable(Real("x", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.x = growth.advance(self.x, step_size)
        return True
'''


def build_foreign_fmu(folder: Path, model: str) -> Path:
    """Build the foreign FMU ``model`` in ``folder`` (in a fresh process: the builder imports its modules)."""
    source = folder / f"{model}_src"
    (source / "double_pendulum").mkdir(parents=True)
    (source / f"{model}.py").write_text(ADAPTER.format(model=model))
    (source / "slave_common.py").write_text(f"START = {START}\n")
    (source / "double_pendulum" / "__init__.py").write_text("")
    (source / "double_pendulum" / "growth.py").write_text(f"def advance(x, h):\n    return x + {RATE} * h\n")
    script = textwrap.dedent(f"""
        from pythonfmu.builder import FmuBuilder
        print(FmuBuilder.build_FMU({str(source / f"{model}.py")!r}, dest={str(folder)!r},
                                   project_files=[{str(source / "slave_common.py")!r},
                                                  {str(source / "double_pendulum")!r}]))
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=source, check=True)
    return Path(done.stdout.strip().splitlines()[-1])
