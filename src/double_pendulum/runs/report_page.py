"""A scenario's ``report.md`` as a web page, ``report.html`` beside it, which the run's page links to.

A browser shows a Markdown file as plain text (the reports hold about 15,800 words, with tables): the page is
rendered by markdown-it-py (CommonMark, with tables), styled by the run page's own style sheet (given:
:data:`~double_pendulum.runs.page.STYLE`) and :data:`REPORT_STYLE` (a wide table or a formula scrolls sideways
inside its own box, so that the page is never wider than a phone's screen), with a link back to the scenario's
section of ``index.html``. Relative links and images keep working: the page sits beside the report. Written
atomically (:mod:`.results_io`).
"""

from __future__ import annotations

import html
from pathlib import Path

REPORT = "report.md"
REPORT_PAGE = "report.html"

REPORT_STYLE = """
.report table { display: block; overflow-x: auto; border-collapse: collapse; margin: 0.8rem 0; }
.report th, .report td { border-bottom: 1px solid #e4e4e4; padding: 0.25rem 0.7rem 0.25rem 0; text-align: left;
  vertical-align: top; min-width: 4.5rem; }
.report th { border-bottom: 1px solid #aaa; } .report pre { overflow-x: auto; background: #f6f6f6; padding: 0.5rem; }
.report blockquote { color: #555; border-left: 3px solid #ddd; margin-left: 0; padding-left: 0.8rem; }
.report h1 { margin-top: 0.5rem; } .report h2 { margin-top: 2rem; }
"""
"""What a report adds to the run page's style sheet: tables and code blocks that scroll sideways in their own box."""


def render_markdown(text: str) -> str:
    """Markdown ``text`` as HTML: CommonMark and tables (markdown-it-py); HTML written in the text is escaped."""
    from markdown_it import MarkdownIt

    return MarkdownIt("commonmark", {"html": False}).enable("table").render(text)


def report_html(folder: Path, style: str) -> str:
    """The page of ``folder``'s ``report.md``: its text rendered, a link back to its section of the run's page, the
    run page's ``style`` sheet and :data:`REPORT_STYLE`."""
    name = folder.name
    back = f'<p class="back"><a href="../index.html#{html.escape(name)}">back to the run\'s page</a></p>'
    body = render_markdown((folder / REPORT).read_text(encoding="utf-8"))
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<title>{html.escape(name)}: report</title><style>{style}{REPORT_STYLE}</style></head><body>\n"
            f'{back}<article class="report">\n{body}</article>{back}\n</body></html>\n')


def write_report_page(folder: Path, style: str) -> Path | None:
    """Write ``folder/report.html`` from ``folder/report.md`` in the run page's ``style`` (None, and nothing written,
    if there is no report)."""
    from .results_io import write_text

    if not (folder / REPORT).is_file():
        return None
    return write_text(folder / REPORT_PAGE, report_html(folder, style))
