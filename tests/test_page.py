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
from double_pendulum.scenarios import FIGURES, HEADLINES, READING_ORDER, SCENARIOS

from double_pendulum.runs.page import (
    Headline,
    RunInfo,
    ScenarioPage,
    format_figure,
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
    (19.986653319986655, None, "19.99"),
    ([0.0, 37.2], None, "0 to 37.2"),
    (19, None, "19"), (True, None, "yes"), ("regular", None, "regular"),
])
def test_a_figure_is_shown_with_its_uncertainty_to_two_digits(value, uncertainty, text):
    assert format_figure(value, uncertainty) == text


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
            uncertainty = lookup(summary, line.uncertainty) if line.uncertainty else None
            assert html.escape(format_figure(value, uncertainty)) in section, (name, line.label)
        assert 'class="short"' in section, f"{name}: no plain summary"
        assert f'href="{name}/summary.json"' in section


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
        assert browser.evaluate("document.querySelectorAll('section').length") == len(SCENARIOS)
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
        assert browser.errors() == []
        assert {urlparse(url).scheme for url in browser.requested_urls()} == {"file"}  # nothing from the network
    assert shot.stat().st_size > 100_000
