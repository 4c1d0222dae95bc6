"""Animations of the pendulum as GIF files that play in real time, drawn from the CSV files a run wrote.

Every frame comes from rows of a CSV file a scenario (or ``double-pendulum simulate``) wrote: the animation never
simulates anything itself, so it shows the very numbers of the run. A GIF shows each frame for its own duration,
in GIF's 10 ms steps: the durations are the differences of the frames' times rounded to them, so the animation
keeps real time over its whole length (a fixed frame rate would drift by the rounding of every frame), at most
:data:`MAX_FRAME_RATE` frames a second (every k-th row of the CSV). The frames share one palette of at most
white, black and the runs' colours in :data:`BLENDS` shades each (:func:`palette_image`), which keeps a GIF of
20 s at some 1 to 2 MB.

A pendulum is drawn as a :class:`Swing`: its links from the pivot through both bobs (the simulation) or its two
markers alone (the camera's LEDs), with the lower bob's trail over the last :data:`TRAIL_S` seconds; the time of
the frame is in the title, where it covers nothing.
"""

from __future__ import annotations

import os
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.animation import AbstractMovieWriter

MAX_FRAME_RATE = 20.0
"""Most frames [1/s] an animation shows a second of motion (a browser draws a GIF's frames no faster than
every 20 ms; 20 a second look smooth at the pendulum's speeds)."""
GIF_DPI = 80
"""Resolution [dots per inch] of the animations: a 5 inch figure is 400 pixels wide."""
BLENDS = 12
"""Shades of each colour between white and it in a GIF's palette (:func:`palette_image`)."""
TRAIL_S = 1.0
"""How long [s] the lower bob's trail reaches back."""
HOLD_LAST_MS = 1000
"""How long [ms] the last frame stays before the GIF starts again."""
TITLE_PT = 12
"""Font size [pt] of the title and the clock: at :data:`GIF_DPI` about 13 pixels, readable where the page shows the
GIF at its own 400 pixels (9 pt, some 10 pixels, was not)."""
LEGEND_PT = 10
"""Font size [pt] of the legend and the axis labels."""


@dataclass(frozen=True)
class Swing:
    """One pendulum to draw, frame by frame: the positions [m] of its bobs and of its pivot (one position or one
    per frame), its colour, and whether it is drawn as links (pivot, upper bob, lower bob) or as markers only."""

    label: str
    x1: np.ndarray
    y1: np.ndarray
    x2: np.ndarray
    y2: np.ndarray
    colour: str
    links: bool = True
    pivot: tuple[float, float] = (0.0, 0.0)


def swing(table: np.ndarray, label: str, colour: str, *, suffix: str = "", links: bool = True,
          pivot: tuple[float, float] = (0.0, 0.0)) -> Swing:
    """The :class:`Swing` of a result table as read back from a CSV file: its columns ``x1``, ``y1``, ``x2``,
    ``y2`` (each followed by ``suffix``, as ``x1_measured``)."""
    columns = [np.asarray(table[f"{name}{suffix}"], dtype=float) for name in ("x1", "y1", "x2", "y2")]
    return Swing(label, *columns, colour=colour, links=links, pivot=pivot)


def frame_rows(times: np.ndarray, max_rate: float = MAX_FRAME_RATE) -> np.ndarray:
    """The rows of ``times`` [s] an animation draws: every k-th one, k the smallest that keeps the frames at most
    ``max_rate`` a second (every row if they are that far apart already)."""
    times = np.asarray(times, dtype=float)
    if len(times) < 2:
        return np.arange(len(times))
    step = float(np.median(np.diff(times)))
    every = max(1, int(np.ceil((1.0 / max_rate) / step - 1e-9)))
    return np.arange(0, len(times), every)


def real_time_durations_ms(times: Sequence[float], hold_last_ms: int = HOLD_LAST_MS) -> list[int]:
    """How long [ms] a GIF shows each frame of ``times`` [s] to play in real time: the differences of the times
    rounded to GIF's 10 ms from the first frame on (so the rounding does not add up), at least 20 ms (browsers
    draw shorter ones slower); the last frame ``hold_last_ms``."""
    t = np.asarray(times, dtype=float)
    ticks = np.round((t - t[0]) * 100.0).astype(int)  # GIF's 10 ms units since the first frame
    durations = [max(2, int(d)) * 10 for d in np.diff(ticks)]
    return [*durations, hold_last_ms]


