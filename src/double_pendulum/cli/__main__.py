"""``python -m double_pendulum.cli``: the ``double-pendulum`` command (how the pool starts each scenario)."""

from . import entry

entry()
