"""The run machinery: what runs the scenarios and what a run writes, none of it physics.

* :mod:`.pool` -- ``run all``: the scenarios in child processes, one per core, the longest first;
* :mod:`.lines` -- the lines a scenario run prints about itself, which the pool reads back;
* :mod:`.progress` -- progress bars and step lines; :mod:`.interrupts` -- Ctrl-C for a run and its processes;
* :mod:`.workers` -- how many processes a run uses; :mod:`.result_cache` -- slow results kept on disk;
* :mod:`.results_io` -- the result files (CSV with units, summary.json, reports), written atomically;
* :mod:`.page` -- ``index.html``, the one page that shows a whole run.

The studies (:mod:`double_pendulum.analysis`) and the scenarios use the tools here; nothing here imports a
study, a scenario or the FMU (the pool starts scenarios by their command line, and the command line gives it
what it needs to know of them).
"""
