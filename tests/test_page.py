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
    (48.65185663245, 9.2e-05, "48.651857 \u00b1 0.000092"),
    (2.062512148422251, 0.0264751271309287, "2.063 \u00b1 0.026"),
    (1.5e-7, 2.5e-8, "(1.50 \u00b1 0.25) \u00d7 10^-7"),
    (19.986653319986655, None, "20.0"), (0.0015656906443263265, None, "0.00157"), (3.436e-09, None, "3.44e-09"),
    ([0.0, 37.2], None, "0 to 37.2"),
    ([2.7361, 2.7364], None, "2.74"),  # a range whose ends read the same is one value
    (19, None, "19"), (True, None, "yes"), ("regular", None, "regular"),
])
def test_a_figure_is_shown_with_its_uncertainty_to_two_digits(value, uncertainty, text):
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
        assert len(images) >= sum(len(figures) for figures in FIGURES.values())
        assert [src for src, loaded in images if not loaded] == []
        assert browser.evaluate("document.querySelectorAll('section:not(#conclusions)').length") == len(SCENARIOS)
        gif = browser.evaluate(
            "(() => { const i = document.querySelector('img[src$=\"measured_vs_sim.gif\"]'); i.scrollIntoView(); "
            "const r = i.getBoundingClientRect(); "
            "return {x: r.x + scrollX, y: r.y + scrollY, width: r.width, height: r.height}; })()")
        first = browser.screenshot(tmp_path / "gif_1.png", gif).read_bytes()
        later = first
        for attempt in range(20):  # the GIF moves on every 50 to 70 ms; a busy machine may draw late
            later = browser.screenshot(tmp_path / f"gif_{attempt + 2}.png", gif).read_bytes()
            if later != first:
                break
        assert later != first, "the animation does not play"
        shot = browser.screenshot(tmp_path / "index.png")
        links = browser.evaluate(
            "Array.from(document.querySelectorAll('#contents a, #conclusions a, a[href=\"#top\"]'))"
            ".map(a => [a.closest('nav, section') ? a.closest('nav, section').id : '', a.getAttribute('href'), "
            "!!document.getElementById(a.getAttribute('href').slice(1))])")
        assert [href for _, href, found in links if not found] == []  # every link of contents and conclusions lands
        assert {href for where, href, _ in links if where == "contents"} >= {f"#{name}" for name in SCENARIOS}
        assert {href for where, href, _ in links if where == "conclusions"} <= {f"#{name}" for name in SCENARIOS}
        assert browser.evaluate("getComputedStyle(document.querySelector('a.to-top')).position") == "fixed"
        for width in (1280, 390):  # a desktop window and a phone: never wider than the screen
            browser.emulate(width, 900, mobile=width < 500)
            assert browser.evaluate("document.documentElement.scrollWidth") <= width
            browser.screenshot(tmp_path / f"top_{width}.png", {"x": 0, "y": 0, "width": width, "height": 1500})
        assert browser.errors() == []
        assert {urlparse(url).scheme for url in browser.requested_urls()} == {"file"}  # nothing from the network
    assert shot.stat().st_size > 100_000
