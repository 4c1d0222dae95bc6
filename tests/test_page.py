"""``index.html``, the page of a run: the summaries' numbers as written, every scenario's section, local links only,
and in a real browser (headless Chromium): every image loads, the animations play, the console stays clean."""

from __future__ import annotations

import datetime
import html
import json
import re
from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest
from browser import Browser, find_chromium
from double_pendulum.scenarios import ANIMATIONS, CONCLUSIONS, FIGURES, HEADLINES, READING_ORDER, SCENARIOS

from double_pendulum.runs.page import (
    STYLE,
    Headline,
    RunInfo,
    ScenarioPage,
    conclusion,
    format_figure,
    headline_text,
    in_short,
    lookup,
    null_reason,
    page_html,
)
from double_pendulum.runs.report_page import write_report_page

SRC_OR_HREF = re.compile(r'(?:src|href)="([^"]+)"')


def test_lookup_walks_keys_lists_selectors_and_scales():
    summary = {"a": {"b": [1.0, 2.0]}, "runs": [{"name": "x", "v": 3.0}], "regular / default / jacobi": 0.99,
               "m": {"regular / default": {"method": "iterative"}}}
    assert lookup(summary, "a/b/1") == 2.0
    assert lookup(summary, "a/b*100") == [100.0, 200.0]
    assert lookup(summary, "runs/[name=x]/v*0.5") == 1.5
    assert lookup(summary, "regular / default / jacobi") == 0.99  # a slash between spaces is part of a key
    assert lookup(summary, "m/regular / default/method") == "iterative"
    with pytest.raises(KeyError):
        lookup(summary, "a/c")


@pytest.mark.parametrize("value, uncertainty, text", [
    (-0.02515277933048963, 0.0020621874767029636, "-0.0252 \u00b1 0.0021"),
    (48.65185663245, 9.2e-05, "48.65186 \u00b1 0.00009"),  # issue 52: it read 48.651857 +- 0.000092
    (3.14159, 0.00097, "3.1416 \u00b1 0.0010"), (123.4, 4.2, "123 \u00b1 4"), (1234.5, 97.0, "1230 \u00b1 100"),
    (1.0, 0.0355, "1.00 \u00b1 0.04"), (0.5, 0.354, "0.50 \u00b1 0.35"),
    (2.062512148422251, 0.0264751271309287, "2.063 \u00b1 0.026"),
    (1.5e-7, 2.5e-8, "(1.50 \u00b1 0.25) \u00d7 10^-7"),
    (19.986653319986655, None, "20.0"), (0.0015656906443263265, None, "0.00157"), (3.436e-09, None, "3.44e-09"),
    ([0.0, 37.2], None, "0 to 37.2"),
    ([2.7361, 2.7364], None, "2.74"),  # a range whose ends read the same is one value
    (19, None, "19"), (True, None, "yes"), ("regular", None, "regular"),
])
def test_a_figure_is_shown_to_the_precision_its_uncertainty_supports(value, uncertainty, text):
    """The uncertainty to two significant digits where its leading ones are 100 to 354, else one (950 to 999 round up
    to two): the Particle Data Group's rule; the value to the same place."""
    assert format_figure(value, uncertainty) == text


@pytest.mark.parametrize("value, resolution, text", [
    (0.7340674007340675, 0.25, "0.7"), ([12.078745412078748, 19.986653319986655], 0.25, "12.1 to 20.0"),
    ([11.14447781114448, 15.015015015015017], 1 / 30, "11.14 to 15.02"), (0.9996548821187504, 0.01, "1.00"),
    (1234.5, 20.0, "1234"),
])
def test_a_figure_without_an_uncertainty_is_shown_to_its_resolution(value, resolution, text):
    assert format_figure(value, None, resolution) == text


def test_table_and_conclusion_show_a_figure_alike_and_a_missing_one_drops_the_sentence():
    summary = {"h": [12.07, 19.98], "smoothing": {"window_s": 0.25}, "n": 5, "gone": None}
    lines = (Headline("horizon", "h", unit="s", resolution="smoothing/window_s"), Headline("models", "n"),
             Headline("nothing", "gone"), Headline("absent", "no/such/key"))
    assert headline_text(lines[0], summary) == "12.1 to 20.0 s"
    page = ScenarioPage("x", "x", lines, conclusion="{1} models hold it for {0}.")
    assert conclusion(page, summary) == "5 models hold it for 12.1 to 20.0 s."
    assert conclusion(ScenarioPage("x", "x", lines, conclusion="It is {2}."), summary) is None  # null
    assert conclusion(ScenarioPage("x", "x", lines, conclusion="It is {3}."), summary) is None  # not in the summary
    assert conclusion(ScenarioPage("x", "x", lines), summary) is None


