"""Build the FMUs and the coupled system.

:mod:`.fmi2` builds the FMI 2.0 FMUs (DoublePendulum, Suspension) with pythonfmu, :mod:`.fmi3` the FMI 3.0
DoublePendulum (Model Exchange and Co-Simulation) with pythonfmu3; both stage the runtime and rewrite the
built zip through :mod:`.staging`, which lays the bundled code out under private names (:mod:`.bundle`)
and compiles the FMU's one binary (:mod:`.loader`). :mod:`.systems` builds everything, then
PendulumOnSuspension as an SSP (:mod:`.ssp`) and as fmpy's container FMU (:mod:`.container`). What a
built FMU carries besides its code comes from :mod:`double_pendulum.fmu.carries`.
"""
