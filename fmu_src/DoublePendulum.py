"""pythonfmu adapter of ``DoublePendulum.fmu``: the component
:class:`double_pendulum.component.cosimulation.DoublePendulumCoSimulation` behind FMI 2.0
co-simulation (the mapping itself is :class:`double_pendulum_slave.ComponentSlave`).
"""

from __future__ import annotations

from .double_pendulum_slave import ComponentSlave, DefaultExperiment, runtime_module

_cosim = runtime_module("component.cosimulation")
_interface = runtime_module("component.variables").INTERFACES["DoublePendulum"]


class DoublePendulum(ComponentSlave):
    description = _interface.description
    default_experiment = DefaultExperiment(**_interface.default_experiment)
    interface = _interface

    def make_component(self):
        return _cosim.DoublePendulumCoSimulation()
