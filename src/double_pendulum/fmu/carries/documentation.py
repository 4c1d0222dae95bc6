"""``documentation/index.html`` of an FMU, generated at build from the sources the package documents itself with.

Nothing here is a second copy of the documentation: the page is assembled from

* the FMU's own ``modelDescription.xml`` (name, description, interfaces, GUID, default experiment, the
  variable table with units and start values) and the validity rules of the interface's parameters
  (:mod:`double_pendulum.component.variables`: the "valid values" column);
* the model's module docstrings (the equations, :data:`MODEL_SOURCES`), rendered by
  :mod:`double_pendulum.fmu.carries.docstring_html`;
* the parameter groups' docstrings and switches (:data:`SWITCH_GROUPS`: the switches of a scene);
* the FMU's binaries folders, read for what each holds (the loader, the CPython it carries) and needs of the
  target machine (:mod:`double_pendulum.fmu.carries.elf_needs`), the CPython a lean FMU recorded at build and the
  loader's docstring (how the FMU finds its Python, :mod:`double_pendulum.fmu.build.loader`);
* the result plot ``result.png`` of the FMU's default run (:mod:`double_pendulum.fmu.carries.doc_plot`).

The page is plain HTML with its style inline and no script, so the simple HTML views of FMI tools show
it as a browser does.
"""

from __future__ import annotations

import html
import importlib
import io
import re
import zipfile
from collections.abc import Mapping, Sequence
from dataclasses import fields
from xml.etree import ElementTree as ET

from ... import __version__
from ...component.variables import INTERFACES
from ...model.parameters import MAX_START_ANGLE, AirDragParameters, BearingParameters, SuspensionParameters
from .. import presets
from . import elf_needs
from .docstring_html import docstring_html, inline_html, summary

MODEL_SOURCES: dict[str, tuple[str, ...]] = {
    "DoublePendulum": ("model.dynamics", "model.links", "model.kinematics", "model.forces", "model.inputs"),
    "DoublePendulumFmi3": ("model.dynamics", "model.links", "model.kinematics", "model.forces", "model.inputs",
                           "component.model_exchange"),
    "Suspension": ("model.suspension", "component.suspension"),
    "PendulumOnSuspension": ("fmu.build.container",),
}
"""The modules (under ``double_pendulum``) whose docstrings are the page's "The model" section."""
SWITCH_GROUPS = {"DoublePendulum": (AirDragParameters, BearingParameters, SuspensionParameters)}
RULES = {"positive": "> 0", "nonnegative": "≥ 0", "finite": "finite", "bool": "true, false", "str": "text",
         "count": "whole number ≥ 1", "angle": f"within ±{MAX_START_ANGLE:g} rad"}
RESULT_PLOT = "documentation/result.png"
STYLE = """
body { font-family: Helvetica, Arial, sans-serif; margin: 2em; color: #1b1f23; line-height: 1.45; }
div.container { max-width: 960px; margin: auto; }
h1, h2 { border-bottom: 1px solid #eaecef; padding-bottom: .3em; }
h3 { margin-top: 1.6em; }
p.lead { font-size: 1.1em; }
code { background-color: #f3f4f6; padding: 0 .2em; border-radius: 3px; font-size: 90%; }
pre { background-color: #f6f8fa; border-radius: 3px; font-size: 85%; padding: 12px; overflow: auto; }
table { border-collapse: collapse; border-spacing: 0; margin: 1em 0; display: block; max-width: 100%;
        overflow-x: auto; }
th, td { font-size: 0.88em; border: 1px solid #dfe2e5; padding: 4px 9px; text-align: left; vertical-align: top; }
th { background-color: #f6f8fa; }
td.number { text-align: right; white-space: nowrap; }
div.equation { font-family: 'Times New Roman', Times, serif; font-size: 1.15em; margin: .8em 2em; overflow-x: auto; }
span.math { font-family: 'Times New Roman', Times, serif; font-size: 1.08em; white-space: nowrap; }
figure { margin: 1em 0; }
figcaption { font-size: 0.9em; color: #57606a; }
footer { margin-top: 3em; font-size: 0.8em; color: #57606a; }
img { max-width: 100%; height: auto; }
h1, h2, h3, p, li { overflow-wrap: break-word; } p code, li code { overflow-wrap: anywhere; }
@media (max-width: 40rem) { body { margin: 0.8em; } h1 { font-size: 1.6em; } div.equation { margin: .8em 0; } }
"""
"""The page's style sheet. A table wider than the screen scrolls on its own, so that the page is never wider than
a phone's screen (the page's viewport tag makes a phone lay it out at its own width)."""


