"""A named quantity of the model's interface: the record both the inputs and the outputs are listed in.

:mod:`.inputs` lists the inputs, :mod:`.outputs` the outputs and :mod:`.suspension` the Suspension
FMU's variables as :class:`Quantity` rows; the FMU's variable table
(:mod:`double_pendulum.component.variables`) is built from them.
"""

from __future__ import annotations

from typing import NamedTuple


class Quantity(NamedTuple):
    """A model variable: name, unit (FMI unit string, e.g. ``"rad/s"``) and description."""

    name: str
    unit: str
    description: str
