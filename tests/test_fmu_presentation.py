"""What a tool shows of each FMU the build writes: documentation/index.html with its result plot, the icon
(model.png, terminalsAndIcons/icon.png) and terminalsAndIcons.xml, valid against FMI 3.0's schema and
naming only the FMU's own variables (double_pendulum.fmu.carries.presentation)."""

from __future__ import annotations

import html
import re
import sys
import zipfile
from pathlib import Path
from urllib.parse import urlparse
from xml.etree import ElementTree as ET

import numpy as np
import pytest
from browser import Browser, find_chromium
from fmpy import read_model_description, simulate_fmu

from double_pendulum.fmu.carries import doc_plot, documentation, terminals
from double_pendulum.fmu.carries.docstring_html import docstring_html, inline_html
from double_pendulum.fmu.carries.tex_html import UnsupportedTeX, tex_to_html

FMUS = ("DoublePendulum.fmu", "Suspension.fmu", "PendulumOnSuspension.fmu", "fmi3/DoublePendulum.fmu")
PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def contents(fmu_path: Path) -> dict[str, dict[str, bytes]]:
    """Every file of every FMU of the session's build, by FMU (path relative to the build folder)."""
    out = {}
    for name in FMUS:
        with zipfile.ZipFile(fmu_path.parent / name) as z:
            out[name] = {item: z.read(item) for item in z.namelist()}
    return out


def schema():
    import fmpy
    from lxml import etree

    return etree.XMLSchema(etree.parse(str(Path(fmpy.__file__).parent / "schema" / "fmi3" /
                                           "fmi3TerminalsAndIcons.xsd")))


@pytest.mark.parametrize("name", FMUS)
def test_every_fmu_carries_documentation_icon_and_terminals(contents, name):
    files = contents[name]
    for path in ("documentation/index.html", documentation.RESULT_PLOT, "terminalsAndIcons/icon.png", terminals.FILE):
        assert path in files, path
    assert files[documentation.RESULT_PLOT].startswith(PNG) and files["terminalsAndIcons/icon.png"].startswith(PNG)
    fmi2 = not name.startswith("fmi3/")
    assert ("model.png" in files) == fmi2  # FMI 2.0's icon; FMI 3.0 has terminalsAndIcons/icon.png only
    if fmi2:
        assert files["model.png"] == files["terminalsAndIcons/icon.png"]


@pytest.mark.parametrize("name", FMUS)
def test_terminals_and_icons_validate_and_name_only_the_fmus_variables(contents, name):
    from lxml import etree

    files = contents[name]
    xsd = schema()
    document = etree.fromstring(files[terminals.FILE])
    assert xsd.validate(document), xsd.error_log
    assert document.get("fmiVersion") == "3.0"  # FMI 2.0.4: the FMI 3.0 definition the file follows
    variables = {v.get("name") for v in ET.fromstring(files["modelDescription.xml"]).find("ModelVariables")}
    members = [m.get("variableName") for m in document.iter("TerminalMemberVariable")]
    assert members and set(members) <= variables
    for picture in document.iter("TerminalGraphicalRepresentation"):
        assert files[f"terminalsAndIcons/{picture.get('iconBaseName')}.png"].startswith(PNG)


def terminal_members(files: dict[str, bytes]) -> dict[str, dict[str, str]]:
    root = ET.fromstring(files[terminals.FILE])
    return {t.get("name"): {m.get("memberName"): m.get("variableName") for m in t.iter("TerminalMemberVariable")}
            for t in root.iter("Terminal")}


def test_the_pendulums_pivot_plugs_into_the_suspensions_mount(contents):
    """Same member names, one side's inputs the other side's outputs: what the container wires."""
    pendulum = terminal_members(contents["DoublePendulum.fmu"])
    suspension = terminal_members(contents["Suspension.fmu"])
    assert set(pendulum) == {"pivot", "joint_torques", "angles"} and set(suspension) == {"mount"}
    assert set(pendulum["pivot"]) == set(suspension["mount"]) == {"x", "y", "vx", "vy", "ax", "ay", "F_x", "F_y"}

    def causality(name):
        root = ET.fromstring(contents[name]["modelDescription.xml"])
        return {v.get("name"): v.get("causality") for v in root.find("ModelVariables")}

    mine, theirs = causality("DoublePendulum.fmu"), causality("Suspension.fmu")
    for member, variable in pendulum["pivot"].items():
        assert {mine[variable], theirs[suspension["mount"][member]]} == {"input", "output"}, member
    assert pendulum["joint_torques"] == {"tau1": "tau1", "tau2": "tau2"}
    assert terminal_members(contents["fmi3/DoublePendulum.fmu"]) == pendulum
    assert terminal_members(contents["PendulumOnSuspension.fmu"]) == {
        "angles": {"phi1": "DoublePendulum.phi1", "phi2": "DoublePendulum.phi2"}}
    # the container has the angles but not their rates: its terminal says so, the pendulum's does not need to
    descriptions = {name: {t.get("name"): t.get("description") for t in ET.fromstring(contents[name][terminals.FILE])
                           .iter("Terminal")} for name in ("DoublePendulum.fmu", "PendulumOnSuspension.fmu")}
    assert descriptions["PendulumOnSuspension.fmu"]["angles"].endswith("(this FMU has phi1, phi2 only)")
    assert "only" not in descriptions["DoublePendulum.fmu"]["angles"]


