"""Run built FMUs in FMI tools: fmpy (:mod:`.runner`, :class:`~.runner.FmuRunner`), libcosim and the
container FMU (:mod:`.hosts`), and start values given on the command line (:mod:`.start_values`,
``--set NAME=VALUE`` checked against a modelDescription). The runner builds the FMU when it is missing
or stale (:mod:`double_pendulum.fmu.build`).
"""
