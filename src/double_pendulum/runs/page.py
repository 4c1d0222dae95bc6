"""``index.html``: one page that shows a whole run, written into the output folder by every ``double-pendulum run``.

At the top the run itself (date, version, mode, wall and CPU time, the command), what the run found (a sentence of
each of up to five scenarios that ran, with their headline figures, linking to their sections: :func:`conclusion`)
and a table of contents; then, for each, its plain summary (the "In short" of its ``report.md``, or ``in_short`` of its
``summary.json``), its headline figures with their uncertainty, read from its ``summary.json`` as the scenario
wrote them (:class:`Headline`: nothing on the page is a number typed by hand), its key figures and animations,
and links to its report, its CSV files, its ``summary.json`` and its other figures. Scenario folders of earlier
runs that this run did not touch are listed at the end, with links.

The page is self-contained: plain HTML with its style sheet inline, every link and image a relative path into
the output folder, nothing from the network; its one script is the animations' player (:mod:`.player`,
inline). It is written atomically (:mod:`.results_io`). The
scenarios' registry (:mod:`double_pendulum.scenarios`) declares what it shows of each with the classes here, so
this module imports nothing slow at its top.
"""

from __future__ import annotations

import html
import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any

from .player import PLAYER_SCRIPT, PLAYER_STYLE, Animation, animation_html

PAGE = "index.html"


@dataclass(frozen=True)
class Headline:
    """A headline figure of a scenario: ``label`` in words, the ``value`` and its ``uncertainty`` (one standard
    error or the error budget's total, as the summary says) as paths into ``summary.json`` (:func:`lookup`), its
    ``unit``, and ``note``: the path of a text in the summary that qualifies it (e.g. why a horizon is a bound)."""

    label: str
    value: str
    uncertainty: str | None = None
    unit: str = ""
    note: str | None = None
    resolution: float | str | None = None
    """Without an uncertainty: the smallest difference the data resolve, in the value's unit (after its scale), a
    number or a path into the summary (e.g. a smoothing window [s]); the value is rounded to its first significant
    digit's decimal (:func:`format_figure`). None: :data:`SIGNIFICANT` significant digits."""


@dataclass(frozen=True)
class ScenarioPage:
    """What the page shows of one scenario: its ``description``, its :class:`Headline` figures, its key
    ``figures`` (file name and caption, in the order shown) and its sentence of the run's ``conclusion``."""

    name: str
    description: str
    headlines: Sequence[Headline] = ()
    figures: Sequence[tuple[str, str]] = ()
    conclusion: str = ""
    """One sentence of the run's conclusions at the top of the page, with ``{0}``, ``{1}``, ... where the headline
    figures of that index go, formatted as in the table (:func:`conclusion`); "" for none."""
    animations: Sequence[Animation] = ()  # the players shown in place of their GIFs (:mod:`.player`)


@dataclass(frozen=True)
class RunInfo:
    """The run the page is about: when it ``started``, the package ``version``, its ``mode`` (quick, default or
    thorough), its wall and CPU time [s], the ``command``, the scenarios it ran (in the order given), those of
    them that ``failed`` and the user's ``record`` if it analysed one."""

    started: datetime
    version: str
    mode: str
    wall_s: float
    cpu_s: float
    command: str
    ran: Sequence[str]
    failed: Sequence[str] = field(default_factory=tuple)
    record: str = ""
    """The file name of a user's own camera track the run analysed (``--track``); "" for the seed's."""


_PART = re.compile(r"(?<! )/(?! )")
"""Path parts are separated by ``/``; a ``/`` between spaces belongs to a key (``"regular / default / jacobi"``)."""