@pytest.mark.parametrize("name", FMUS)
def test_the_documentation_lists_every_variable_with_its_start_and_unit(contents, name):
    page = contents[name]["documentation/index.html"].decode()
    root = ET.fromstring(contents[name]["modelDescription.xml"])
    rows = re.findall(r"<tr><td><code>([^<]+)</code></td>(.*?)</tr>", page.split("<h2>Variables</h2>")[1])
    table = {html.unescape(n): cells for n, cells in rows}
    for variable in root.find("ModelVariables"):
        cells = table[variable.get("name")]
        typed = variable if name.startswith("fmi3/") else next(iter(variable))
        start = typed.get("start") or (typed.find("Start").get("value") if typed.find("Start") is not None else "")
        assert f'<td class="number">{html.escape(start)}</td><td>{html.escape(typed.get("unit", ""))}</td>' in cells
    assert documentation.untranslated_markup(page) == []
    assert re.search(r'<img src="result.png"', page)
    assert (root.get("guid") or root.get("instantiationToken")) in page


def test_the_pendulums_page_has_its_equations_switches_rules_and_needs(contents):
    page = contents["DoublePendulum.fmu"]["documentation/index.html"].decode()
    assert "Equations of motion of the planar double pendulum" in page and 'class="equation"' in page
    for switch in ("air_drag", "rod_drag", "bearing_friction", "bearing_drag", "suspension"):
        assert f"<li><code>{switch}</code> (start false)" in page
    assert "<td>m1</td>" not in page and "<code>m1</code></td><td>parameter</td><td>fixed</td><td>Real</td>" in page
    assert re.search(r"<code>l1</code>.*?<td>&gt; 0</td>", page)  # l1 must be > 0
    needs = page.split("What a target machine needs")[1]
    minor = sys.version_info[1]
    for folder, library, system in (("linux64", f"libpython3.{minor}.so.1.0", "glibc &gt;= 2."),
                                    ("win64", f"python3{minor}.dll", "Windows 10 or newer")):
        row = re.search(rf"<tr><td><code>binaries/{folder}/</code></td>(.*?)</tr>", needs).group(1)
        assert f"the CPython 3.{minor}." in row and f"<code>{library}</code>" in row and system in row, row
    assert "DOUBLE_PENDULUM_FMU_PYTHON" in needs  # how it finds its Python
    assert "needs nothing installed" in needs and "only the standard library" in needs  # and what that Python needs
    fmi3 = contents["fmi3/DoublePendulum.fmu"]["documentation/index.html"].decode()
    assert "Model Exchange of the FMI 3 <code>DoublePendulum</code> FMU" in fmi3


def test_the_containers_page_links_the_pages_of_its_two_fmus(contents):
    files = contents["PendulumOnSuspension.fmu"]
    page = files["documentation/index.html"].decode()
    for target in re.findall(r'href="\.\./([^"]+)"', page):
        assert target in files
    assert len(re.findall(r'href="\.\./resources/\w+/documentation/index.html"', page)) == 2
    assert "fmpy&#x27;s container binary (no Python)" in page


def test_the_result_plot_shows_the_fmus_own_numbers(fmu_path):
    """doc_plot.run is the FMU's run: the same numbers as fmpy through the built FMU."""
    plotted = doc_plot.run("DoublePendulum", {"phi1_0": 2.0}, 1.0, 0.01)
    result = simulate_fmu(str(fmu_path), start_values={"phi1_0": 2.0}, stop_time=1.0, output_interval=0.01,
                          output=["phi1", "omega2"])
    assert plotted["phi1"] == result["phi1"].tolist() and plotted["omega2"] == result["omega2"].tolist()


def test_the_containers_plot_is_the_container_run(fmu_path):
    container = fmu_path.parent / "PendulumOnSuspension.fmu"
    assert read_model_description(str(container)).defaultExperiment.stepSize == "0.001"
    plotted = doc_plot.run("PendulumOnSuspension", {"DoublePendulum.phi1_0": 1.0}, 0.2, 1e-3)
    result = simulate_fmu(str(container), stop_time=0.2, output_interval=1e-3,
                          output=["DoublePendulum.phi1", "Suspension.x"])
    assert np.allclose(plotted["DoublePendulum.phi1"], result["DoublePendulum.phi1"], rtol=0, atol=1e-12)
    assert np.allclose(plotted["Suspension.x"], result["Suspension.x"], rtol=0, atol=1e-12)


def test_a_build_with_baked_start_values_documents_and_plots_them(tmp_path):
    from double_pendulum.fmu.build.fmi2 import build_fmu

    fmu = build_fmu(tmp_path / "Chaotic.fmu", "DoublePendulum", {"phi1_0": 2.0, "phi2_0": 2.0})
    with zipfile.ZipFile(fmu) as z:
        page = z.read("documentation/index.html").decode()
        plot = z.read(documentation.RESULT_PLOT)
    assert "<th>start values of this build</th><td>phi1_0 = 2.0, phi2_0 = 2.0</td>" in page
    assert plot == doc_plot.result_plot("DoublePendulum", {"phi1_0": 2.0, "phi2_0": 2.0}, 10.0, 0.01)


