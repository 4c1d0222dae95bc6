"""The TeX of the model's docstrings as plain HTML: letters, sub- and superscripts, accents, symbols.

The FMU's ``documentation/index.html`` shows the equations of the model's docstrings
(:mod:`double_pendulum.fmu.carries.docstring_html`). FMI tools show an FMU's documentation in whatever HTML
view they have (often no MathML, no JavaScript, no network), so the formulas become text: Latin
letters in italics, Greek letters and symbols as Unicode, ``_``/``^`` as ``<sub>``/``<sup>``, dots
as combining marks (U+0307, U+0308, U+0302), vectors in bold, ``\\tfrac12`` as ½.

Only the subset the docstrings use is known; anything else raises :class:`UnsupportedTeX` naming it,
so a new formula in a docstring fails the build (and its test) instead of showing raw TeX.
"""

from __future__ import annotations

import html
import re

GREEK = {
    "alpha": "α", "beta": "β", "gamma": "γ", "delta": "δ", "epsilon": "ε", "varepsilon": "ε", "zeta": "ζ",
    "eta": "η", "theta": "θ", "vartheta": "ϑ", "kappa": "κ", "lambda": "λ", "mu": "μ", "nu": "ν", "xi": "ξ",
    "pi": "π", "rho": "ρ", "sigma": "σ", "tau": "τ", "phi": "ϕ", "varphi": "φ", "chi": "χ", "psi": "ψ",
    "omega": "ω", "Gamma": "Γ", "Delta": "Δ", "Theta": "Θ", "Lambda": "Λ", "Pi": "Π", "Sigma": "Σ",
    "Phi": "Φ", "Psi": "Ψ", "Omega": "Ω",
}
SYMBOLS = {
    "cdot": "·", "times": "×", "ge": "≥", "geq": "≥", "le": "≤", "leq": "≤", "ne": "≠", "approx": "≈",
    "in": "∈", "int": "∫", "sum": "∑", "partial": "∂", "infty": "∞", "pm": "±", "langle": "⟨", "rangle": "⟩",
    "to": "→", "dots": "…", "ldots": "…", "nabla": "∇",
    ",": "\u2009", " ": " ", ";": "\u2005", "quad": "\u2003", "qquad": "\u2003\u2003", "_": "_", "{": "{",
    "}": "}", "\\": "<br>",
}
FUNCTIONS = {"sin", "cos", "tan", "tanh", "sinh", "cosh", "exp", "log", "ln", "max", "min", "det"}
ACCENTS = {"dot": "\u0307", "ddot": "\u0308", "hat": "\u0302", "bar": "\u0305", "tilde": "\u0303"}
FRACTIONS = {("1", "2"): "½", ("1", "3"): "⅓", ("1", "4"): "¼", ("3", "4"): "¾"}


class UnsupportedTeX(ValueError):
    """A formula uses TeX that :func:`tex_to_html` does not know; the message names it."""


def tex_to_html(tex: str) -> str:
    """``tex`` (math mode, the docstrings' subset) as HTML inline markup."""
    return re.sub(" {2,}", " ", _Parser(tex).sequence(top=True)).strip()


class _Parser:
    """Recursive descent over ``tex``: a sequence of atoms, each with optional ``_`` and ``^``."""

    def __init__(self, tex: str) -> None:
        self.tex, self.at = tex, 0

    def fail(self, what: str) -> UnsupportedTeX:
        return UnsupportedTeX(f"unsupported TeX {what} in formula {self.tex!r}")

    def peek(self) -> str:
        return self.tex[self.at] if self.at < len(self.tex) else ""

    def sequence(self, top: bool = False, upright: bool = False) -> str:
        parts = []
        while self.at < len(self.tex):
            if self.peek() == "}":
                if top:
                    raise self.fail("'}' without '{'")
                break
            atom = self.atom(upright)
            while self.peek() in ("_", "^"):
                mark = self.peek()
                self.at += 1
                script = self.argument(upright=True)
                atom += f"<sub>{script}</sub>" if mark == "_" else f"<sup>{script}</sup>"
            parts.append(atom)
        return "".join(parts)

    def argument(self, upright: bool = False) -> str:
        """One argument: a ``{group}`` or the next single atom (no scripts)."""
        self.skip_spaces()
        if self.peek() == "{":
            self.at += 1
            inner = self.sequence(upright=upright)
            if self.peek() != "}":
                raise self.fail("(missing '}')")
            self.at += 1
            return inner
        return self.atom(upright)

    def raw_argument(self) -> str:
        """The text of the next ``{group}`` or character, unparsed (``\\text``, fractions of digits)."""
        self.skip_spaces()
        if self.peek() == "{":
            end = self.tex.index("}", self.at)
            text, self.at = self.tex[self.at + 1:end], end + 1
            return text
        char = self.peek()
        self.at += 1
        return char

    def skip_spaces(self) -> None:
        while self.peek() == " ":
            self.at += 1

    def atom(self, upright: bool = False) -> str:
        char = self.peek()
        if char == "\\":
            return self.command(upright)
        if char == "{":
            return self.argument(upright)
        self.at += 1
        if char == " ":
            return ""
        if char.isalpha():
            if upright:  # a word in a subscript (W_{air}) stays upright
                word = char
                while self.peek().isalpha():
                    word += self.peek()
                    self.at += 1
                return word if len(word) > 1 else f"<i>{word}</i>"
            return f"<i>{char}</i>"
        if char == ",":
            return ",\u2009"
        if char in "=+<>":
            return f" {html.escape(char)} "
        if char == "-":
            return " − " if not upright else "−"
        return html.escape(char)

    def command(self, upright: bool) -> str:
        self.at += 1
        start = self.at
        if self.peek().isalpha():
            while self.peek().isalpha():
                self.at += 1
        else:
            self.at += 1
        name = self.tex[start:self.at]
        if name in GREEK:
            return GREEK[name]
        if name in SYMBOLS:
            symbol = SYMBOLS[name]
            return f" {symbol} " if name in ("ge", "geq", "le", "leq", "ne", "approx", "in", "to") else symbol
        if name in FUNCTIONS:
            return f"{name}\u2009"
        if name in ACCENTS:  # the mark inside the letter's own tags, so that it sits on the letter
            base, mark = self.argument(upright), ACCENTS[name]
            closing = re.search(r"(</\w+>)+$", base)
            return base[:closing.start()] + mark + closing.group() if closing else base + mark
        if name == "vec":  # a vector in bold (the arrow mark U+20D7 is missing from common serif fonts)
            return f"<b>{self.argument(upright).replace('<i>', '').replace('</i>', '')}</b>"
        if name in ("frac", "tfrac", "dfrac"):
            numerator, denominator = self.raw_argument(), self.raw_argument()
            if (numerator, denominator) in FRACTIONS:
                return FRACTIONS[(numerator, denominator)]
            return f"{tex_to_html(numerator)}/{tex_to_html(denominator)}"
        if name in ("text", "mathrm", "operatorname"):
            return html.escape(self.raw_argument())
        if name == "mathrel":  # \mathrel{+}= : an operator written as a relation
            operator = html.escape(self.raw_argument())
            if self.peek() == "=":
                self.at += 1
                operator += "="
            return f" {operator} "
        raise self.fail(f"\\{name}")
