"""Build the FMU and run the component: through fmpy (:mod:`double_pendulum.fmu.running.runner`), libcosim
(:mod:`double_pendulum.fmu.hosts`) or in-process (:mod:`double_pendulum.fmu.masters.simulate`). Not bundled into the
FMU; :mod:`double_pendulum.fmu.build.staging` decides what is.
"""