@pytest.mark.parametrize(("tex", "expected"), [
    (r"\dot\varphi_1^2", "φ\u0307<sub>1</sub><sup>2</sup>"),
    (r"\tfrac12 M_s |\dot{\vec s}|^2", "½<i>M</i><sub><i>s</i></sub>|<b>s\u0307</b>|<sup>2</sup>"),
    (r"Q_1 \mathrel{+}= \tau_1 - \tau_2", "<i>Q</i><sub>1</sub> += τ<sub>1</sub> − τ<sub>2</sub>"),
    (r"\tanh(\omega/\omega_{reg}) \ge 0", "tanh\u2009(ω/ω<sub>reg</sub>) ≥ 0"),
    (r"W_{bearing\_drag}", "<i>W</i><sub>bearing_drag</sub>"),
])
def test_formulas_become_plain_html(tex, expected):
    assert tex_to_html(tex) == expected


def test_unknown_tex_stops_the_build_naming_it():
    with pytest.raises(UnsupportedTeX, match=r"unsupported TeX \\begin in formula"):
        tex_to_html(r"\begin{pmatrix} a \end{pmatrix}")


def test_docstrings_become_paragraphs_lists_equations_and_code():
    doc = '''Summary line.

    A paragraph with ``code``, :math:`x_1`, :class:`~pkg.mod.Thing` and **bold**
    over two lines.

    * first item,
      continued
    * second

    .. math::

        a = b

        c = d
        + e

    Literal::

        raw <text>
    '''
    out = docstring_html(doc)
    assert "Summary" not in out
    assert ("<p>A paragraph with <code>code</code>, <span class=\"math\"><i>x</i><sub>1</sub></span>, "
            "<code>Thing</code> and <strong>bold</strong> over two lines.</p>") in out
    assert "<ul>\n<li>first item, continued</li>\n<li>second</li>\n</ul>" in out
    assert '<div class="equation"><i>a</i> = <i>b</i></div>' in out
    assert '<div class="equation"><i>c</i> = <i>d</i><br>+ <i>e</i></div>' in out
    assert "<p>Literal:</p>\n<pre>raw &lt;text&gt;</pre>" in out
    assert inline_html("a < b") == "a &lt; b"


@pytest.mark.parametrize("name", FMUS)
def test_every_page_links_the_fmus_reference_result_and_licences(contents, name):
    """The page points to what the FMU carries besides its code, and each link resolves inside the FMU."""
    files = contents[name]
    page = files["documentation/index.html"].decode()
    carried = page.split("Reference result and licences")[1]
    links = re.findall(r'href="([^"]+)"', carried)
    resolved = [link.removeprefix("../") if link.startswith("../") else f"documentation/{link}" for link in links]
    assert all(path in files for path in resolved), resolved
    assert any(p.startswith("extra/org.fmi-standard.fmi-ls-ref/") and p.endswith("_out.csv") for p in resolved)
    assert {p for p in resolved if p.startswith("documentation/licenses/")} == {
        p for p in files if p.startswith("documentation/licenses/")}


BROWSER = find_chromium()


@pytest.mark.skipif(BROWSER is None, reason="no Chromium on PATH (Debian: apt-get install chromium; .ci/run installs "
                                            "it where it runs as root with apt)")
def test_each_page_in_a_real_browser_shows_its_plot_and_fits_a_phone_and_a_desktop(contents, tmp_path):
    """Each FMU's page as a tool's user opens it (unzipped): the result plot loads, nothing is asked of the
    network, no error is logged, and the page is never wider than a 1280 px window or a 390 px phone: a wide table
    scrolls on its own, the page does not."""
    with Browser(BROWSER) as browser:
        for name in FMUS:
            folder = tmp_path / name.replace("/", "_")
            for item, data in contents[name].items():
                if item.startswith(("documentation/", "extra/")):
                    (folder / item).parent.mkdir(parents=True, exist_ok=True)
                    (folder / item).write_bytes(data)
            browser.open((folder / "documentation" / "index.html").as_uri())
            images = browser.evaluate("Array.from(document.images).map(i => [i.getAttribute('src'), "
                                      "i.complete && i.naturalWidth > 0])")
            assert images and all(loaded for _, loaded in images), (name, images)
            for width in (1280, 390):
                browser.emulate(width, 900, mobile=width < 500)
                wide = browser.evaluate("document.documentElement.scrollWidth")
                assert wide <= width, f"{name}: the page is {wide} px wide in a {width} px window"
                browser.screenshot(tmp_path / f"{folder.name}_{width}.png",
                                   {"x": 0, "y": 0, "width": width, "height": 1500})
        assert browser.errors() == []
        assert {urlparse(url).scheme for url in browser.requested_urls()} == {"file"}
