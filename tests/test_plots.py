"""Figures: legends outside the data, panels in order, log axes fitted to the data (no scenario runs)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest

from double_pendulum.plots import chaos, decay, style, suspension, trajectories


@pytest.fixture
def captured(monkeypatch):
    """Keep figures open: ``save`` records the figure instead of closing it."""
    figures = []
    monkeypatch.setattr(decay, "save", lambda fig, path: figures.append(fig) or path)
    monkeypatch.setattr(suspension, "save", lambda fig, path: figures.append(fig) or path)
    monkeypatch.setattr(trajectories, "save", lambda fig, path: figures.append(fig) or path)
    monkeypatch.setattr(chaos, "save", lambda fig, path: figures.append(fig) or path)
    yield figures
    plt.close("all")


def _panel(m_s: float) -> dict:
    k, c = np.geomspace(5e3, 2e5, 5), np.geomspace(1.0, 3e3, 5)
    b = -0.01 - 0.1 * np.outer(1.0 / (1.0 + k / 1e4), np.ones(c.size)) / m_s
    return {"k": k, "c": c, "b": b, "m_s": m_s}


def test_decay_rate_map_orders_panels_by_mass_with_one_colour_bar_and_the_legend_outside(captured):
    panels = {f"M_s = {m:g} kg": _panel(m) for m in (2.0, 0.5, 8.0)}
    suspension.plot_decay_rate_map(panels, {"measured": -0.03}, "unused.png", points={"identified": (2e4, 40.0)},
                              slope_through=(2e4, 40.0))
    fig = captured[0]
    data_axes = [ax for ax in fig.axes if ax.get_title().startswith("M_s")]
    assert [ax.get_title().split(" (")[0] for ax in data_axes] == ["M_s = 0.5 kg", "M_s = 2 kg", "M_s = 8 kg"]
    assert len(fig.axes) == 4  # three panels and one shared colour bar
    assert "[1/s]" in fig.axes[-1].get_ylabel() and "decay rate" in fig.axes[-1].get_ylabel()
    assert all(ax.get_legend() is None for ax in data_axes) and len(fig.legends) == 1
    assert "assumed" in data_axes[1].get_title()  # the points belong to the first panel given (2 kg)


def test_smooth_log_field_keeps_the_grid_values_and_stays_within_their_range():
    p = _panel(2.0)
    k, c, b = suspension.smooth_log_field(p["k"], p["c"], p["b"], n=41)
    assert k[0] == pytest.approx(p["k"][0]) and c[-1] == pytest.approx(p["c"][-1]) and b.shape == (41, 41)
    assert b.min() >= p["b"].min() - 1e-12 and b.max() <= p["b"].max() + 1e-12
    assert b[0, 0] == pytest.approx(p["b"][0, 0]) and b[-1, -1] == pytest.approx(p["b"][-1, -1])


def test_circle_fit_lists_flagged_frames_only_when_there_are_some(captured):
    t = np.linspace(0.0, 1.0, 20)
    x1, y1 = 0.3 * np.sin(t), -0.3 * np.cos(t)
    x2, y2 = x1 + 0.2 * np.sin(2 * t), y1 - 0.2 * np.cos(2 * t)
    decay.plot_circle_fit(x1, y1, x2, y2, t, 0.3, 0.2, "unused.png")
    flagged = np.zeros(t.size, dtype=bool)
    flagged[3] = True
    decay.plot_circle_fit(x1, y1, x2, y2, t, 0.3, 0.2, "unused.png", valid=~flagged)
    labels = [[text.get_text() for text in fig.legends[0].get_texts()] for fig in captured]
    assert not any("flagged" in s for s in labels[0]) and "flagged frames (1)" in labels[1]
    assert "fitted pivot" in labels[0]


def test_residual_plot_marks_exact_zeros_instead_of_stretching_the_log_axis(captured):
    t = np.linspace(0.0, 1.0, 11)
    residual = np.where(t == 0.0, 0.0, 1e-10 * (1.0 + t))
    run = {"time": t, "energy_residual": residual, "E_total": np.ones_like(t)}
    trajectories.plot_residuals({"case": run}, "unused.png")
    ax = captured[0].axes[0]
    low, high = ax.get_ylim()
    assert 1e-11 < low < 1e-10 and high < 1e-9
    assert any("exactly 0" in text.get_text() for text in ax.get_legend().get_texts())


def test_legend_outside_sits_right_of_the_axes():
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1], label="line")
    legend = style.legend_outside(ax)
    fig.canvas.draw()
    assert legend.get_window_extent().x0 > ax.get_window_extent().x1
    plt.close(fig)


def test_draft_figures_are_smaller_and_drop_the_minor_ticks_of_log_axes(tmp_path):
    """Quick runs save drafts: half the resolution, laid out once, without minor ticks (most of a log
    axis's cost); other figures keep theirs."""
    import matplotlib.image
    from matplotlib.ticker import NullLocator

    def figure() -> plt.Figure:
        fig, ax = plt.subplots(figsize=(4.0, 3.0))
        ax.loglog([1.0, 10.0, 100.0], [1e-3, 1.0, 1e3])
        ax.set(xlabel="x [1]", ylabel="y [1]", title="a log-log line")
        return fig

    full, draft = figure(), figure()
    style.save(full, tmp_path / "full.png")
    with style.draft_figures():
        style.save(draft, tmp_path / "draft.png")
    assert not isinstance(full.axes[0].xaxis.get_minor_locator(), NullLocator)
    assert isinstance(draft.axes[0].xaxis.get_minor_locator(), NullLocator)
    assert isinstance(draft.axes[0].yaxis.get_minor_locator(), NullLocator)
    h_full, w_full = matplotlib.image.imread(tmp_path / "full.png").shape[:2]
    h_draft, w_draft = matplotlib.image.imread(tmp_path / "draft.png").shape[:2]
    assert w_draft == pytest.approx(w_full * style.DRAFT_DPI / style.FIGURE_DPI, rel=0.15)
    assert h_draft == pytest.approx(h_full * style.DRAFT_DPI / style.FIGURE_DPI, rel=0.15)


def test_figures_ask_for_no_font_the_machine_lacks(tmp_path, monkeypatch, caplog):
    """Math text (log-axis tick labels) on a machine whose Matplotlib lacks the STIX fonts, even with a matplotlibrc
    asking for them: no findfont warning."""
    import logging

    import matplotlib
    import matplotlib.pyplot as plt
    from matplotlib import font_manager

    manager = font_manager.fontManager
    monkeypatch.setattr(manager, "ttflist", [font for font in manager.ttflist if not font.name.startswith("STIX")])
    font_manager.FontManager._findfont_cached.cache_clear()  # lookups made with the full list
    try:
        with matplotlib.rc_context({"mathtext.fontset": "stix", "mathtext.fallback": "stix"}):
            style.use_installed_fonts()  # as importing the plots does
            assert plt.rcParams["mathtext.fontset"] == "custom" and plt.rcParams["mathtext.fallback"] is None
            fig, ax = plt.subplots()
            ax.semilogy([1.0, 10.0, 100.0])  # tick labels 10^0 ... 10^2 are math text
            ax.set_title(r"$\alpha$ [1/s]")
            with caplog.at_level(logging.WARNING, logger="matplotlib.font_manager"):
                style.save(fig, tmp_path / "math.png")
    finally:
        font_manager.FontManager._findfont_cached.cache_clear()
    assert [r.getMessage() for r in caplog.records if "findfont" in r.getMessage()] == []
    assert (tmp_path / "math.png").stat().st_size > 1000


def test_a_decay_rate_map_within_one_decade_of_k_still_numbers_its_k_axis(captured):
    k, c = np.array([2e4, 8e4]), np.array([5.0, 200.0])  # the quick run's map: no power of ten inside
    panel = {"k": k, "c": c, "b": -0.02 - 1e-3 * np.outer(np.ones(2), np.log(c)), "m_s": 2.0}
    suspension.plot_decay_rate_map({"M_s = 2 kg": panel}, {"measured": -0.023}, "unused.png")
    ax = next(ax for ax in captured[0].axes if ax.get_title().startswith("M_s"))
    captured[0].canvas.draw()
    labels = [tick.get_text() for tick in ax.get_xticklabels() if k[0] <= tick.get_position()[0] <= k[-1]]
    assert "20000" in labels and "50000" in labels


def test_the_lyapunov_convergence_puts_its_long_labels_below_the_axes(captured):
    t = np.linspace(0.5, 100.0, 50)
    label = "integration {}, mean of 32 starts within 5 mm of the default start"
    curves = {label.format(i): (t, 1.0 + i / t) for i in range(3)}
    chaos.plot_lyapunov_convergence(curves, "unused.png", title="default start")
    fig = captured[0]
    assert fig.axes[0].get_legend() is None and len(fig.legends) == 1  # not beside the axes, taking their room
    fig.canvas.draw()
    legend, axes = fig.legends[0].get_window_extent(), fig.axes[0].get_window_extent()
    assert legend.y1 <= axes.y0  # below the axes, over no data


def test_angles_say_they_are_unwrapped(captured):
    t = np.linspace(0.0, 1.0, 11)
    run = np.zeros(11, dtype=[("time", float), ("phi1", float), ("phi2", float)])
    run["time"], run["phi2"] = t, 20.0 * t  # a lower rod turning over
    trajectories.plot_angles({"chaotic": run}, "unused.png")
    ax = captured[0].axes[0]
    assert "unwrapped" in ax.get_title() and "unwrapped" in ax.get_ylabel() and "[rad]" in ax.get_ylabel()


def test_quick_figures_are_drawn_at_a_readable_resolution():
    assert style.DRAFT_DPI >= 100  # at 60 dpi their text was a few pixels high
