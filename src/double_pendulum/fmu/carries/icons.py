"""The FMUs' icons, drawn at build: the model's picture and one small picture per kind of terminal.

``icon(model)`` is the FMU's icon (FMI 2: ``model.png``; FMI 3 and FMI 2.0.4: ``terminalsAndIcons/
icon.png``) as a square PNG with a transparent background, :data:`ICON_PIXELS` wide:

* ``DoublePendulum``: a support, two rods and two bobs;
* ``Suspension``: a block on a spring and a damper to the ground;
* ``PendulumOnSuspension``: the pendulum hanging from that block.

``terminal_icon(kind)`` is the picture of a terminal (``terminalsAndIcons/<kind>.png``,
:mod:`double_pendulum.fmu.carries.terminals`): ``mount`` (the pivot: a grey square with a hinge),
``torque`` (a curved arrow) and ``sensor`` (an output triangle). Drawn once per process.
"""

from __future__ import annotations

import functools
import io
import math
from typing import Any

ICON_PIXELS = 200
TERMINAL_PIXELS = 40
INK, STEEL, BOB = "#1f3b57", "#8a99a8", "#c0392b"
MODELS = ("DoublePendulum", "Suspension", "PendulumOnSuspension")
TERMINAL_KINDS = ("mount", "torque", "sensor")


def _canvas(pixels: int) -> tuple[Any, Any]:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(1.0, 1.0), dpi=pixels)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.set_xlim(-100, 100)
    ax.set_ylim(-100, 100)
    ax.set_aspect("equal")
    ax.axis("off")
    return fig, ax


def _png(fig: Any) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", transparent=True)
    return buffer.getvalue()


def _pendulum(ax: Any, top: tuple[float, float], scale: float = 1.0) -> None:
    """Two rods and two bobs hanging from ``top``, swung out."""
    from matplotlib.patches import Circle

    x0, y0 = top
    x1, y1 = x0 + 60 * scale * math.sin(0.5), y0 - 60 * scale * math.cos(0.5)
    x2, y2 = x1 + 50 * scale * math.sin(1.0), y1 - 50 * scale * math.cos(1.0)
    ax.plot([x0, x1, x2], [y0, y1, y2], color=INK, linewidth=5 * scale, solid_capstyle="round", zorder=2)
    for x, y in ((x1, y1), (x2, y2)):
        ax.add_patch(Circle((x, y), 14 * scale, color=BOB, zorder=3))
    ax.add_patch(Circle((x0, y0), 6 * scale, color=INK, zorder=4))


def _spring(ax: Any, x: float, bottom: float, top: float) -> None:
    """A zig-zag spring from ``bottom`` to ``top`` at ``x``."""
    turns = 6
    ys = [bottom + (top - bottom) * k / (2 * turns) for k in range(2 * turns + 1)]
    xs = [x + (8 if k % 2 else -8) if 0 < k < 2 * turns else x for k in range(2 * turns + 1)]
    ax.plot(xs, ys, color=INK, linewidth=2.5)


def _damper(ax: Any, x: float, bottom: float, top: float) -> None:
    middle = (bottom + top) / 2
    ax.plot([x, x], [bottom, middle - 4], color=INK, linewidth=2.5)
    ax.plot([x - 9, x - 9, x + 9, x + 9], [middle + 8, middle - 8, middle - 8, middle + 8], color=INK, linewidth=2.5)
    ax.plot([x - 6, x + 6], [middle, middle], color=INK, linewidth=2.5)
    ax.plot([x, x], [middle, top], color=INK, linewidth=2.5)


def _suspension(ax: Any, block_y: float, spread: float = 30.0) -> None:
    """A block at ``block_y`` (its bottom) on a spring and a damper ``2 spread`` apart to the hatched ground."""
    from matplotlib.patches import Rectangle

    ground, half = -90.0, spread + 30.0
    ax.plot([-half - 10, half + 10], [ground, ground], color=INK, linewidth=3)
    for x in range(int(-half - 6), int(half + 10), 14):
        ax.plot([x, x - 8], [ground, ground - 8], color=INK, linewidth=1.5)
    _spring(ax, -spread, ground, block_y)
    _damper(ax, spread, ground, block_y)
    ax.add_patch(Rectangle((-half, block_y), 2 * half, 28, color=STEEL, zorder=2))


@functools.cache
def icon(model: str) -> bytes:
    """The icon of ``model`` (one of :data:`MODELS`) as PNG bytes."""
    from matplotlib.patches import Rectangle

    fig, ax = _canvas(ICON_PIXELS)
    if model == "DoublePendulum":
        ax.add_patch(Rectangle((-60, 78), 120, 12, color=STEEL, zorder=1))
        _pendulum(ax, (0.0, 78.0))
    elif model == "Suspension":
        _suspension(ax, -10.0)
    elif model == "PendulumOnSuspension":
        _suspension(ax, 45.0, spread=62.0)
        _pendulum(ax, (0.0, 45.0), scale=0.62)
    else:
        raise ValueError(f"no icon for {model!r}; known: {', '.join(MODELS)}")
    return _png(fig)


@functools.cache
def terminal_icon(kind: str) -> bytes:
    """The picture of a terminal of ``kind`` (one of :data:`TERMINAL_KINDS`) as PNG bytes."""
    from matplotlib.patches import Circle, FancyArrowPatch, Polygon, Rectangle

    fig, ax = _canvas(TERMINAL_PIXELS)
    if kind == "mount":
        ax.add_patch(Rectangle((-90, -90), 180, 180, color=STEEL))
        ax.add_patch(Circle((0, 0), 35, color=INK))
    elif kind == "torque":
        ax.add_patch(Circle((0, 0), 90, color="white", ec=INK, lw=2))
        ax.add_patch(FancyArrowPatch((-55, -30), (55, -30), connectionstyle="arc3,rad=-0.9", arrowstyle="-|>",
                                     mutation_scale=10, color=BOB, lw=2.5))
    elif kind == "sensor":
        ax.add_patch(Polygon([(-80, -80), (-80, 80), (85, 0)], closed=True, color=INK))
    else:
        raise ValueError(f"no terminal icon {kind!r}; known: {', '.join(TERMINAL_KINDS)}")
    return _png(fig)
