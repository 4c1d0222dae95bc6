"""Analysis around the component, one subpackage a study: the measured track (:mod:`.track`), its energy
decay (:mod:`.decay`), the loss identification (:mod:`.losses`), the pivot suspension (:mod:`.suspension`),
predictions of the track (:mod:`.prediction`), chaos and ensembles (:mod:`.chaos`), the solvers
(:mod:`.solvers`), co-simulation (:mod:`.coupling`) and the driven pivot (:mod:`.excitation`); with the
parameter sweeps they share (:mod:`.sweep`). Uses the model, the solvers, the FMU and the run machinery
(:mod:`double_pendulum.runs`: progress, Ctrl-C, the result cache and files); never bundled.
"""
