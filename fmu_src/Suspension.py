"""pythonfmu adapter of ``Suspension.fmu``: the component
:class:`double_pendulum.component.suspension.SuspensionCoSimulation` behind FMI 2.0
co-simulation (the mapping itself is :class:`double_pendulum_slave.ComponentSlave`).
"""

from __future__ import annotations

from .double_pendulum_slave import ComponentSlave, DefaultExperiment, runtime_module

_component = runtime_module("component.suspension")
_interface = runtime_module("component.variables").INTERFACES["Suspension"]


class Suspension(ComponentSlave):
    description = _interface.description
    default_experiment = DefaultExperiment(**_interface.default_experiment)
    interface = _interface

    def make_component(self):
        return _component.SuspensionCoSimulation()
