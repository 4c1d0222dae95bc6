"""A docstring of the package (the reStructuredText subset it uses) as HTML, for the FMU's documentation.

The documentation inside each FMU is generated from the sources the package documents itself with,
so it cannot drift from them: the model's module docstrings (equations), the parameter groups'
docstrings (the switches of a scene). This turns one docstring into HTML:

* paragraphs; bullet (``*``, ``-``) and numbered (``1.``) lists with indented continuation lines;
* ``.. math::`` blocks: one formula per blank-line-separated group, its source lines kept as lines;
* literal blocks after a paragraph ending in ``::``;
* inline ``:math:`...```, ``:mod:``, ``:func:``, ``:class:``, ``:meth:``, ``:data:`` (as code, ``~``
  keeps the last name), ````code````, ``**strong**`` and ``*emphasis*``.

Formulas go through :func:`double_pendulum.fmu.carries.tex_html.tex_to_html`.
"""

from __future__ import annotations

import html
import inspect
import re

from .tex_html import tex_to_html

INLINE = re.compile(r":(?P<role>\w+):`(?P<target>[^`]+)`|``(?P<code>.+?)``|\*\*(?P<strong>.+?)\*\*"
                    r"|(?<![\w*])\*(?P<em>[^*\s][^*]*?)\*(?!\w)")
BULLET = re.compile(r"^(?:[*-]|\d+\.) ")


def inline_html(text: str) -> str:
    """One paragraph's text with its inline markup as HTML (everything else escaped)."""
    out, at = [], 0
    for match in INLINE.finditer(text):
        out.append(html.escape(text[at:match.start()]))
        at = match.end()
        if match["role"] == "math":
            out.append(f'<span class="math">{tex_to_html(match["target"])}</span>')
        elif match["role"]:
            target = match["target"]
            name = target.lstrip("~.").rsplit(".", 1)[-1] if target.startswith("~") else target.lstrip(".")
            out.append(f"<code>{html.escape(name)}</code>")
        elif match["code"] is not None:
            out.append(f"<code>{html.escape(match['code'])}</code>")
        elif match["strong"] is not None:
            out.append(f"<strong>{inline_html(match['strong'])}</strong>")
        else:
            out.append(f"<em>{inline_html(match['em'])}</em>")
    out.append(html.escape(text[at:]))
    return "".join(out)


def summary(docstring: str) -> str:
    """The docstring's first line, without its final full stop."""
    return inspect.cleandoc(docstring).splitlines()[0].rstrip(".")


def docstring_html(docstring: str, *, skip_summary: bool = True) -> str:
    """The body of ``docstring`` as HTML (without its summary line unless ``skip_summary`` is False)."""
    lines = inspect.cleandoc(docstring).splitlines()
    if skip_summary:
        lines = lines[1:]
    return "\n".join(_blocks(lines))


def _indented_block(lines: list[str], at: int) -> tuple[list[str], int]:
    """The lines indented under ``lines[at - 1]`` (blank lines inside kept), dedented; and where it ends."""
    block = []
    while at < len(lines) and (not lines[at].strip() or lines[at].startswith(" ")):
        block.append(lines[at])
        at += 1
    while block and not block[-1].strip():
        block.pop()
    return inspect.cleandoc("\n".join(block)).splitlines() if block else [], at


def _math_block(lines: list[str]) -> str:
    """A ``.. math::`` body: one ``div.equation`` per formula, its source lines as lines."""
    formulas, current = [], []
    for line in [*lines, ""]:
        if line.strip():
            current.append(line.strip())
        elif current:
            formulas.append("<br>".join(tex_to_html(part) for part in current))
            current = []
    return "\n".join(f'<div class="equation">{formula}</div>' for formula in formulas)


def _blocks(lines: list[str]) -> list[str]:
    out: list[str] = []
    at = 0
    while at < len(lines):
        line = lines[at]
        if not line.strip():
            at += 1
        elif line.strip() == ".. math::":
            body, at = _indented_block(lines, at + 1)
            out.append(_math_block(body))
        elif BULLET.match(line):
            items, ordered = [], line[0].isdigit()
            while at < len(lines) and BULLET.match(lines[at]):
                item = [BULLET.sub("", lines[at])]
                at += 1
                while at < len(lines) and lines[at].startswith("  ") and lines[at].strip():
                    item.append(lines[at].strip())
                    at += 1
                items.append(f"<li>{inline_html(' '.join(item))}</li>")
                while at < len(lines) and not lines[at].strip() and at + 1 < len(lines) \
                        and BULLET.match(lines[at + 1]):
                    at += 1
            tag = "ol" if ordered else "ul"
            out.append(f"<{tag}>\n" + "\n".join(items) + f"\n</{tag}>")
        else:
            paragraph = []
            while at < len(lines) and lines[at].strip() and lines[at].strip() != ".. math::" \
                    and not (paragraph and BULLET.match(lines[at])):
                paragraph.append(lines[at].strip())
                at += 1
            text = " ".join(paragraph)
            literal = text.endswith("::")
            if literal:
                text = text[:-1]
            out.append(f"<p>{inline_html(text)}</p>")
            if literal:
                body, at = _indented_block(lines, at + 1 if at < len(lines) and not lines[at].strip() else at)
                out.append(f"<pre>{html.escape(chr(10).join(body))}</pre>")
    return out
