"""The interactive app (``double-pendulum app``): the FMU run through fmpy from a form in the browser, animated
with play, pause, step, speed and a time slider, its angles, energy budget and path plotted, compared with the
measured track or with a start a hair apart, given as CSV and as the fmpy call that reproduces it
(docs/app.md). Modules: :mod:`.form` (the inputs and their checks), :mod:`.worker` (the runs, a process each),
:mod:`.figures` (the plots), :mod:`.layout` (the page), :mod:`.callbacks`, :mod:`.server` (the command)."""