def lookup(summary: Any, path: str) -> Any:
    """The value at ``path`` in ``summary``: keys separated by ``/`` (see :data:`_PART`), an integer indexes a list,
    ``[name=value]`` selects the list entry whose ``name`` is ``value``; ``*SCALE`` at the end multiplies a number
    (each number of a list) by SCALE. A KeyError (or IndexError) if the path does not exist; None where a part of
    it is null (a summary's null, which its ``null_means`` explain: :func:`null_reason`)."""
    path, _, scale = path.partition("*")
    value = summary
    for part in _PART.split(path):
        if value is None:
            return None
        selector = re.fullmatch(r"\[(\w+)=(.+)\]", part)
        if selector:
            value = next(v for v in value if str(v.get(selector[1])) == selector[2])
        elif isinstance(value, list):
            value = value[int(part)]
        else:
            value = value[part]
    if not scale:
        return value
    factor = float(scale)
    if isinstance(value, list):
        return [v * factor if isinstance(v, (int, float)) and not isinstance(v, bool) else v for v in value]
    return value * factor if isinstance(value, (int, float)) and not isinstance(value, bool) else value


def null_reason(summary: Any, path: str) -> str | None:
    """Why the value at ``path`` is null: the text of a ``null_means`` entry at or above it that names a key on
    the path (as the summaries explain their nulls), or None."""
    parts = _PART.split(path.partition("*")[0])
    node, reason = summary, None
    for part in parts:
        if isinstance(node, dict):
            means = node.get("null_means", {})
            reason = next((means[p] for p in parts if p in means), reason)
            node = node.get(part)
        elif isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        else:
            break
    return reason


SIGNIFICANT = 3
"""Significant digits of a headline value that has neither an uncertainty nor a resolution."""


def _decimals(uncertainty: float, digits: int = 2) -> int:
    """Decimals that show ``uncertainty`` (> 0) to ``digits`` significant digits."""
    return max(0, digits - 1 - math.floor(math.log10(uncertainty)))


