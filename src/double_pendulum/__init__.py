"""double-pendulum-fmu: a planar double pendulum as an FMI 2.0 co-simulation FMU.

Modules: :mod:`.parameters` (units, defaults, checks), :mod:`.dynamics` (equations of motion),
:mod:`.kinematics`, :mod:`.energy`, :mod:`.outputs`, :mod:`.solvers` (integrators),
:mod:`.cosimulation` (the slave the FMU runs), :mod:`.simulate` (the same in-process),
:mod:`.fmu_build` (build the FMU), :mod:`.runner` (run it through fmpy), :mod:`.results_io`
(CSV/JSON), :mod:`.plotting` and :mod:`.cli`.

Importing the package is cheap (no NumPy, SciPy or Matplotlib): the FMU loads it at start-up.
"""

__version__ = "0.1.0"
