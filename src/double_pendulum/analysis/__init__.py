"""Analysis around the component: the measured track (:mod:`.measurement`), decay-law fits
(:mod:`.decay_fit`), start-state and suspension identification, parameter sweeps, chaos and
ensembles, and reference solutions. Uses the model, the solvers and the FMU; never bundled.
"""