def rounded_uncertainty(uncertainty: float) -> tuple[float, int]:
    """``uncertainty`` (> 0) rounded as the Particle Data Group rounds an error, and the place of its last digit (the
    power of ten: -5 for 0.00009): to two significant digits if its three leading digits are 100 to 354, to one if
    they are 355 to 949, and 950 to 999 up to 1000, two digits (0.000092 -> 0.00009; 0.0264 -> 0.026;
    0.00097 -> 0.0010; 97 -> 100). A value is shown to the same place: as precise as its uncertainty supports."""
    exponent = math.floor(math.log10(uncertainty))
    leading = round(uncertainty / 10.0 ** (exponent - 2))  # 100 .. 1000
    place = exponent - 1 if leading <= 354 else exponent
    return round(uncertainty, -place), place


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def format_figure(value: Any, uncertainty: Any = None, resolution: Any = None) -> str:
    """A headline value as text, the one format of the page's table and its conclusions.

    A number with its uncertainty u > 0 as ``v +- u`` (u to one or two significant digits,
    :func:`rounded_uncertainty`, v to the same decimal); a number
    with a ``resolution`` r > 0 (the smallest difference its data resolve) to the decimal of r's first significant
    digit (r = 0.25 s: one decimal); any other float to :data:`SIGNIFICANT` significant digits; a range ``lo to hi``
    (each end so), one value where both ends read the same; yes/no; or the text."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, list) and len(value) == 2 and all(_is_number(v) for v in value):
        low, high = (format_figure(v, None, resolution) for v in value)
        return low if low == high else f"{low} to {high}"
    if isinstance(value, int):
        return str(value)
    if not isinstance(value, float):
        return str(value)
    if _is_number(uncertainty) and uncertainty > 0:
        exponent = math.floor(math.log10(abs(value))) if value and not 1e-3 <= abs(value) < 1e5 else 0
        u, place = rounded_uncertainty(float(uncertainty) / 10**exponent)
        v, digits = round(value / 10**exponent, -place), max(0, -place)
        text = f"{v:.{digits}f} \u00b1 {u:.{digits}f}"
        return f"({text}) \u00d7 10^{exponent}" if exponent else text
    if not math.isfinite(value) or value == 0:
        return f"{value:g}"
    if _is_number(resolution) and resolution > 0:
        return f"{value:.{_decimals(float(resolution), 1)}f}"
    if not 1e-3 <= abs(value) < 1e5:
        return f"{value:.{SIGNIFICANT - 1}e}"
    return f"{value:.{_decimals(abs(value), SIGNIFICANT)}f}"


def headline_text(line: Headline, summary: Mapping[str, Any]) -> str | None:
    """The headline ``line`` of ``summary`` as the page shows it (:func:`format_figure`, with its unit); "none: why"
    for a null; None if the summary does not have it (e.g. a setting of the thorough run only)."""
    try:
        value = lookup(summary, line.value)
        uncertainty = lookup(summary, line.uncertainty) if line.uncertainty else None
        resolution = lookup(summary, line.resolution) if isinstance(line.resolution, str) else line.resolution
    except (KeyError, IndexError, StopIteration, TypeError):
        return None
    if value is None:
        return "none: " + (null_reason(summary, line.value) or "no value in summary.json")
    return format_figure(value, uncertainty, resolution) + (f" {line.unit}" if line.unit else "")


def conclusion(page: ScenarioPage, summary: Mapping[str, Any]) -> str | None:
    """The scenario's sentence for the run's conclusions: :attr:`ScenarioPage.conclusion` with its headline figures
    put in as the table shows them; None if it has none, or if a figure it needs is missing or null."""
    if not page.conclusion:
        return None
    figures = []
    for index in map(int, re.findall(r"\{(\d+)\}", page.conclusion)):
        text = headline_text(page.headlines[index], summary) if index < len(page.headlines) else None
        if text is None or text.startswith("none:"):
            return None
        figures.append((index, text))
    sentence = page.conclusion
    for index, text in figures:
        sentence = sentence.replace(f"{{{index}}}", text)
    return sentence


def in_short(folder: Path, summary: Mapping[str, Any]) -> str:
    """The scenario's plain summary: the "In short" paragraph of its ``report.md``, else ``in_short`` of its summary
    ("" if it has neither)."""
    from .results_io import IN_SHORT  # here: the scenarios' registry imports this module, and NumPy is slow

    report = folder / "report.md"
    if report.is_file():
        text = report.read_text(encoding="utf-8")
        if IN_SHORT in text:
            after = text.split(IN_SHORT, 1)[1]
            return re.split(r"\n(?:#|---)", after, maxsplit=1)[0].strip()
    return str(summary.get("in_short", ""))


def _inline(text: str) -> str:
    """Markdown text as HTML: escaped, ``**bold**`` and ```code``` kept."""
    text = html.escape(text)
    text = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", text)
    return re.sub(r"`([^`]+)`", r"<code>\1</code>", text)


def _link(href: str, text: str) -> str:
    return f'<a href="{html.escape(href)}">{html.escape(text)}</a>'


def _headline_rows(page: ScenarioPage, summary: Mapping[str, Any]) -> list[str]:
    rows = []
    for line in page.headlines:
        shown = headline_text(line, summary)
        if shown is None:
            continue  # not in this run's summary (e.g. a setting of the thorough run only)
        note = ""
        if line.note:
            try:
                found = lookup(summary, line.note)
            except (KeyError, IndexError, StopIteration, TypeError):
                found = None
            note = "" if found is None else str(found)  # a null note is no text ("None")
        source = line.value + (f", \u00b1 {line.uncertainty}" if line.uncertainty else "")
        rows.append(f'<tr><td>{html.escape(line.label)}</td><td class="value" title="summary.json: '
                    f'{html.escape(source)}">{html.escape(shown)}</td><td class="note">{html.escape(note)}</td></tr>')
    return rows


def _files(folder: Path, shown: set[str]) -> str:
    """The links to a scenario folder's report, summary, CSV files and the figures not shown above."""
    name = folder.name
    parts = []
    if (folder / "report.md").is_file():  # its page, report.html, is written with index.html (write_index)
        parts.append("report: " + _link(f"{name}/report.html", "report") + " (its Markdown: "
                     + _link(f"{name}/report.md", "report.md") + ")")
    parts.append("figures in numbers: " + _link(f"{name}/summary.json", "summary.json"))
    csv = sorted(p.name for p in folder.glob("*.csv"))
    if csv:
        parts.append("data: " + ", ".join(_link(f"{name}/{c}", c) for c in csv))
    more = sorted(p.name for p in folder.iterdir() if p.suffix in (".png", ".gif") and p.name not in shown)
    if more:
        parts.append("more figures: " + ", ".join(_link(f"{name}/{m}", m) for m in more))
    return '<p class="files">' + " &middot; ".join(parts) + "</p>"