def test_the_conclusions_come_from_the_scenarios_that_ran_and_link_to_their_sections(tmp_path):
    for name, value in (("a", 1.5), ("b", 2.5), ("c", 3.5)):
        (tmp_path / name).mkdir()
        (tmp_path / name / "summary.json").write_text(json.dumps({"v": value}))
    pages = [ScenarioPage(name, name, (Headline("v", "v", unit="s"),), conclusion=f"{name} takes {{0}}.")
             for name in "abc"]
    text = page_html(tmp_path, _run(["a", "b", "c"], failed=["b"]), pages)
    found = text.split('<ul class="conclusions">', 1)[1].split("</ul>", 1)[0]
    assert 'a takes 1.50 s. (<a href="#a">a</a>)' in found and "c takes 3.50 s." in found
    assert "b takes" not in found  # failed in this run
    assert "c takes" not in page_html(tmp_path, _run(["a"]), pages)  # did not run
    assert 'href="#contents"' not in text and '<nav id="contents">' in text and 'href="#conclusions"' in text
    assert text.count('href="#top"') == 4 and 'id="top"' in text  # one a section, one always in the corner


def test_a_null_is_shown_with_the_reason_its_summary_gives():
    summary = {"horizons": {"run": {"h_5cm_s": None}}, "null_means": {"horizons": "not reached within 20 s"}}
    assert null_reason(summary, "horizons/run/h_5cm_s") == "not reached within 20 s"
    assert null_reason({"x": None}, "x") is None


def test_the_plain_summary_is_the_report_s_in_short_or_the_summary_s(tmp_path):
    (tmp_path / "report.md").write_text("# Title\n\n## In short\n\nIt **works**, `b` too.\n\n## Words used below\n")
    assert in_short(tmp_path, {"in_short": "not this"}) == "It **works**, `b` too."
    (tmp_path / "report.md").unlink()
    assert in_short(tmp_path, {"in_short": "this"}) == "this"


def test_a_report_is_a_web_page_rendered_from_its_markdown_with_tables_and_the_page_s_style(tmp_path):
    folder = tmp_path / "sc"
    folder.mkdir()
    (folder / "report.md").write_text("# Title\n\n## In short\n\nIt **works**.\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n"
                                      "![a figure](fig.png) <script>alert(1)</script>\n")
    (folder / "summary.json").write_text(json.dumps({"x": 1.0}))
    assert write_report_page(folder, STYLE) == folder / "report.html"
    text = (folder / "report.html").read_text()
    assert "<h1>Title</h1>" in text and "<strong>works</strong>" in text
    assert "<table>" in text and "<td>1</td>" in text  # tables enabled
    assert '<img src="fig.png" alt="a figure"' in text  # relative: the page sits beside the report
    assert "<script>" not in text and "&lt;script&gt;" in text  # HTML in the text is shown, not run
    assert STYLE in text and text.count('href="../index.html#sc"') == 2
    page_text = page_html(tmp_path, _run(["sc"]), [ScenarioPage("sc", "s", (Headline("x", "x"),))])
    assert 'href="sc/report.html"' in page_text and 'href="sc/report.md"' in page_text
    (tmp_path / "bare").mkdir()
    assert write_report_page(tmp_path / "bare", STYLE) is None and list((tmp_path / "bare").iterdir()) == []


def test_an_animation_is_one_player_its_gif_only_where_scripts_cannot_run(tmp_path):
    from double_pendulum.runs.player import Animation, Drawn

    folder = tmp_path / "sc"
    folder.mkdir()
    (folder / "run.gif").write_bytes(b"GIF89a" + (640).to_bytes(2, "little") + (480).to_bytes(2, "little"))
    (folder / "summary.json").write_text(json.dumps({"x": 1.0}))
    page = ScenarioPage("sc", "s", (Headline("x", "x"),), (("run.gif", "it swings"),),
                        animations=(Animation("run.gif", "it swings", (Drawn("FMU", "C0", "run.csv"),)),))
    missing = page_html(tmp_path, _run(["sc"]), [page])  # no CSV for the player: the GIF shows the motion
    assert 'class="dp-player"' not in missing and missing.count('<img src="sc/run.gif"') == 1
    assert "<noscript>" not in missing
    (folder / "run.csv").write_text('"time [s]","x1 [m]","y1 [m]","x2 [m]","y2 [m]"\n0.0,0.1,-0.2,0.2,-0.4\n'
                                    "0.05,0.11,-0.2,0.21,-0.4\n")
    text = page_html(tmp_path, _run(["sc"]), [page])
    assert text.count('class="dp-player"') == 1 and text.count('<img src="sc/run.gif"') == 1
    assert re.search(r'<noscript><a href="sc/run.gif"><img src="sc/run.gif"[^>]*></a></noscript>', text)


