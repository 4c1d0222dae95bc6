"""double-pendulum-fmu: a planar double pendulum as an FMI 2.0 co-simulation FMU.

The runtime, which the FMU bundles and runs (pure Python, standard library only):

* :mod:`.model` -- parameters, kinematics, equations of motion, forces, energies, the assembled
  vector field and the outputs;
* :mod:`.solvers` -- the integrators, separate from the vector field;
* :mod:`.component` -- the co-simulation component the FMU adapter drives, and its variables;
* :mod:`.codegen` -- the one code generator of the model's and the solvers' straight-line functions.

What studies it (NumPy, SciPy, Matplotlib, fmpy; never bundled):

* :mod:`.fmu` -- build the FMU, run it through fmpy or libcosim, or in-process;
* :mod:`.analysis` -- measured track, decay fits, identification, chaos, ensembles, sweeps;
* :mod:`.plots`, :mod:`.scenarios` and :mod:`.cli`;
* :mod:`.runs` -- the run machinery: child processes, progress, Ctrl-C, the cache, the result files, the page.

Imports point one way, from the studies to the runtime (``.importlinter``, checked in CI).
Importing the package is cheap: the FMU loads it at start-up.
"""

__version__ = "0.1.0"