def _mode(summary: Mapping[str, Any]) -> str:
    return "quick run" if summary.get("quick") else "thorough run" if summary.get("thorough") else "default run"


def _read_summary(folder: Path) -> tuple[dict[str, Any] | None, str]:
    """A scenario folder's ``summary.json``: (the summary, "") or (None, why not: "" if there is none)."""
    path = folder / "summary.json"
    if not path.is_file():
        return None, ""
    try:
        return json.loads(path.read_text(encoding="utf-8")), ""
    except (OSError, ValueError) as error:  # the page is written whatever a scenario left
        return None, f"Its summary.json cannot be read ({error})."


BACK = '<p class="back"><a href="#top">back to the top</a></p>'


def _section(out: Path, page: ScenarioPage, failed: bool) -> str:
    folder = out / page.name
    head = f'<section id="{page.name}"><h2>{html.escape(page.name)}</h2><p class="what">' \
           f"{html.escape(page.description)}</p>"
    if failed:
        kept = f"{page.name}.failed"
        note = (" What it wrote is in " + _link(f"{kept}/", f"{kept}/") + ".") if (out / kept).is_dir() else ""
        earlier = " The results below are from an earlier run." if (folder / "summary.json").is_file() else ""
        head += f'<p class="failed">This scenario failed in this run.{note}{earlier}</p>'
    summary, error = _read_summary(folder)
    if summary is None:
        return head + (f'<p class="failed">{html.escape(error)}</p>' if error else "") + BACK + "</section>"
    summary_path = folder / "summary.json"
    written = datetime.fromtimestamp(summary_path.stat().st_mtime).strftime("%Y-%m-%d %H:%M")
    parts = [head, f'<p class="mode">{_mode(summary)}, written {written}</p>']
    record = summary.get("record")
    if isinstance(record, dict) and "file" in record:  # a user's own track (run --track)
        parts.append(f'<p class="record">Record: <strong>{html.escape(str(record["file"]))}</strong>, '
                     f'{html.escape(str(record.get("whose", "")))}</p>')
    text = in_short(folder, summary)
    if text:
        parts.append(f'<p class="short">{_inline(text)}</p>')
    rows = _headline_rows(page, summary)
    if rows:
        parts.append('<table class="headlines"><thead><tr><th>headline figure</th><th>value</th><th></th></tr></thead>'
                     f'<tbody>{"".join(rows)}</tbody></table>')
    shown = set()
    for name, caption in page.figures:
        if (folder / name).is_file():
            shown.add(name)
            parts.append(_figure(folder, page, name, caption))
    parts.append(_files(folder, shown))
    return "\n".join([*parts, BACK]) + "</section>"


def _figure(folder: Path, page: ScenarioPage, name: str, caption: str) -> str:
    """A key figure of the scenario in ``folder``, linked to its file (a tap opens it full size). An animation's GIF
    with a player (:mod:`.player`) is shown as the player, the one animation where scripts run; the GIF stands in
    for it only where they cannot (``<noscript>``), or where the player's CSV files are missing."""
    src = html.escape(f"{page.name}/{name}")
    image = f'<a href="{src}"><img src="{src}" alt="{html.escape(caption)}"></a>'
    players = [player for player in (animation_html(folder, a) for a in page.animations if a.gif == name) if player]
    if players:
        return (f'<figure class="animation">{"".join(players)}<noscript>{image}</noscript><figcaption>'
                f'{html.escape(caption)}: play, pause, step or drag the time (the same as a GIF: '
                f'<a href="{src}">{html.escape(name)}</a>)</figcaption></figure>')
    size = _pixels(folder / name)
    if size is not None and size[0] >= WIDE_PX:  # on a phone shown wider than the screen, scrolled in its box
        return (f'<figure class="wide"><div class="frame">{image}</div><figcaption>{html.escape(caption)} '
                f'({html.escape(name)})<span class="narrow">: scroll it sideways, or tap it for the full size'
                "</span></figcaption></figure>")
    return f"<figure>{image}<figcaption>{html.escape(caption)} ({html.escape(name)})</figcaption></figure>"