def _run(names, failed=()) -> RunInfo:
    return RunInfo(datetime.datetime(2026, 12, 2, 12, 0, tzinfo=datetime.UTC), "0.1.0", "quick", 30.0, 50.0,
                   "double-pendulum run all --quick", tuple(names), tuple(failed))


def test_a_failed_scenario_and_an_earlier_run_s_folder_are_said_so(tmp_path):
    (tmp_path / "b.failed").mkdir()
    (tmp_path / "c").mkdir()
    (tmp_path / "c" / "summary.json").write_text(json.dumps({"x": 1.0}))
    pages = [ScenarioPage("b", "the second"), ScenarioPage("c", "the third", (Headline("x", "x"),))]
    text = page_html(tmp_path, _run(["b"], failed=["b"]), pages)
    assert "This scenario failed in this run." in text and 'href="b.failed/"' in text
    assert "0 of 1 scenarios wrote their results" in text
    assert "From earlier runs in this folder" in text and 'href="c/summary.json"' in text
    (tmp_path / "c" / "summary.json").write_text("{ half written")  # whatever a scenario left, the page is written
    assert "Its summary.json cannot be read" in page_html(tmp_path, _run(["c"]), pages)


@pytest.fixture(scope="module")
def page(quick_results: Path) -> str:
    return (quick_results / "index.html").read_text(encoding="utf-8")


def test_every_scenario_declares_its_page_and_its_headlines_exist_in_its_summary(quick_results):
    assert sorted(READING_ORDER) == sorted(SCENARIOS)
    for name in SCENARIOS:
        summary = json.loads((quick_results / name / "summary.json").read_text())
        assert HEADLINES[name] and FIGURES[name], f"{name}: nothing for the page"
        for line in HEADLINES[name]:
            lookup(summary, line.value)  # a renamed key fails here
            if line.uncertainty:
                assert isinstance(lookup(summary, line.uncertainty), float), (name, line.uncertainty)
        for file_name, caption in FIGURES[name]:
            assert (quick_results / name / file_name).is_file(), f"{name}: no {file_name}"
            assert caption


def test_the_page_shows_each_scenario_with_the_figures_its_summary_holds(quick_results, page):
    assert "quick run" in page and "11 of 11 scenarios wrote their results" in page
    for name in SCENARIOS:
        section = page.split(f'<section id="{name}">', 1)[1].split("</section>", 1)[0]
        summary = json.loads((quick_results / name / "summary.json").read_text())
        for line in HEADLINES[name]:
            value = lookup(summary, line.value)
            if value is None:
                continue
            assert html.escape(headline_text(line, summary)) in section, (name, line.label)
        assert 'class="short"' in section, f"{name}: no plain summary"
        assert f'href="{name}/summary.json"' in section
        assert section.count('class="dp-player"') == len(ANIMATIONS.get(name, ())), f"{name}: not every player"
        for animation in ANIMATIONS.get(name, ()):  # one player; its GIF only where scripts cannot run
            gif = f'<img src="{name}/{animation.gif}"'
            assert section.count(gif) == 1 and f"<noscript><a href=\"{name}/{animation.gif}\">{gif}" in section
        if (quick_results / name / "report.md").is_file():
            assert f'href="{name}/report.html"' in section
    conclusions = page.split('<section id="conclusions">', 1)[1].split("</section>", 1)[0]
    assert conclusions.count("<li>") == min(5, len(CONCLUSIONS)), "a sentence for each of the first five that ran"


def test_the_page_is_self_contained(quick_results, page):
    assert "<script src" not in page and "http://" not in page and "https://" not in page  # inline scripts only
    targets = SRC_OR_HREF.findall(page)
    assert len(targets) > 50
    for target in targets:
        if target.startswith("#"):
            assert f'id="{target[1:]}"' in page
            continue
        assert not urlparse(target).scheme and not target.startswith("/"), target
        assert (quick_results / unquote(target)).exists(), f"link to a missing file: {target}"


BROWSER = find_chromium()


