"""Build the FMUs and run them, in rooms by purpose; not bundled into the FMU.

Layers, top to bottom (imports point down only; ``.importlinter`` checks it):

* :mod:`.crosscheck` (the FMI Cross-Check: reference cases, their runs, the tree, the Compliance Checker)
  and :mod:`.running` (built FMUs in FMI tools: fmpy's runner, libcosim, the container FMU);
* :mod:`.build` (the FMI 2 and FMI 3 builds, the bundled layout, the C loader, the coupled system);
* :mod:`.carries` (what an FMU carries besides its code: documentation, plots, icon, terminals,
  reference result);
* :mod:`.masters` (the project's own masters: the co-simulation master, the component in-process) and
  :mod:`.presets` (start values baked into a build).

What the FMU bundles is decided in :mod:`.build.staging`.
"""
