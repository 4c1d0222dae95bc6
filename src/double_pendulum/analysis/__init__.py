"""Analysis around the component, one subpackage a study: the measured track (:mod:`.track`), its energy
decay (:mod:`.decay`), the loss identification (:mod:`.losses`), the pivot suspension (:mod:`.suspension`),
predictions of the track (:mod:`.prediction`), chaos and ensembles (:mod:`.chaos`), the solvers
(:mod:`.solvers`), co-simulation (:mod:`.coupling`) and the driven pivot (:mod:`.excitation`); with the
tools they share: parameter sweeps (:mod:`.sweep`), progress (:mod:`.progress`) and the result cache
(:mod:`.result_cache`). Uses the model, the solvers and the FMU; never bundled.
"""