@pytest.mark.skipif(BROWSER is None, reason="no Chromium on PATH (Debian: apt-get install chromium; .ci/run installs "
                                            "it where it runs as root with apt)")
def test_the_page_in_a_real_browser_loads_every_image_plays_the_animations_and_logs_no_error(quick_results,
                                                                                            tmp_path):
    index = quick_results / "index.html"
    with Browser(BROWSER) as browser:
        browser.open(index.as_uri())
        images = browser.evaluate(
            "Array.from(document.images).map(i => [i.getAttribute('src'), i.complete && i.naturalWidth > 0])")
        players = sum(len(animations) for animations in ANIMATIONS.values())
        assert len(images) >= sum(len(figures) for figures in FIGURES.values()) - players
        assert [src for src, loaded in images if not loaded] == []
        assert [src for src, _ in images if src.endswith(".gif")] == []  # a GIF only in <noscript>: not shown
        assert browser.evaluate("document.querySelectorAll('.dp-player').length") == players
        assert browser.evaluate("document.querySelectorAll('section:not(#conclusions)').length") == len(SCENARIOS)
        player = "document.querySelector('#measured_vs_sim .dp-player')"
        browser.evaluate(f"{player}.scrollIntoView(), {player}.querySelector('.dp-play').click()")
        assert browser.wait_for(f"parseInt({player}.dataset.frame, 10) > 3"), "the player does not play"
        shot = browser.screenshot(tmp_path / "index.png")
        links = browser.evaluate(
            "Array.from(document.querySelectorAll('#contents a, #conclusions a, a[href=\"#top\"]'))"
            ".map(a => [a.closest('nav, section') ? a.closest('nav, section').id : '', a.getAttribute('href'), "
            "!!document.getElementById(a.getAttribute('href').slice(1))])")
        assert [href for _, href, found in links if not found] == []  # every link of contents and conclusions lands
        assert {href for where, href, _ in links if where == "contents"} >= {f"#{name}" for name in SCENARIOS}
        assert {href for where, href, _ in links if where == "conclusions"} <= {f"#{name}" for name in SCENARIOS}
        top = ("(() => { const a = document.querySelector('a.to-top'), r = a.getBoundingClientRect(), "
               "b = document.body.getBoundingClientRect(); return [getComputedStyle(a).display, "
               "getComputedStyle(a).position, r.left >= b.right || r.right <= b.left]; })()")
        wide = ("Array.from(document.querySelectorAll('figure.wide .frame'))"
                ".map(f => [f.scrollWidth > f.clientWidth + 50, f.querySelector('img').getBoundingClientRect().width])")
        for width in (1280, 390):  # a desktop window and a phone: never wider than the screen
            browser.emulate(width, 900, mobile=width < 500)
            assert browser.evaluate("document.documentElement.scrollWidth") <= width
            shown, position, beside = browser.evaluate(top)
            if width == 1280:  # in the margin beside the text column: it covers no text
                assert (shown, position, beside) == ("block", "fixed", True)
            else:  # no margin: no button; each section ends with a link to the top
                assert shown == "none"
            frames = browser.evaluate(wide)
            assert frames, "no figure of several panels side by side"
            if width == 390:  # wider than the screen, scrolled sideways within their own box
                assert all(scrolls and image_px >= 800 for scrolls, image_px in frames), frames
            else:
                assert not any(scrolls for scrolls, _ in frames), frames
            browser.screenshot(tmp_path / f"top_{width}.png", {"x": 0, "y": 0, "width": width, "height": 1500})
            section = browser.evaluate(
                "(() => { const r = document.querySelector('#measured_vs_sim').getBoundingClientRect(); "
                "return {x: 0, y: r.y + scrollY, width: innerWidth, height: Math.min(r.height, 3000)}; })()")
            browser.screenshot(tmp_path / f"measured_vs_sim_{width}.png", section)
        assert browser.errors() == []
        browser.open((quick_results / "loss_identification" / "report.html").as_uri())
        for width in (1280, 390):  # the report as a page: its tables, no wider than a phone's screen
            browser.emulate(width, 900, mobile=width < 500)
            assert browser.evaluate("document.querySelectorAll('table').length") >= 1
            assert browser.evaluate("document.documentElement.scrollWidth") <= width
            browser.screenshot(tmp_path / f"report_{width}.png", {"x": 0, "y": 0, "width": width, "height": 2000})
        assert browser.errors() == []
        assert {urlparse(url).scheme for url in browser.requested_urls()} == {"file"}  # nothing from the network
    assert shot.stat().st_size > 100_000