WIDE_PX = 1100
"""A figure at least this many pixels wide (several panels side by side: 14 in at 100 dpi is 1400) is shown at
:data:`PHONE_FIGURE` on a phone, scrolled sideways in its box, so that its labels stay readable."""
PHONE_FIGURE = "52rem"


def _pixels(path: Path) -> tuple[int, int] | None:
    """Width and height [pixels] of a PNG or GIF file, read from its header (None for another kind of file)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(24)
    except OSError:
        return None
    if head.startswith(b"\x89PNG\r\n\x1a\n") and len(head) == 24:
        return int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")
    if head[:6] in (b"GIF87a", b"GIF89a"):
        return int.from_bytes(head[6:8], "little"), int.from_bytes(head[8:10], "little")
    return None


STYLE = """
body { font-family: system-ui, sans-serif; max-width: 62rem; margin: 1.5rem auto; padding: 0 1rem; color: #222;
       line-height: 1.45; overflow-wrap: break-word; }
h1 { font-size: 1.6rem; margin-bottom: 0.2rem; } h2 { margin-top: 2.5rem; border-bottom: 1px solid #ccc; }
.run, .mode, .what, figcaption, .files { color: #555; } .what { font-style: italic; margin-top: 0; }
.conclusions { font-size: 1.05em; } .conclusions li { margin: 0.35rem 0; }
table.headlines { border-collapse: collapse; margin: 0.8rem 0; } .headlines td, .headlines th {
  border-bottom: 1px solid #e4e4e4; padding: 0.25rem 0.8rem 0.25rem 0; text-align: left; vertical-align: top; }
.headlines .value { white-space: nowrap; font-variant-numeric: tabular-nums; } .note { color: #666; font-size: 0.9em; }
figure { margin: 1rem 0; } img { max-width: 100%; height: auto; border: 1px solid #eee; }
.failed { color: #a00; font-weight: bold; } .files { font-size: 0.92em; overflow-wrap: anywhere; }
code { font-size: 0.95em; overflow-wrap: anywhere; } nav li { margin: 0.15rem 0; } .back { font-size: 0.9em; }
a.to-top { display: none; } .narrow { display: none; } .frame { overflow-x: auto; }
@media (min-width: 72rem) {
  a.to-top { display: block; position: fixed; right: 0.8rem; bottom: 0.8rem; padding: 0.2rem 0.6rem; background: #fff;
    border: 1px solid #bbb; border-radius: 0.3rem; font-size: 0.9em; text-decoration: none; }
}
@media (max-width: 40rem) {
  figure.wide img { width: PHONE_FIGURE; max-width: none; } .narrow { display: inline; }
  body { margin: 0.8rem auto; padding: 0 0.7rem; } h1 { font-size: 1.35rem; }
  .headlines thead { display: none; } .headlines tr { display: block; border-bottom: 1px solid #e4e4e4;
    padding: 0.35rem 0; } .headlines td { display: block; border: none; padding: 0.05rem 0; }
  .headlines .value { white-space: normal; font-weight: bold; } .headlines .note:empty { display: none; }
}
"""
STYLE = STYLE.replace("PHONE_FIGURE", PHONE_FIGURE)
"""The page's style sheet. Below 40rem (a phone) a headline table's rows become blocks, label above value above
note, so that the page is never wider than the screen, and a wide figure is shown at :data:`PHONE_FIGURE`, scrolled
sideways in its box (a tap opens it full size). The "top" button sits in the margin beside the 62rem column, so only
where there is one (72rem and wider): nowhere does it cover text; below that each section ends with a link to the
top."""


MOST_CONCLUSIONS = 5
"""At most this many sentences of conclusions at the top of the page."""


def _conclusions(out: Path, ran: Sequence[ScenarioPage], failed: set[str]) -> list[str]:
    """The run's conclusions: the sentence of each scenario that wrote its results in this run and declares one
    (:func:`conclusion`), in the page's order, at most :data:`MOST_CONCLUSIONS`, each linking to its section."""
    items = []
    for page in ran:
        if page.name in failed or not page.conclusion or len(items) == MOST_CONCLUSIONS:
            continue
        summary, _ = _read_summary(out / page.name)
        sentence = conclusion(page, summary) if summary is not None else None
        if sentence:
            items.append(f'<li>{html.escape(sentence)} ({_link(f"#{page.name}", page.name)})</li>')
    return items


def page_html(out: Path, run: RunInfo, pages: Sequence[ScenarioPage]) -> str:
    """The HTML of ``index.html`` for ``run`` in the output folder ``out``; ``pages`` in the order shown (the
    scenarios of the run among them get a section, the other folders in ``out`` a line at the end)."""
    ran = [p for p in pages if p.name in run.ran]
    earlier = [p for p in pages if p.name not in run.ran and (out / p.name / "summary.json").is_file()]
    failed = set(run.failed)
    status = f"{len(ran) - len(failed & {p.name for p in ran})} of {len(ran)} scenarios wrote their results"
    when = run.started.astimezone().strftime("%Y-%m-%d %H:%M %Z")
    head = ['<h1 id="top">Double pendulum: the results of a run</h1>',
            f'<p class="run">{html.escape(when)} &middot; double-pendulum-fmu {html.escape(run.version)} &middot; '
            f"{html.escape(run.mode)} run &middot; {run.wall_s:.0f} s (CPU {run.cpu_s:.0f} s) &middot; "
            f"<code>{html.escape(run.command)}</code><br>{status}.</p>"]
    if run.record:
        head.append(f'<p class="record">Record analysed: <strong>{html.escape(run.record)}</strong>, your own camera '
                    "track (not the seed's); every figure of its scenarios is computed from it.</p>")
    found = _conclusions(out, ran, failed)
    if found:
        head += ['<section id="conclusions"><h2>What this run found</h2><ul class="conclusions">', *found,
                 "</ul></section>"]
    head.append('<nav id="contents"><h2>Contents</h2><ul>')
    if found:
        head.append(f'<li>{_link("#conclusions", "What this run found")}</li>')
    for p in ran:
        mark = " (failed)" if p.name in failed else ""
        head.append(f'<li><a href="#{p.name}">{html.escape(p.name)}</a>{mark}: {html.escape(p.description)}</li>')
    if earlier:
        head.append(f'<li>{_link("#earlier", "From earlier runs in this folder")}</li>')
    head.append("</ul></nav>")
    body = [_section(out, p, p.name in failed) for p in ran]
    if earlier:
        items = "".join(f"<li>{_link(f'{p.name}/summary.json', p.name)}: {html.escape(p.description)}</li>"
                        for p in earlier)
        body.append(f'<section id="earlier"><h2>From earlier runs in this folder</h2><ul>{items}</ul>{BACK}</section>')
    body.append('<a class="to-top" href="#top">&uarr; top</a>')
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<title>Double pendulum: results of a {html.escape(run.mode)} run</title>"
            f"<style>{STYLE}{PLAYER_STYLE}</style>"
            f"{PLAYER_SCRIPT}</head><body>\n" + "\n".join([*head, *body]) + "\n</body></html>\n")


def write_index(out: Path, run: RunInfo, pages: Sequence[ScenarioPage]) -> Path:
    """Write ``out/index.html`` (:func:`page_html`) and the report page of each scenario of the run that has a
    ``report.md`` (:mod:`.report_page`), atomically; return the index's path."""
    from .report_page import write_report_page
    from .results_io import write_text

    for page in pages:
        if page.name in run.ran:
            write_report_page(Path(out) / page.name, STYLE)
    return write_text(Path(out) / PAGE, page_html(Path(out), run, pages))
