"""What a tool shows of an FMU, added to every FMU the build writes: documentation, icon and terminals.

:func:`presentation_files` gives the files, by their path in the FMU:

* ``documentation/index.html`` and ``documentation/result.png`` (:mod:`double_pendulum.fmu.carries.documentation`,
  :mod:`double_pendulum.fmu.carries.doc_plot`);
* the icon: ``model.png`` (FMI 2.0) and ``terminalsAndIcons/icon.png`` (FMI 3.0, and FMI 2.0.4's
  back-port), :mod:`double_pendulum.fmu.carries.icons`;
* ``terminalsAndIcons/terminalsAndIcons.xml`` with the terminals of the FMU's variables and their
  pictures (:mod:`double_pendulum.fmu.carries.terminals`);
* ``documentation/licenses/<distribution>.txt``: the licence of everything the FMU bundles
  (:func:`licence_files`);
* ``extra/org.fmi-standard.fmi-ls-ref/``: the reference result of the default experiment, in Reference-FMUs'
  layout (:mod:`double_pendulum.fmu.carries.reference_result`).

The build adds them in :func:`double_pendulum.fmu.build.staging.rewrite_fmu` (DoublePendulum, Suspension, the
FMI 3 DoublePendulum) and :func:`double_pendulum.fmu.build.container.write_container` (the container).
"""

from __future__ import annotations

import importlib.metadata
from collections.abc import Mapping
from typing import Any
from xml.etree import ElementTree as ET

from . import doc_plot, documentation, icons, reference_result, terminals

CONTAINER = "PendulumOnSuspension"
CONTAINER_PLOT_TIME = 2.0  # [s] of the container's result plot (its default experiment runs 10 s)


def _typed(kind: str, text: str | None) -> Any:
    if kind == "Boolean":
        return text == "true"
    if kind == "String":
        return text
    if kind in ("Integer", "Int32"):
        return int(text)
    return float(text)


def _parameter_starts(root: ET.Element) -> dict[str, Any]:
    """The container's parameters and their start values (it holds the scene as its starts)."""
    starts = {}
    for variable in root.find("ModelVariables"):
        if variable.get("causality") == "parameter":
            typed = next(iter(variable))
            starts[variable.get("name")] = _typed(typed.tag, typed.get("start"))
    return starts


def _plot_case(model: str, fmi_version: int, root: ET.Element,
               start_values: Mapping[str, Any]) -> tuple[dict, float, float, str]:
    """Start values, stop time [s], interval [s] and caption of the result plot."""
    experiment = root.find("DefaultExperiment")
    stop, step = float(experiment.get("stopTime")), float(experiment.get("stepSize"))
    if model == CONTAINER:
        stop = min(stop, CONTAINER_PLOT_TIME)
        caption = (f"The two FMUs coupled as the container couples them (the force passed first, inputs held over "
                   f"each macro step of {step:g} s), from the container's start values, over {stop:g} s; computed "
                   "at build in-process with the components the FMUs run.")
        return _parameter_starts(root), stop, step, caption
    inputs = "no inputs"
    if model == "Suspension":
        inputs = (f"the inputs F_x = {doc_plot.SUSPENSION_STEP['F_x']:g} N and F_y = F_static_y - 1 N from t = 0 "
                  "(a load step: at its default inputs the mass stays at rest)")
    caption = (f"The FMU's default run: its start values (the table below), {stop:g} s, a communication point "
               f"every {step:g} s, {inputs}. Computed at build with the component the FMU runs, which gives the "
               "FMU's numbers" + (" (under Model Exchange, a host's solver gives them to its tolerance)."
                                  if fmi_version == 3 else "."))
    return dict(start_values), stop, step, caption


# What each FMU bundles, by the distribution it comes from: the project's runtime and adapters, and the FMI
# library's Python part (FMI 2: pythonfmu, FMI 3: pythonfmu3); the container fmpy's container binary (its two
# FMUs inside carry their own licences).
BUNDLED = {2: ("double-pendulum-fmu", "pythonfmu"), 3: ("double-pendulum-fmu", "pythonfmu3")}
CONTAINER_BUNDLED = ("double-pendulum-fmu", "fmpy")
LICENCE_FOLDER = "documentation/licenses"


def distribution_licence(name: str) -> bytes:
    """The licence text(s) the installed distribution ``name`` ships in its metadata (PEP 639's licenses/, or
    the older place beside METADATA), joined; raises LookupError if it ships none."""
    dist = importlib.metadata.distribution(name)
    texts = [f.read_text(encoding="utf-8") for f in (dist.files or [])
             if ".dist-info" in str(f) and f.name.upper().startswith(("LICEN", "COPYING"))]
    if not texts:
        raise LookupError(f"the installed {name} ships no licence file in its metadata")
    return "\n".join(texts).encode()


def licence_files(model: str, fmi_version: int) -> dict[str, bytes]:
    """``documentation/licenses/<distribution>.txt`` for everything the FMU ``model`` bundles."""
    names = CONTAINER_BUNDLED if model == CONTAINER else BUNDLED[fmi_version]
    return {f"{LICENCE_FOLDER}/{name}.txt": distribution_licence(name) for name in names}


def presentation_files(model: str, fmi_version: int, files: Mapping[str, bytes],
                       start_values: Mapping[str, Any] | None = None) -> dict[str, bytes]:
    """The documentation, icon and terminal files of an FMU whose other files are ``files``.

    ``model``: ``DoublePendulum``, ``Suspension`` or ``PendulumOnSuspension`` (the container);
    ``start_values``: those baked into the build (:mod:`double_pendulum.fmu.presets`).
    """
    start_values = dict(start_values or {})
    md = files["modelDescription.xml"]
    root = ET.fromstring(md)
    page_kind = "DoublePendulumFmi3" if (model, fmi_version) == ("DoublePendulum", 3) else model
    plot_values, stop, step, caption = _plot_case(model, fmi_version, root, start_values)
    # plot_values: the FMU's own start values (the container's: its parameters'), also the reference run's
    carried = {**licence_files(model, fmi_version), **reference_result.reference_files(model, md, plot_values)}
    page = documentation.index_html(page_kind, md, {**files, **carried}, start_values, caption)
    out = {
        documentation.RESULT_PLOT: doc_plot.result_plot(model, plot_values, stop, step),
        "documentation/index.html": page.encode(),
        "terminalsAndIcons/icon.png": icons.icon(model),
        **carried,
    }
    if fmi_version == 2:
        out["model.png"] = icons.icon(model)
    names = [v.get("name") for v in root.find("ModelVariables")]
    found = [t for prefix in (("DoublePendulum.", "Suspension.") if model == CONTAINER else ("",))
             for t in terminals.terminals_for(names, prefix)]
    out[terminals.FILE] = terminals.terminals_xml(found)
    for path in sorted(terminals.icon_files(found)):
        out[path] = icons.terminal_icon(path.rpartition("/")[2].removesuffix(".png"))
    return out

