"""The co-simulation component: what the FMU adapter runs (pure Python, bundled into the FMU).

:mod:`.cosimulation` (parameters by name, initialisation, doStep, outputs, FMU state),
:mod:`.settings` (solver choice and tolerances), :mod:`.variables` (the FMU's variable table) and
:mod:`.state_check` (a saved FMU state checked before it is restored: ``StateError``).
"""