def _module_doc(name: str) -> str:
    return importlib.import_module(f"{__package__.partition('.')[0]}.{name}").__doc__ or ""


def model_section(sources: Sequence[str]) -> str:
    """"The model": each source module's summary as a heading, its docstring as the text."""
    parts = []
    for name in sources:
        doc = _module_doc(name)
        parts.append(f"<h3>{inline_html(summary(doc))}</h3>\n{docstring_html(doc)}")
    return "\n".join(parts)


def switches_section(groups: Sequence[type]) -> str:
    """"The switches of a scene": per parameter group, its docstring and its Boolean switches."""
    parts = []
    for group in groups:
        doc = group.__doc__ or ""
        switches = [f for f in fields(group) if f.metadata["rule"] == "bool"]
        others = [f.name for f in fields(group) if f.metadata["rule"] != "bool"]
        items = "\n".join(f"<li><code>{f.name}</code> (start {presets.literal(f.default)}): "
                          f"{inline_html(f.metadata['description'])}</li>" for f in switches)
        parts.append(f"<h3>{inline_html(summary(doc))}</h3>\n{docstring_html(doc)}\n<ul>\n{items}\n</ul>\n"
                     f"<p>Parameters: {', '.join(f'<code>{n}</code>' for n in others)}.</p>")
    return "\n".join(parts)


def _rules(model: str, names: Sequence[str]) -> dict[str, str]:
    """The valid values of each variable, from the interface's rules (the container's by component)."""
    by_model = {m: {v.name: v.rule for v in INTERFACES[m].variables()} for m in INTERFACES}
    rules = {}
    for name in names:
        owner, _, variable = name.rpartition(".")
        rule = by_model.get(owner or model, {}).get(variable, "")
        rules[name] = RULES.get(rule, "")
    return rules


def variables_table(root: ET.Element, model: str) -> str:
    """The modelDescription's variables: name, causality, variability, type, start, unit, valid values."""
    fmi3 = root.get("fmiVersion", "").startswith("3")
    rows = []
    variables = list(root.find("ModelVariables"))
    rules = _rules(model, [v.get("name") for v in variables])
    for variable in variables:
        if fmi3:
            kind, start = variable.tag, variable.get("start")
            if kind == "String" and variable.find("Start") is not None:
                start = variable.find("Start").get("value")
            unit = variable.get("unit", "")
        else:
            typed = next(iter(variable))
            kind, start, unit = typed.tag, typed.get("start"), typed.get("unit", "")
        name = variable.get("name")
        cells = [f"<code>{html.escape(name)}</code>", variable.get("causality", "local"),
                 variable.get("variability", "continuous"), kind]
        rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells)
                    + f'<td class="number">{html.escape(start or "")}</td><td>{html.escape(unit)}</td>'
                    f"<td>{html.escape(rules[name])}</td>"
                    f"<td>{html.escape(variable.get('description') or '')}</td></tr>")
    head = "".join(f"<th>{h}</th>" for h in ("name", "causality", "variability", "type", "start", "unit",
                                             "valid values", "description"))
    return f"<table>\n<thead><tr>{head}</tr></thead>\n<tbody>\n" + "\n".join(rows) + "\n</tbody>\n</table>"


def about_table(root: ET.Element, start_values: Mapping[str, object]) -> str:
    """Facts of the FMU: FMI version, interfaces, identifiers, tool, default experiment, baked start values."""
    interfaces = [e for e in root if e.tag in ("ModelExchange", "CoSimulation")]
    experiment = root.find("DefaultExperiment")
    rows = [("FMI version", root.get("fmiVersion")),
            ("interfaces", ", ".join(f"{e.tag} (model identifier <code>{e.get('modelIdentifier')}</code>)"
                                     for e in interfaces)),
            ("GUID" if root.get("guid") else "instantiation token",
             f"<code>{html.escape(root.get('guid') or root.get('instantiationToken') or '')}</code>"),
            ("generated by", html.escape(f"{root.get('generationTool')}, double-pendulum-fmu {__version__}"))]
    if root.get("version") or root.get("license"):
        facts = filter(None, (root.get("version"), root.get("license")))
        rows.append(("version, licence", html.escape(", ".join(facts))))
    if experiment is not None:
        rows.append(("default experiment", ", ".join(f"{k} {html.escape(v)}" for k, v in experiment.attrib.items())))
    if start_values:
        rows.append(("start values of this build", html.escape(presets.describe(start_values))))
    return "<table>\n" + "\n".join(f"<tr><th>{k}</th><td>{v}</td></tr>" for k, v in rows) + "\n</table>"


