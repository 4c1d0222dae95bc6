"""Run built FMUs in FMI tools: fmpy (:mod:`.runner`, :class:`~.runner.FmuRunner`), libcosim and the
container FMU (:mod:`.hosts`), and start values given on the command line (:mod:`.start_values`,
``--set NAME=VALUE`` checked against a modelDescription), and which FMU a command runs (:mod:`.choice`): one a user
names, checked and only read, never built or written, or the project's, which :func:`~.runner.ensure_fmu` builds
where the project keeps it when it is missing or stale (:mod:`double_pendulum.fmu.build`).
"""
