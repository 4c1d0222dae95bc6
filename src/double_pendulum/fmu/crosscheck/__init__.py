"""The FMI Cross-Check: the reference cases (:mod:`.reference_cases`), their runs and committed results
(:mod:`.reference_runs`), the tree the project exports and fmpy's import of it (:mod:`.tree`), and the
FMI Compliance Checker run on the cases (:mod:`.compliance_checker`). The top of the fmu package: it
builds FMUs (:mod:`double_pendulum.fmu.build`) and nothing below imports it.
"""