def palette_image(inks: Sequence[str], steps: int = BLENDS) -> Any:
    """A Pillow palette image of white, black and each colour of ``inks`` blended with white in ``steps`` steps
    (the antialiased edges of lines and text on a white figure): every frame is mapped onto the same colours,
    so a run's colour stays its own in every frame."""
    from matplotlib.colors import to_rgb
    from PIL import Image

    colours = [(1.0, 1.0, 1.0)]
    for ink in ("black", *inks):
        rgb = np.array(to_rgb(ink))
        colours += [tuple(1.0 - (1.0 - rgb) * k / steps) for k in range(1, steps + 1)]
    values = [round(255 * c) for colour in colours[:256] for c in colour]
    palette = Image.new("P", (1, 1))
    palette.putpalette(values + values[-3:] * (256 - len(values) // 3))
    return palette


class RealTimeGifWriter(AbstractMovieWriter):
    """A Matplotlib movie writer: a GIF through Pillow whose frames last ``durations_ms`` each
    (:func:`real_time_durations_ms`), on one palette (:func:`palette_image` of the colours drawn).
    :meth:`grab_frame` takes the canvas as it is drawn now (:func:`animate_swings` draws only what moves, on a
    saved background: a frame then costs a few milliseconds instead of two full drawings of the figure)."""

    def __init__(self, durations_ms: Sequence[int], inks: Sequence[str]) -> None:
        mean_ms = float(np.mean(durations_ms[:-1])) if len(durations_ms) > 1 else 100.0
        super().__init__(fps=1000.0 / mean_ms)
        self.durations_ms = [int(d) for d in durations_ms]
        self._palette = palette_image(inks)
        self._frames: list = []

    def setup(self, fig, outfile, dpi=None) -> None:  # noqa: ANN001 - Matplotlib's signature
        super().setup(fig, outfile, dpi=dpi)
        self._frames = []

    def grab_frame(self, **savefig_kwargs) -> None:
        """Keep the canvas as drawn now as a palette image (one byte a pixel: 300 frames of 400 x 460 pixels take
        55 MB)."""
        from PIL import Image

        image = Image.fromarray(np.asarray(self.fig.canvas.buffer_rgba())).convert("RGB")
        self._frames.append(image.quantize(palette=self._palette, dither=Image.Dither.NONE))

    def finish(self) -> None:
        """Write the GIF (looping) with each frame's own duration."""
        if len(self._frames) != len(self.durations_ms):
            raise ValueError(f"{len(self._frames)} frames drawn for {len(self.durations_ms)} durations")
        first, *rest = self._frames
        first.save(self.outfile, format="GIF", save_all=True, append_images=rest, duration=self.durations_ms,
                   loop=0, optimize=False, disposal=1)
        self._frames = []


def _limits(swings: Sequence[Swing], rows: np.ndarray) -> tuple[float, float, float, float]:
    """Axis limits [m] that hold every drawn position and pivot with a margin, square."""
    xs = np.concatenate([np.r_[s.x1[rows], s.x2[rows], s.pivot[0]] for s in swings])
    ys = np.concatenate([np.r_[s.y1[rows], s.y2[rows], s.pivot[1]] for s in swings])
    xs, ys = xs[np.isfinite(xs)], ys[np.isfinite(ys)]
    cx, cy = (xs.max() + xs.min()) / 2, (ys.max() + ys.min()) / 2
    half = 0.55 * max(xs.max() - xs.min(), ys.max() - ys.min(), 0.05)
    return cx - half, cx + half, cy - half, cy + half


def _lay_out(fig: plt.Figure, margin_in: float = 0.05) -> None:
    """Lay ``fig`` out (its layout engine, by drawing it), made taller until nothing sticks out of it: the legend
    under an axes of equal aspect and a title of three lines need more height than a fixed size may leave."""
    for _ in range(4):
        fig.canvas.draw()
        box = fig.get_tightbbox(fig.canvas.get_renderer())
        width, height = fig.get_size_inches()
        over = max(0.0, box.y1 - height) + max(0.0, -box.y0)
        if over <= 0.0:
            return
        fig.set_size_inches(width, height + over + margin_in)


def animate_swings(
    times: np.ndarray,
    swings: Sequence[Swing],
    path: str | Path,
    *,
    title: str,
    time_label: str = "t",
    size_in: tuple[float, float] = (5.0, 5.6),
    trail_s: float = TRAIL_S,
) -> Path:
    """Write a real-time GIF of ``swings`` over ``times`` [s] (one row per time in each swing's arrays) to
    ``path``: the frames of :func:`frame_rows`, ``title`` above them with the frame's time (``time_label`` =
    ... s, real time), the lower bob's trail over the last ``trail_s`` s, one legend under the axes."""
    times = np.asarray(times, dtype=float)
    rows = frame_rows(times)
    durations = real_time_durations_ms(times[rows])
    fig, ax = plt.subplots(figsize=size_in, dpi=GIF_DPI, layout="constrained")
    x0, x1, y0, y1 = _limits(swings, rows)
    ax.set(xlim=(x0, x1), ylim=(y0, y1), aspect="equal", xlabel="horizontal position x [m]",
           ylabel="vertical position y [m] (up)")
    ax.grid(alpha=0.3)
    drawn = []
    for s in swings:
        trail, = ax.plot([], [], "-" if s.links else ".", color=s.colour, lw=1.0, ms=2.5, alpha=0.55,
                         label=f"{s.label}: lower bob, last {trail_s:g} s")
        if s.links:  # dots on the bobs only: the pivot keeps its own marker, drawn above the rods
            body, = ax.plot([], [], "-o", color=s.colour, lw=2.2, ms=7, mfc=s.colour, markevery=[1, 2],
                            label=f"{s.label}: rods and bobs")
        else:
            body, = ax.plot([], [], "o", color=s.colour, ms=9, mfc="none", mew=2.0,
                            label=f"{s.label}: markers on both bobs")
        drawn.append((s, trail, body))
    pivots = sorted({s.pivot for s in swings})
    pivot, = ax.plot([p[0] for p in pivots], [p[1] for p in pivots], "P", color="k", mfc="white", mew=1.4, ms=11,
                     zorder=5, label="pivot")  # a white cross edged in black: seen on the rods and on the grid
    handles = [*(t for _, t, _ in drawn), pivot, *(b for _, _, b in drawn)]  # rows: a swing's trail and body
    fig.legend(handles, [h.get_label() for h in handles], loc="outside lower center", ncols=2, fontsize=LEGEND_PT - 1,
               frameon=False)
    ax.xaxis.label.set_size(LEGEND_PT)
    ax.yaxis.label.set_size(LEGEND_PT)
    clock = f"{time_label} = {{:.2f}} s (real time)"
    width = int(size_in[0] * 72 / (0.6 * TITLE_PT))  # characters a line holds at the title's size
    title = "\n".join(textwrap.fill(line, width) for line in title.split("\n"))
    ax.set_title(f"{title}\n{clock.format(times[-1])}", fontsize=TITLE_PT)  # the last line: the time's room
    _lay_out(fig)  # once: the frames only redraw what moves
    fig.set_layout_engine("none")
    ax.set_title(f"{title}\n ", fontsize=TITLE_PT)  # the time goes on the (now blank) last line, frame by frame
    heading = ax.text(*ax.title.get_position(), "", transform=ax.title.get_transform(), ha="center", va="baseline",
                      fontsize=TITLE_PT)
    trail_rows = max(1, int(round(trail_s / max(float(np.median(np.diff(times))) if len(times) > 1 else 1.0, 1e-9))))

    def draw(k: int) -> list:
        i = rows[k]
        lo = max(0, i - trail_rows)
        for s, trail, body in drawn:
            trail.set_data(s.x2[lo:i + 1], s.y2[lo:i + 1])
            if s.links:
                body.set_data([s.pivot[0], s.x1[i], s.x2[i]], [s.pivot[1], s.y1[i], s.y2[i]])
            else:
                body.set_data([s.x1[i], s.x2[i]], [s.y1[i], s.y2[i]])
        heading.set_text(clock.format(times[i]))
        return [heading, *(a for _, t, b in drawn for a in (t, b)), pivot]  # the pivot last: above the rods

    moving = [heading, *(a for _, t, b in drawn for a in (t, b)), pivot]
    for artist in moving:
        artist.set_animated(True)  # left out of the background
    fig.canvas.draw()
    background = fig.canvas.copy_from_bbox(fig.bbox)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.partial")  # renamed into place once whole
    writer = RealTimeGifWriter(durations, [s.colour for s in swings])
    try:
        with writer.saving(fig, partial, dpi=fig.dpi):
            for k in range(len(rows)):
                fig.canvas.restore_region(background)
                for artist in draw(k):
                    fig.draw_artist(artist)
                writer.grab_frame()
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)
        plt.close(fig)
    return path
