"""A scrubbable animation of the pendulum for a web page: a canvas with play, pause, step, speed and a time slider.

The player draws the very rows of a run's CSV file (or of a result table): the bob positions ``x1``, ``y1``,
``x2``, ``y2`` [m] the FMU reported (with a suffix such as ``_measured``), the pivot where it moves or sits
elsewhere, and the lower bob's trail over the last :data:`TRAIL_S` seconds, as the GIF of
:mod:`double_pendulum.plots.animation` shows them; nothing is recomputed. A frame is the last row at or before
the slider's time, so playing at speed 1 keeps real time whatever the rows' spacing.

The HTML is self-contained (no network, no file besides the page: the data are embedded as JSON), so the run's
page (:mod:`.page`) still opens from ``file://``, and the app (:mod:`double_pendulum.app`) shows the same player
in a frame of its own. :data:`PLAYER_SCRIPT` defines the player once a page; :func:`player_html` places one
player, :func:`animation_html` one drawn from a scenario's CSV files as an :class:`Animation` declares them.
"""

from __future__ import annotations

import html
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

TRAIL_S = 1.0
"""How long [s] the lower bob's trail reaches back (as in the GIFs)."""
SPEEDS = (0.1, 0.25, 0.5, 1.0, 2.0)
"""The playing speeds offered (1: real time)."""
DIGITS = 5
"""Decimals kept of a position [m] in the embedded data (10 micrometres: below a pixel at any size)."""


@dataclass(frozen=True)
class Drawn:
    """One pendulum of an animation, as columns of a CSV file in the scenario's folder: ``csv``, its bob columns
    ``x1``... ``y2`` followed by ``suffix``; drawn as rods and bobs (``links``) or as the two markers alone;
    ``pivot``: the columns of the pivot's position [m] (None: at the origin); ``colour``: a Matplotlib colour."""

    label: str
    colour: str
    csv: str
    suffix: str = ""
    links: bool = True
    pivot: tuple[str, str] | None = None


@dataclass(frozen=True)
class Animation:
    """A player the run's page shows in place of the GIF ``gif`` (the GIF only where scripts cannot run), drawn from
    the CSV files of :class:`Drawn` over their column ``time`` [s] (at most ``until_s`` seconds of it; None: all),
    with ``title`` above it."""

    gif: str
    title: str
    drawn: Sequence[Drawn]
    time: str = "time"
    time_label: str = "t"
    until_s: float | None = None


def swing_data(label: str, colour: str, x1: Sequence[float], y1: Sequence[float], x2: Sequence[float],
               y2: Sequence[float], *, links: bool = True, pivot: tuple[Any, Any] = (0.0, 0.0)) -> dict[str, Any]:
    """One pendulum for :func:`player_data`: its bob positions [m] per row, its pivot (a position, or one per row)."""
    from matplotlib.colors import to_hex  # the Matplotlib colours of the GIFs, as a browser names them

    def column(values: Any) -> list[float] | float:
        if isinstance(values, (int, float)):
            return round(float(values), DIGITS)
        return [round(float(v), DIGITS) if math.isfinite(v) else None for v in values]

    return {"label": label, "colour": to_hex(colour), "links": bool(links),
            "x1": column(x1), "y1": column(y1), "x2": column(x2), "y2": column(y2),
            "px": column(pivot[0]), "py": column(pivot[1])}


def _finite(values: Any) -> list[float]:
    values = values if isinstance(values, list) else [values]
    return [v for v in values if v is not None]