_CARRIED = re.compile(rb"CPython (3\.\d+\.\d+) ")  # the comment of a carried standard library's zip


def python_version(stdlib: bytes, library: str) -> str:
    """The full version of a carried CPython ("3.11.7"), from its zipped standard library's comment, else the minor
    version from the name of its library."""
    try:
        found = _CARRIED.match(zipfile.ZipFile(io.BytesIO(stdlib)).comment)
    except zipfile.BadZipFile:
        found = None
    if found:
        return found.group(1).decode()
    digits = re.search(r"python(\d)\.?(\d+)", library)
    return f"{digits.group(1)}.{digits.group(2)}" if digits else "?"


def _is_python_library(file: str) -> bool:
    return bool(re.fullmatch(r"libpython3\.\d+\.so(\.[\d.]+)?|python3\d+\.dll", file))


def _folder_row(folder: str, files: Mapping[str, bytes]) -> str:
    """One row of the machine table: what ``folder`` (``.../binaries/<platform>/``) holds and what it needs."""
    inside = {name[len(folder):]: data for name, data in files.items() if name.startswith(folder) and
              "/" not in name[len(folder):]}
    windows = any(name.endswith(".dll") for name in inside)
    loaders = sorted(name for name in inside if name.startswith("container_fmu") or
                     (name.endswith((".so", ".dll")) and name.rsplit(".", 1)[0] in INTERFACES))
    libraries = sorted(name for name in inside if _is_python_library(name))
    what = [html.escape("fmpy's container binary (no Python)") if name.startswith("container_fmu") else
            f"the loader <code>{html.escape(name)}</code> (the FMI functions)" for name in loaders]
    if libraries:
        extensions = [name for name in inside if name.endswith(".pyd") or ".cpython-" in name]
        others = sorted(name for name in inside if name.endswith((".dll", ".so")) or ".so." in name)
        others = [name for name in others if name not in loaders and name not in libraries and name not in extensions]
        zipped = [name for name in inside if name.endswith(".zip")]
        modules = sum(1 for n in zipfile.ZipFile(io.BytesIO(inside[zipped[0]])).namelist() if n.endswith(".pyc")) \
            if zipped else 0
        what.append(f"the CPython {python_version(inside[zipped[0]] if zipped else b'', libraries[0])} it carries: "
                    f"<code>{html.escape(libraries[0])}</code>, {modules} modules of its standard library in "
                    f"<code>{html.escape(zipped[0] if zipped else '')}</code>, {len(extensions)} extension modules"
                    + (f", and what they need: {', '.join(f'<code>{html.escape(n)}</code>' for n in others)}"
                       if others else ""))
    elif loaders and not any(name.startswith("container_fmu") for name in loaders):
        what.append("no Python of its own: it uses the one of a Python host, else finds one (below)")
    if windows:
        needs = "Windows 10 or newer, x64 (the Universal C Runtime, part of Windows since 10)"
    else:
        floors = [elf_needs.newest(elf_needs.version_needs(data), "GLIBC") for data in inside.values()
                  if data[:4] == b"\x7fELF"]
        floor = max((f for f in floors if f), key=elf_needs.version_key, default=None)
        needs = f"Linux on x86-64 with glibc &gt;= {floor.partition('_')[2]}" if floor else "Linux on x86-64"
    size = sum(len(data) for data in inside.values()) / 1e6
    return (f"<tr><td><code>{html.escape(folder)}</code></td><td>{'; '.join(what)}</td><td>{needs}</td>"
            f"<td class=\"number\">{size:.1f} MB</td></tr>")


def machine_section(files: Mapping[str, bytes], model: str) -> str:
    """What a target machine needs: each binaries folder of the FMU (a container's components too), what it holds
    (the loader, the CPython it carries) and what it asks of the system (glibc, read from every Linux binary in
    it: :mod:`~double_pendulum.fmu.carries.elf_needs`), the CPython a lean FMU was built with, and how the loader
    finds a Python (its docstring)."""
    folders = sorted({name.rpartition("/")[0] + "/" for name in files if "binaries/" in name and
                      name.split("/")[-2] != "binaries" and name.rpartition("/")[0].split("/")[-2] == "binaries"})
    rows = [_folder_row(folder, files) for folder in folders]
    record = [f for f in sorted(files) if f.endswith("resources/python.cfg")]
    recorded = ""
    if record:
        lines = [line for line in files[record[0]].decode().splitlines() if line and not line.startswith("#")]
        recorded = (f"<p>The CPython this FMU was built with (<code>{html.escape(record[0])}</code>):</p>\n"
                    f"<pre>{html.escape(chr(10).join(lines))}</pre>")
    intro = ("<p>The container's own binary (fmpy's <code>container_fmu</code>) needs no Python; each of its two "
             "FMUs, under <code>resources/</code>, carries its own, and the first to start in a process starts it "
             "for both:</p>" if model == "PendulumOnSuspension" else "")
    loader_doc = _module_doc("fmu.build.loader")
    head = "<thead><tr><th>binaries</th><th>what they are</th><th>needs of the system</th><th>size</th></tr></thead>"
    return (f"{intro}\n<table>\n{head}\n<tbody>\n"
            + "\n".join(rows) + f"\n</tbody>\n</table>\n{recorded}\n"
            f"<h3>{inline_html(summary(loader_doc))}</h3>\n{docstring_html(loader_doc)}")


