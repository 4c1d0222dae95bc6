"""Chaos and ensembles (scenario ``chaos``): batch integration (:mod:`.ensemble`), Lyapunov exponents
(:mod:`.lyapunov`, :mod:`.lyapunov_study`), predictability of a release (:mod:`.predictability`) and
phase-space pictures (:mod:`.phase_space`)."""
