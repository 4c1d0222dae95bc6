"""The project's own co-simulation masters, which run the component or FMUs without an FMI tool.

:mod:`.coupling` couples the DoublePendulum and Suspension FMUs (or their components) over communication
steps: Jacobi, extrapolated inputs, iterative with rollback. :mod:`.simulate` runs the component in-process
as fmpy runs the FMU (same communication points). They know no build and no FMI tool's runner: what the FMU
carries draws its plots with them (:mod:`double_pendulum.fmu.carries`).
"""