def carried_section(files: Mapping[str, bytes]) -> str:
    """Links to what the FMU carries besides its code: the reference result (``extra/org.fmi-standard.fmi-ls-ref``)
    and the licence of everything it bundles (``documentation/licenses``), by their paths in the FMU."""
    results = sorted(p for p in files if p.startswith("extra/org.fmi-standard.fmi-ls-ref/") and p.endswith(".csv"))
    licences = sorted(p for p in files if p.startswith("documentation/licenses/"))
    parts = []
    if results:
        links = ", ".join(f'<a href="../{html.escape(p)}"><code>{html.escape(p)}</code></a>' for p in results)
        parts.append(f"<p>The outputs of the default experiment, computed at build: {links} (the layout of "
                     "Reference-FMUs; <code>fmi-ls-manifest.xml</code> beside it says what it holds). A host that "
                     "runs the FMU with its defaults at that output interval should get these numbers.</p>")
    if licences:
        items = "".join(f'<li><a href="{html.escape(p.removeprefix("documentation/"))}">'
                        f'{html.escape(p.rpartition("/")[2].removesuffix(".txt"))}</a></li>' for p in licences)
        parts.append(f"<p>Licences of what this FMU bundles:</p>\n<ul>{items}</ul>")
    return "\n".join(parts)


def index_html(model: str, model_description: bytes, files: Mapping[str, bytes],
               start_values: Mapping[str, object], plot_caption: str) -> str:
    """The page of one FMU: ``model`` names its kind (a key of :data:`MODEL_SOURCES`), ``files`` are the FMU's
    other files (binaries, ``python.cfg``), ``start_values`` those baked into the build."""
    root = ET.fromstring(model_description)
    kind = model if model in MODEL_SOURCES else "DoublePendulum"
    base = "DoublePendulum" if kind == "DoublePendulumFmi3" else kind
    title = html.escape(root.get("modelName", base))
    sections = [
        f"<h1>{title}</h1>\n<p class=\"lead\">{html.escape(root.get('description', ''))}</p>",
        about_table(root, start_values),
        f"<h2>Result</h2>\n<figure><img src=\"{RESULT_PLOT.rpartition('/')[2]}\" alt=\"result plot\" width=\"700\">"
        f"<figcaption>{plot_caption}</figcaption></figure>",
        f"<h2>The model</h2>\n{model_section(MODEL_SOURCES[kind])}",
    ]
    if base == "PendulumOnSuspension":
        sections.append("<p>The two FMUs inside have their own documentation: "
                        + ", ".join(f'<a href="../resources/{n}/documentation/index.html">{n}</a>'
                                    for n in ("DoublePendulum", "Suspension")) + ".</p>")
    if base in SWITCH_GROUPS:
        sections.append(f"<h2>The switches of a scene</h2>\n{switches_section(SWITCH_GROUPS[base])}")
    sections += [f"<h2>Variables</h2>\n{variables_table(root, base)}",
                 f"<h2>What a target machine needs</h2>\n{machine_section(files, base)}",
                 f"<h2>Reference result and licences</h2>\n{carried_section(files)}",
                 f"<footer>Generated by double-pendulum-fmu {__version__} from the package's docstrings and this "
                 "FMU's modelDescription.xml.</footer>"]
    body = "\n\n".join(sections)
    return (f"<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f"<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>{title}</title>\n"
            f"<style>{STYLE}</style>\n</head>\n<body>\n<div class=\"container\">\n{body}\n</div>\n</body>\n</html>\n")


def untranslated_markup(page: str) -> list[str]:
    """reST or TeX the page shows raw (roles, double back-quotes, backslash commands); empty when clean."""
    text = re.sub(r"<pre>.*?</pre>", "", page, flags=re.S)
    return re.findall(r":\w+:`|``|\\[A-Za-z]+", text)
