"""Shared figure handling: the headless Agg backend, saving PNG files, legends outside the data, small helpers."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.artist import Artist  # noqa: E402
from matplotlib.legend import Legend  # noqa: E402

FIGURE_DPI = 120
"""Resolution [dots per inch] of the saved figures."""
DRAFT_DPI = 100
"""Resolution [dots per inch] of draft figures (quick runs). At 60 dpi their text was too small to read; a
figure's cost hardly depends on it (the layout and the drawing of its artists dominate), what the draft saves
is the layout (:func:`save`)."""
_DRAFT: ContextVar[bool] = ContextVar("draft_figures", default=False)
"""Whether :func:`save` writes draft figures now (:func:`draft_figures`; this package's own setting:
matplotlib's rcParams stay the user's, but for math fonts the machine lacks: :func:`use_installed_fonts`)."""
DRAFT_PAD_INCHES = 0.1
"""Margin [in] around a draft figure's content (matplotlib's default ``savefig.pad_inches``)."""
DRAFT_SPACING: dict[str, float] = {"hspace": 0.5, "wspace": 0.35}
"""Space between the subplots of a draft figure (fractions of the mean axes height and width), instead of
``tight_layout``'s measured spacing: room for a title above and tick labels and an axis label below."""


def _installed(family: str) -> bool:
    """Whether Matplotlib's font list has ``family``."""
    from matplotlib import font_manager

    return any(font.name == family for font in font_manager.fontManager.ttflist)


def font_settings() -> dict[str, str]:
    """Settings that keep the figures' math text (log-axis tick labels among it) to fonts the machine has.

    Every math font set built into Matplotlib loads the STIX fonts as its fallback when it parses math text; a
    Matplotlib without them (a distribution's package that leaves out the fonts Matplotlib ships) then prints
    "findfont: Font family ['STIXGeneral'] not found" for each lookup. Without STIX: the ``custom`` set (its
    letters from ``mathtext.rm`` and the like: DejaVu Sans by default, calligraphic ones from it too rather than
    a cursive font few machines have) and no fallback; with it, nothing to change."""
    if _installed("STIXGeneral"):
        return {}
    return {"mathtext.fontset": "custom", "mathtext.fallback": "None", "mathtext.cal": "sans:italic"}


def use_installed_fonts() -> None:
    """Apply :func:`font_settings` (nothing, where the user's fonts are there); done when the plots are imported.
    A text keeps the math font set of the time it was made, so this cannot wait for :func:`save`."""
    plt.rcParams.update(font_settings())


use_installed_fonts()


@contextmanager
def draft_figures(draft: bool = True) -> Iterator[None]:
    """Within the block, :func:`save` writes draft figures (if ``draft``), as quick runs do: at :data:`DRAFT_DPI`,
    and laid out once (see :func:`save`)."""
    token = _DRAFT.set(draft)
    try:
        yield
    finally:
        _DRAFT.reset(token)


def save(fig: plt.Figure, path: str | Path) -> Path:
    """Write ``fig`` as a PNG (:data:`FIGURE_DPI`, :data:`DRAFT_DPI` in :func:`draft_figures`) cropped to
    its content, legends outside the axes included; close it.

    A figure is laid out by ``tight_layout`` (unless it has a layout engine of its own) and cropped by
    ``bbox_inches="tight"``, which draws it once more without rendering to find its extent. A draft figure
    without a layout engine skips both: its extent is measured once (``get_tightbbox``, no drawing) and it is
    drawn once, about half the CPU time of a figure (the subplots spaced by :data:`DRAFT_SPACING`)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    draft, own_layout = _DRAFT.get(), fig.get_layout_engine() is not None
    if draft:
        for ax in fig.axes:  # a log axis draws a tick, a label and a grid line per minor tick: most of its cost
            ax.minorticks_off()
    if draft and not own_layout:
        fig.subplots_adjust(**DRAFT_SPACING)
        bbox = fig.get_tightbbox(fig.canvas.get_renderer()).padded(DRAFT_PAD_INCHES)
        fig.savefig(path, dpi=DRAFT_DPI, bbox_inches=bbox)
    else:
        if not own_layout:
            fig.tight_layout()
        fig.savefig(path, dpi=DRAFT_DPI if draft else FIGURE_DPI, bbox_inches="tight")
    plt.close(fig)
    return path


def legend_outside(ax: plt.Axes, *, fontsize: float = 8, **kwargs) -> Legend | None:
    """Legend of ``ax`` to the right of its axes, so it never covers data; None if nothing is labelled."""
    handles, labels = ax.get_legend_handles_labels()
    if not handles:
        return None
    return ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0,
                     fontsize=fontsize, **kwargs)


def legend_below(
    fig: plt.Figure, handles: Sequence[Artist], labels: Sequence[str], *, ncols: int = 3, fontsize: float = 9,
    **kwargs,
) -> Legend | None:
    """One legend for the whole figure, centred under its axes (``save`` crops to include it)."""
    if not handles:
        return None
    return fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncols=ncols,
                      fontsize=fontsize, frameon=False, **kwargs)


def running_mean(values: np.ndarray, width: int) -> np.ndarray:
    """Centered moving average over ``width`` samples (shorter at the ends)."""
    width = max(1, int(width))
    kernel = np.ones(width)
    return np.convolve(values, kernel, mode="same") / np.convolve(np.ones_like(values), kernel, mode="same")


def plain_log_numbers(ax: plt.Axes, axis: str = "y") -> None:
    """Number a log axis of ``ax`` (``"x"`` or ``"y"``) in plain decimals (0.3, 0.5, 2), enough of them to read it.

    Matplotlib numbers a log axis at its decades and, within less than a decade, only some minor ticks, as
    "6x10^-1", leaving parts of the axis without a number. Call after the limits are set: within a decade every
    digit 1 to 9 gets a number and the limits widen to the numbered values just outside them (so both ends are
    numbered), within about two decades 1, 2 and 5 do, beyond that the decades alone."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter  # noqa: PLC0415

    target = ax.yaxis if axis == "y" else ax.xaxis
    lo, hi = sorted(ax.get_ylim() if axis == "y" else ax.get_xlim())
    decades = np.log10(hi / lo) if lo > 0 else np.inf
    if decades <= 1.2:
        lo, hi = _digit_below(lo), _digit_above(hi)
        (ax.set_ylim if axis == "y" else ax.set_xlim)(lo, hi)
    subs = (1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0) if decades <= 1.2 else (1.0, 2.0, 5.0) if decades <= 2.5 \
        else (1.0,)
    target.set_major_locator(LogLocator(base=10.0, subs=subs))
    target.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    target.set_minor_formatter(NullFormatter())


def _digit_below(value: float) -> float:
    """The largest d x 10^n (d = 1 .. 9) at most ``value`` (> 0)."""
    scale = 10.0 ** np.floor(np.log10(value))
    return float(np.floor(value / scale * (1 + 1e-12)) * scale)


def _digit_above(value: float) -> float:
    """The smallest d x 10^n (d = 1 .. 10) at least ``value`` (> 0)."""
    scale = 10.0 ** np.floor(np.log10(value))
    return float(np.ceil(value / scale * (1 - 1e-12)) * scale)