def player_data(times: Sequence[float], swings: Sequence[Mapping[str, Any]], title: str, *, time_label: str = "t",
                trail_s: float = TRAIL_S) -> dict[str, Any]:
    """What a player draws: the rows' ``times`` [s], the ``swings`` (:func:`swing_data`), the ``title``, and square
    axis limits [m] holding every position and pivot with a margin."""
    xs = [v for s in swings for key in ("x1", "x2", "px") for v in _finite(s[key])]
    ys = [v for s in swings for key in ("y1", "y2", "py") for v in _finite(s[key])]
    cx, cy = (max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2
    half = 0.55 * max(max(xs) - min(xs), max(ys) - min(ys), 0.05)
    return {"t": [round(float(t), 6) for t in times], "swings": list(swings), "title": title,
            "timeLabel": time_label, "trail": trail_s, "limits": [cx - half, cx + half, cy - half, cy + half]}


def player_html(element_id: str, data: Mapping[str, Any]) -> str:
    """One player (the page must hold :data:`PLAYER_SCRIPT` before it): its canvas, controls and legend."""
    speeds = "".join(f'<option value="{s:g}"{" selected" if s == 1.0 else ""}>{s:g}\u00d7</option>' for s in SPEEDS)
    legend = "".join(  # a space after each key: the line may break there (a key itself does not break)
        f'<span class="dp-key"><span class="dp-swatch" style="background:{html.escape(s["colour"])}"></span>'
        f'{html.escape(s["label"])}: {"rods and bobs" if s["links"] else "markers on both bobs"}</span> '
        for s in data["swings"])
    payload = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    return (f'<div class="dp-player" id="{html.escape(element_id)}" data-frame="0">'
            f'<canvas width="480" height="480" aria-label="{html.escape(data["title"])}"></canvas>'
            '<div class="dp-controls"><button type="button" class="dp-play">play</button>'
            '<button type="button" class="dp-pause">pause</button>'
            '<button type="button" class="dp-step">step</button>'
            f'<label>speed <select class="dp-speed">{speeds}</select></label>'
            '<input type="range" class="dp-time" min="0" value="0" step="1" aria-label="time">'
            '<span class="dp-clock"></span></div>'
            f'<div class="dp-legend">{legend}<span class="dp-key">the lower bob\'s trail: its last '
            f'{data["trail"]:g} s</span></div></div>'
            f"<script>dpPlayer({json.dumps(element_id)}, {payload});</script>")


PLAYER_STYLE = """
.dp-player { margin: 0.5rem 0 1rem; max-width: 480px; font-size: 0.9rem; }
.dp-player canvas { width: 100%; height: auto; border: 1px solid #eee; display: block; }
.dp-controls { display: flex; flex-wrap: wrap; gap: 0.4rem; align-items: center; margin-top: 0.3rem; }
.dp-controls .dp-time { flex: 1 1 12rem; } .dp-clock { font-variant-numeric: tabular-nums; min-width: 7.5rem; }
.dp-legend { color: #555; } .dp-key { margin-right: 1rem; white-space: nowrap; }
.dp-swatch { display: inline-block; width: 0.8rem; height: 0.8rem; margin-right: 0.3rem; vertical-align: -0.1rem; }
"""

PLAYER_SCRIPT = """<script>
function dpPlayer(id, d) {
  const root = document.getElementById(id), canvas = root.querySelector("canvas"), ctx = canvas.getContext("2d");
  const slider = root.querySelector(".dp-time"), clock = root.querySelector(".dp-clock");
  const speed = root.querySelector(".dp-speed"), t = d.t, n = t.length, W = canvas.width, H = canvas.height;
  const m = {l: 62, r: 14, t: 44, b: 50}, [x0, x1, y0, y1] = d.limits;
  const sx = (W - m.l - m.r) / (x1 - x0), sy = (H - m.t - m.b) / (y1 - y0);
  const X = x => m.l + (x - x0) * sx, Y = y => H - m.b - (y - y0) * sy;
  const at = (v, i) => Array.isArray(v) ? v[i] : v;
  let frame = 0, playing = null, last = 0, now = t[0];
  slider.max = n - 1;
  function ticks(lo, hi) {
    const step = Math.pow(10, Math.floor(Math.log10((hi - lo) / 4))), k = (hi - lo) / step > 8 ? 2 * step : step;
    const out = []; for (let v = Math.ceil(lo / k) * k; v <= hi; v += k) out.push(Math.round(v / k) * k); return out;
  }
  function axes() {
    ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, W, H); ctx.strokeStyle = "#ddd"; ctx.lineWidth = 1;
    ctx.fillStyle = "#333"; ctx.font = "11px sans-serif"; ctx.textAlign = "center";
    for (const v of ticks(x0, x1)) { ctx.beginPath(); ctx.moveTo(X(v), m.t); ctx.lineTo(X(v), H - m.b); ctx.stroke();
      ctx.fillText(v.toFixed(2), X(v), H - m.b + 14); }
    ctx.textAlign = "right";
    for (const v of ticks(y0, y1)) { ctx.beginPath(); ctx.moveTo(m.l, Y(v)); ctx.lineTo(W - m.r, Y(v)); ctx.stroke();
      ctx.fillText(v.toFixed(2), m.l - 5, Y(v) + 4); }
    ctx.strokeStyle = "#888"; ctx.strokeRect(m.l, m.t, W - m.l - m.r, H - m.t - m.b);
    ctx.textAlign = "center"; ctx.fillText("horizontal position x [m]", m.l + (W - m.l - m.r) / 2, H - 14);
    ctx.save(); ctx.translate(14, m.t + (H - m.t - m.b) / 2); ctx.rotate(-Math.PI / 2);
    ctx.fillText("vertical position y [m] (up)", 0, 0); ctx.restore();
  }
  function draw(i) {
    frame = i; root.dataset.frame = i; slider.value = i; axes();
    ctx.save(); ctx.beginPath(); ctx.rect(m.l, m.t, W - m.l - m.r, H - m.t - m.b); ctx.clip();
    let lo = i; while (lo > 0 && t[lo - 1] >= t[i] - d.trail) lo--;
    for (const s of d.swings) {
      ctx.strokeStyle = s.colour; ctx.fillStyle = s.colour; ctx.globalAlpha = 0.55; ctx.lineWidth = 1.2;
      ctx.beginPath(); let pen = false;
      for (let k = lo; k <= i; k++) { const x = s.x2[k], y = s.y2[k];
        if (x === null || y === null) { pen = false; continue; }
        if (s.links) { pen ? ctx.lineTo(X(x), Y(y)) : ctx.moveTo(X(x), Y(y)); pen = true; }
        else ctx.fillRect(X(x) - 1.5, Y(y) - 1.5, 3, 3); }
      ctx.stroke(); ctx.globalAlpha = 1;
      const px = at(s.px, i), py = at(s.py, i), b = [[s.x1[i], s.y1[i]], [s.x2[i], s.y2[i]]];
      if (s.links) { ctx.lineWidth = 2.5; ctx.beginPath(); ctx.moveTo(X(px), Y(py));
        for (const [x, y] of b) ctx.lineTo(X(x), Y(y)); ctx.stroke(); }
      for (const [x, y] of b) { if (x === null || y === null) continue; ctx.beginPath();
        ctx.arc(X(x), Y(y), s.links ? 6 : 8, 0, 2 * Math.PI);
        if (s.links) ctx.fill(); else { ctx.lineWidth = 2; ctx.stroke(); } }
      ctx.strokeStyle = "#000"; ctx.lineWidth = 1.5; ctx.beginPath(); ctx.moveTo(X(px) - 6, Y(py));
      ctx.lineTo(X(px) + 6, Y(py)); ctx.moveTo(X(px), Y(py) - 6); ctx.lineTo(X(px), Y(py) + 6); ctx.stroke();
    }
    ctx.restore(); ctx.fillStyle = "#222"; ctx.font = "13px sans-serif"; ctx.textAlign = "center";
    ctx.fillText(d.title, W / 2, 18, W - 10);
    const shown = d.timeLabel + " = " + t[i].toFixed(2) + " s"; ctx.fillText(shown, W / 2, 36);
    clock.textContent = shown + " of " + t[n - 1].toFixed(2) + " s";
  }
  function frameAt(time) { let lo = 0, hi = n - 1;
    while (lo < hi) { const mid = (lo + hi + 1) >> 1; if (t[mid] <= time) lo = mid; else hi = mid - 1; } return lo; }
  function tick(stamp) {
    if (playing === null) return;
    now += (stamp - last) / 1000 * parseFloat(speed.value); last = stamp;
    if (now >= t[n - 1]) { now = t[n - 1]; draw(n - 1); playing = null; return; }
    const i = frameAt(now); if (i !== frame) draw(i); playing = requestAnimationFrame(tick);
  }
  function pause() { if (playing !== null) cancelAnimationFrame(playing); playing = null; }
  root.querySelector(".dp-play").onclick = () => { if (playing !== null) return;
    if (frame >= n - 1) { now = t[0]; draw(0); } else now = t[frame];
    last = performance.now(); playing = requestAnimationFrame(tick); };
  root.querySelector(".dp-pause").onclick = pause;
  root.querySelector(".dp-step").onclick = () => { pause(); draw(Math.min(frame + 1, n - 1)); now = t[frame]; };
  slider.oninput = () => { pause(); draw(parseInt(slider.value, 10)); now = t[frame]; };
  draw(0);
}
</script>"""
"""The player's JavaScript and nothing else: once a page, before its players."""


def standalone_html(data: Mapping[str, Any], element_id: str = "player") -> str:
    """A whole HTML document holding one player (the app shows it in a frame of its own)."""
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(data['title'])}</title><style>body {{ font-family: system-ui, sans-serif; "
            f"margin: 0.5rem; }} {PLAYER_STYLE}</style>{PLAYER_SCRIPT}</head><body>"
            f"{player_html(element_id, data)}</body></html>\n")


def animation_html(folder: Path, animation: Animation) -> str:
    """The player of ``animation`` drawn from the CSV files in the scenario's ``folder`` ("" when one is missing
    or cannot be read: the page then shows the GIF instead)."""
    from .results_io import read_results_csv  # here: the page imports this module, and NumPy is slow

    tables: dict[str, Any] = {}
    try:
        for drawn in animation.drawn:
            if drawn.csv not in tables:
                tables[drawn.csv] = read_results_csv(folder / drawn.csv)
    except (OSError, ValueError):
        return ""
    first = tables[animation.drawn[0].csv]
    times = first[animation.time]
    rows = len(times) if animation.until_s is None else int((times <= animation.until_s + 1e-9).sum())
    swings = []
    for d in animation.drawn:
        table = tables[d.csv][:rows]
        pivot = (0.0, 0.0) if d.pivot is None else (table[d.pivot[0]], table[d.pivot[1]])
        swings.append(swing_data(d.label, d.colour, *(table[f"{c}{d.suffix}"] for c in ("x1", "y1", "x2", "y2")),
                                 links=d.links, pivot=pivot))
    data = player_data(times[:rows], swings, animation.title, time_label=animation.time_label)
    return player_html(f"player-{folder.name}-{Path(animation.gif).stem}", data)
