"""The reference result inside every FMU, in Reference-FMUs' layout (the layered standard ``fmi-ls-ref``)::

    extra/org.fmi-standard.fmi-ls-ref/fmi-ls-manifest.xml   names the result and says what it is
    extra/org.fmi-standard.fmi-ls-ref/<model>_out.csv       time and every output of the default experiment

The result is the FMU's default experiment (its ``DefaultExperiment`` start and stop, the start values the FMU
carries, baked presets included, the default inputs), every :func:`interval` [s], computed at build in-process
with the component(s) the FMU runs (:func:`double_pendulum.fmu.carries.doc_plot.run`; the container's two components as
it couples them). An importer that simulates the FMU with its defaults and that output interval should get
these numbers: fmpy does, to rounding under Co-Simulation and within the tolerance under Model Exchange
(``tests/test_reference_result.py``). The cross-check tree's references
(:mod:`double_pendulum.fmu.crosscheck.reference_cases`) are other cases, with inputs and tight tolerances.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Mapping
from typing import Any
from xml.etree import ElementTree as ET

from . import doc_plot

FOLDER = "extra/org.fmi-standard.fmi-ls-ref"
MANIFEST = f"{FOLDER}/fmi-ls-manifest.xml"
MOST_ROWS = 1000  # intervals of a reference: the default experiment's step, coarser where it would give more
CONTAINER = "PendulumOnSuspension"


def interval(start: float, stop: float, step: float, macro_step: float | None = None) -> float:
    """The reference's output interval [s]: the default experiment's ``step``, or the smallest multiple of it
    (and of the container's ``macro_step``) that keeps the result to :data:`MOST_ROWS` intervals."""
    base = macro_step or step
    every = max(1, round(step / base))
    while (stop - start) / (every * base) > MOST_ROWS * (1 + 1e-9):
        every += 1
    return every * base


def csv_text(rows: Mapping[str, list[float]]) -> str:
    """Rows as Reference-FMUs' CSV: a header ``time,<names>``, then every value with 17 significant digits."""
    names = list(rows)
    lines = [",".join(names)]
    lines += [",".join(f"{rows[n][k]:.17g}" for n in names) for k in range(len(rows["time"]))]
    return "\n".join(lines) + "\n"


def manifest(model: str, step: float, description: str | None = None) -> bytes:
    """``fmi-ls-manifest.xml``: the one related file, the result of the default experiment."""
    ET.register_namespace("fmi-ls", "http://fmi-standard.org/fmi-ls-manifest")
    ls = "{http://fmi-standard.org/fmi-ls-manifest}"
    root = ET.Element("fmiReferences", {f"{ls}fmi-ls-name": "org.fmi-standard.fmi-ls-ref",
                                        f"{ls}fmi-ls-version": "1.0.0-alpha.1"})
    ET.SubElement(root, "Related", type="text/csv", source=f"{model}_out.csv", role="result",
                  description=description or f"Outputs of the default experiment every {step:g} s (computed at "
                  "build with the component the FMU runs)")
    ET.indent(root, space="    ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def reference_files(model: str, model_description: bytes, start_values: Mapping[str, Any]) -> dict[str, bytes]:
    """The manifest and ``<model>_out.csv`` of the FMU ``model`` (``DoublePendulum``, ``Suspension`` or the
    container) whose modelDescription is ``model_description``; ``start_values``: those baked into its build (the
    container's: its parameters' start values, ``DoublePendulum.phi1_0``)."""
    root = ET.fromstring(model_description)
    experiment = root.find("DefaultExperiment")
    start, stop = float(experiment.get("startTime", "0")), float(experiment.get("stopTime"))
    if start != 0.0:
        raise ValueError(f"{model}: a default experiment that starts at {start:g} s, not 0")
    step = float(experiment.get("stepSize"))
    outputs = [v.get("name") for v in root.find("ModelVariables") if v.get("causality") == "output"]
    if model == CONTAINER:
        macro = step  # the container's stepSize is its macro step (write_container; FMI 2 has no attribute for it)
        every = interval(start, stop, step, macro)
        rows = doc_plot.run(model, dict(start_values), stop, every, outputs, macro_step=macro)
    else:
        every = interval(start, stop, step)
        rows = doc_plot.run(model, dict(start_values), stop, every, outputs)
    return {MANIFEST: manifest(model, every), f"{FOLDER}/{model}_out.csv": csv_text(rows).encode()}


SSP_STATES = ("DoublePendulum.phi1", "DoublePendulum.phi2", "DoublePendulum.omega1", "DoublePendulum.omega2",
              "Suspension.x", "Suspension.y", "Suspension.vx", "Suspension.vy")
"""The SSP reference's columns: the states, which every master reads alike; the direct-feedthrough outputs (the
pivot force, the suspension's acceleration) depend on when a master reads them between its exchanges."""
LIBCOSIM_INITIAL_EXCHANGES = 2  # libcosim exchanges twice more while initialising (docs/coupling.md)


def ssp_reference_files(values: Mapping[str, Any], stop_time: float, macro_step: float) -> dict[str, bytes]:
    """The SSP's reference result, in the FMUs' layout: the coupled system from the monolith's start ``values`` as
    libcosim's fixed-step algorithm steps it (``jacobi``: both FMUs step on the inputs of the last exchange, then
    all outputs are passed; two extra exchanges while initialising), macro step ``macro_step`` [s], to
    ``stop_time`` [s], :data:`SSP_STATES` every :func:`interval`. Computed at build in-process with the two
    components; ``run_coupled`` reproduces libcosim to rounding (``tests/test_engines.py``). Kept per process for
    the same arguments, as :func:`double_pendulum.fmu.carries.doc_plot.run` keeps its runs."""
    return dict(_ssp_reference_files(json.dumps(dict(values), sort_keys=True), float(stop_time), float(macro_step)))


@functools.lru_cache(maxsize=8)
def _ssp_reference_files(values_json: str, stop_time: float, macro_step: float) -> dict[str, bytes]:
    from ..masters.coupling import run_coupled, split_values
    from ..presets import COMPONENTS

    every = interval(0.0, stop_time, macro_step, macro_step)
    pendulum_values, suspension_values = split_values(json.loads(values_json))
    pendulum, suspension = COMPONENTS["DoublePendulum"](), COMPONENTS["Suspension"]()
    for component, start in ((pendulum, pendulum_values), (suspension, suspension_values)):
        for name, value in start.items():
            component.set(name, value)
        component.initialise()
    names = [n.partition(".")[2] for n in SSP_STATES]
    rows = run_coupled(pendulum, suspension, stop_time=stop_time, macro_step=macro_step, scheme="jacobi",
                       pendulum_outputs=names[:4], suspension_outputs=names[4:],
                       initial_exchanges=LIBCOSIM_INITIAL_EXCHANGES)
    kept = rows[:: round(every / macro_step)]
    table = {"time": [k * every for k in range(len(kept))],
             **{full: kept[short].tolist() for full, short in zip(SSP_STATES, names)}}
    description = (f"States of the coupled system every {every:g} s as libcosim's fixed-step algorithm steps it "
                   f"(Jacobi, macro step {macro_step:g} s; computed at build in-process). Its difference to the "
                   "monolith, DoublePendulum with suspension on, is the coupling error, first order in the macro "
                   "step (docs/coupling.md)")
    return {MANIFEST: manifest(CONTAINER, every, description),
            f"{FOLDER}/{CONTAINER}_out.csv": csv_text(table).encode()}
