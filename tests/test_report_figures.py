"""The report's figures as a reader sees them (issue 22): what each figure draws, where its
legend sits, that its axes are labelled with units, and that the predicted-vs-measured figure
is a page of report.pdf; and simulate's manoeuvre.png.

The figures are checked through their artists (bands, lines, legend boxes in display
coordinates, axis labels and limits), so that each test fails when the drawing regresses.
"""

from __future__ import annotations

import copy
import math
from itertools import combinations

import numpy as np
import pandas as pd
import pytest
from conftest import draw_only_pages
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from pypdf import PdfReader

from towtank.report import figure_base, figures, pdf
from towtank.report.manoeuvre_figure import manoeuvre_figure, wrapped_heading
from towtank.report.tare_figure import fig_tare, tare_caption
from towtank.report.vehicle import fig_predicted
from towtank.stats.quantiles import normal_quantile, t95


# ----------------------------------------------------------------------------- helpers
def _bands(ax) -> list[PolyCollection]:
    return [c for c in ax.collections if isinstance(c, PolyCollection)]


def _legend_texts(ax) -> list[str]:
    leg = ax.get_legend()
    return [t.get_text() for t in leg.get_texts()] if leg is not None else []


def _with_prediction(day):
    """A copy of ``day`` whose coefficients carry a prediction, as a [vehicle] day's do."""
    moved = copy.deepcopy(day)
    coef = moved.hull.coefficients
    coef["predicted"] = coef["prime"].to_numpy(float) * np.linspace(0.8, 1.3, len(coef))
    coef.loc[coef["symbol"] == "X_uv", "predicted"] = np.nan  # no prediction: not drawn
    coef["predicted_diff_pct"] = (coef["prime"] - coef["predicted"]) / coef["predicted"].abs() \
        * 100
    return moved


# ------------------------------------------------------------------------------ the tare
def test_tare_caption_gives_both_channels_coefficients_and_the_legend_the_band(hull_day):
    day = hull_day.result
    model = next(iter(day.tares.values()))
    assert model.lift is not None  # the synthetic sting measures lift too
    text = tare_caption(day.tare)
    for channel in ("drag", "lift"):
        fit = getattr(model, channel)
        assert f"{channel.capitalize()}, group" in text
        for name, value in zip(("t2", "t1", "m_t"), fit.coef, strict=True):
            assert f"{name} = {float(value):.4g}" in text, (channel, name)
    fig = fig_tare(day.tare, day.runs)
    axes = [ax for ax in fig.axes if ax.get_title() in ("Drag", "Lift")]
    assert len(axes) == 2
    for ax in axes:
        fit = model.drag if ax.get_title() == "Drag" else model.lift
        (band,) = _bands(ax)
        assert any("95 % confidence band" in t for t in _legend_texts(ax))
        # the band is the fit's own: ± t95(dof)·s.e. of the curve at a = 0
        xs, ys = band.get_paths()[0].vertices.T
        centre = fit(xs, np.zeros_like(xs))
        half = t95(fit.dof) * fit.std_error(xs, np.zeros_like(xs))
        assert half.max() > 0
        np.testing.assert_allclose(np.abs(ys - centre), half, rtol=1e-6, atol=1e-12)


# ---------------------------------------------------------------------------- legends
def test_data_under_legend_sees_a_legend_on_a_curve():
    fig = Figure()
    ax = fig.add_subplot()
    x = np.linspace(0, 1, 50)
    ax.plot(x, 0.5 + 0 * x, label="a line through the middle")
    ax.plot([0.1, 0.9], [0.9, 0.9], "o", label="two points")
    ax.legend(loc="center")
    assert figure_base.data_under_legend(ax) >= 1  # the check can fail
    leg = figure_base.place_legend(ax)
    assert figure_base.data_under_legend(ax, leg) == 0


@pytest.mark.parametrize("name", ["tare", "added_mass", "damping", "scaling"])
def test_no_legend_covers_data(hull_day, name):
    # each figure bound to the day's results as the report draws it
    (func,) = [f for n, _, f in figures.available_figures(hull_day.result) if n == name]
    fig = func(page=True)
    legends = 0
    renderer = figure_base._renderer(fig)
    for ax in fig.axes:
        if ax.get_legend() is None:
            continue
        legends += 1
        covered = figure_base.data_under_legend(ax, renderer=renderer)
        assert covered == 0, (name, ax.get_title(), covered)
        # ... and it stays inside its axes
        box = ax.get_legend().get_window_extent(renderer)
        frame = ax.get_window_extent(renderer)
        assert frame.x0 - 1 <= box.x0 and box.x1 <= frame.x1 + 1
        assert frame.y0 - 1 <= box.y0 and box.y1 <= frame.y1 + 1
    assert legends >= 1


def test_scaling_legend_names_the_recommended_resistance(hull_day):
    # the sample hull day ran at 5 D: ITTC-57 is the prototype resistance, the Froude-scaled
    # total resistance a comparison (scaling.csv's `recommended`)
    day = hull_day.result
    assert set(day.scaling.table["recommended"]) == {"drag_ittc57"}
    fig = figures.fig_scaling(day.scaling, day.runs, day.protocol, page=True)
    texts = _legend_texts(fig.axes[1])
    assert any("ITTC-57" in t and "(recommended)" in t for t in texts), texts
    assert any("Froude" in t and "comparison only" in t for t in texts), texts
    assert not any("Froude" in t and "(recommended)" in t for t in texts), texts


# ------------------------------------------------------------ the result drawn, not the day
def _drawn(fig: Figure) -> list[str]:
    """Every axes' title and line data of a figure (repr: NaN compares equal)."""
    return [repr((ax.get_title(), [ln.get_xydata().tolist() for ln in ax.get_lines()]))
            for ax in fig.axes]


def test_the_hull_figures_draw_the_hull_result_and_still_take_a_day(hull_day):
    day = hull_day.result
    alpha_max = day.protocol.processing.damping_alpha_max_deg
    damping = figures.fig_damping(day.hull, alpha_max)
    assert _drawn(damping) == _drawn(figures.fig_damping(day))  # the older call: the same
    caption = " ".join(" ".join(t.get_text() for t in damping.texts).split())
    assert f"|α| ≤ {alpha_max:g}°" in caption
    added = figures.fig_added_mass(day.hull, day.reductions)
    assert _drawn(added) == _drawn(figures.fig_added_mass(day))
    # the samples drawn are those of the reductions given: one run fewer, fewer points
    am = next(iter(day.hull.fit.added_mass.values()))
    fewer = {r: red for r, red in day.reductions.items() if r != am.runs[0]}
    points = sum(len(ln.get_xdata()) for ln in added.axes[0].get_lines())
    assert sum(len(ln.get_xdata()) for ln in
               figures.fig_added_mass(day.hull, fewer).axes[0].get_lines()) < points
    with pytest.raises(TypeError, match="reductions"):
        figures.fig_added_mass(day.hull)
    assert figures.fig_added_mass(None, {}) is None and figures.fig_damping(None) is None


# ---------------------------------------------------------------------- transverse band
def test_transverse_panel_draws_the_fits_own_95_percent_interval(hull_day):
    day = hull_day.result
    dm = day.hull.fit.damping
    est = day.hull.fit.estimates["Y_v|v|"]
    fig = figures.fig_damping(day.hull, day.protocol.processing.damping_alpha_max_deg)
    (ax,) = [a for a in fig.axes if a.get_title().startswith("Transverse")]
    (band,) = _bands(ax)
    y = band.get_paths()[0].vertices[:, 1]
    half = 0.5 * (y.max() - y.min())
    assert 0.5 * (y.max() + y.min()) == pytest.approx(dm.cd90)
    # Student's t at the estimate's own degrees of freedom, the same relative width as Y_v|v|'s
    assert math.isfinite(est.dof)
    assert half == pytest.approx(t95(est.dof) * dm.cd90_se, rel=1e-9)
    assert half / dm.cd90 == pytest.approx((est.ci_high - est.value) / abs(est.value), rel=1e-6)
    assert half != pytest.approx(normal_quantile() * dm.cd90_se, rel=1e-3)
    assert any("95 % interval" in t for t in _legend_texts(ax))
    lo, hi = ax.get_ylim()
    assert 2 * half / (hi - lo) > 0.03  # the band is a visible part of the axis
    assert "1.96" not in figures.damping_caption(day.protocol.processing.damping_alpha_max_deg)


# ------------------------------------------------------------------------- thumbnails
def test_align_zero_puts_both_zeros_at_one_height():
    fig = Figure()
    ax = fig.add_subplot()
    twin = ax.twinx()
    ax.set_ylim(-0.1, 2.0)
    twin.set_ylim(-0.5, 0.6)
    figure_base.align_zero(ax, twin)
    assert figure_base.zero_fraction(ax) == pytest.approx(figure_base.zero_fraction(twin))
    assert ax.get_ylim()[1] == 2.0 and twin.get_ylim() == (-0.5, 0.6)  # only a bottom moved


def test_thumbnails_label_both_axes_and_share_the_zero_line(hull_day):
    day = hull_day.result
    fig = Figure()
    ax = fig.add_subplot()
    twin = figures.run_thumbnail(ax, day.reductions[13])
    assert "[m/s]" in ax.get_ylabel() and "[N]" in twin.get_ylabel()
    assert figure_base.zero_fraction(ax) == pytest.approx(figure_base.zero_fraction(twin))
    grid = pdf.ThumbGrid()
    runs = pdf.thumbnail_runs(day.runs, day.reductions, day.previews,
                              day.rejected)[:pdf.THUMBS_PER_PAGE]
    grid.draw(day, runs)
    drawn = 0
    for ax, twin in grid.cells:
        if not (ax.get_visible() and ax.axison and twin.get_visible() and ax.get_lines()):
            continue
        drawn += 1
        assert "U" in ax.get_ylabel() and "[m/s]" in ax.get_ylabel()
        assert "D" in twin.get_ylabel() and "[N]" in twin.get_ylabel()
        assert ax.get_xlabel() == "t [s]"
        assert figure_base.zero_fraction(ax) == pytest.approx(figure_base.zero_fraction(twin))
    assert drawn >= 8


# ---------------------------------------------------------------- predicted vs measured
@pytest.mark.heavy
def test_predicted_vs_measured_is_a_page_of_the_report(hull_day, tmp_path, monkeypatch):
    day = hull_day.result
    # the pages read below drawn, the others blank (the PDF still holds the whole plan)
    draw_only_pages(monkeypatch, lambda page: page.kind == "title" or page.section == "Vehicle")
    assert pdf.vehicle_pages(day) == []  # no [vehicle]: no page
    moved = _with_prediction(day)
    pages = pdf.page_plan(moved)
    assert [p.section for p in pages].count("Vehicle") == 1
    assert len(pages) == len(pdf.page_plan(day)) + 1
    fig = fig_predicted(moved.coefficients, page=True)
    (ax,) = fig.axes
    n = int(np.isfinite(moved.hull.coefficients["predicted"]).sum())
    assert len(ax.get_yticks()) == n and ax.get_xlabel()
    path = pdf.write_pdf(moved, tmp_path)
    reader = PdfReader(path)
    assert len(reader.pages) == len(pages)
    i = next(k for k, p in enumerate(pages) if p.section == "Vehicle")
    text = reader.pages[i].extract_text()
    assert "Vehicle" in text and "Measured beside predicted" in text
    assert "Vehicle" in reader.pages[0].extract_text()  # in the contents


# ------------------------------------------------------------------------- manoeuvre.png
def _turning_ts(duration: float = 100.0) -> pd.DataFrame:
    t = np.linspace(0.0, duration, 2001)
    r = -20.0  # yaw rate [deg/s]: five and a half turns to port
    psi = r * t
    radius = 1.8
    ang = np.radians(psi)
    return pd.DataFrame({
        "t_s": t, "x_m": radius * np.sin(-ang), "y_m": -radius * (1 - np.cos(ang)),
        "z_m": -0.04 * t, "phi_deg": 0 * t, "theta_deg": 0 * t, "psi_deg": psi,
        "u_m_s": 0.6 + 0.9 * np.exp(-t), "v_m_s": 0.1 + 0 * t, "w_m_s": 0 * t,
        "p_deg_s": 0 * t, "q_deg_s": 0 * t, "r_deg_s": r + 0 * t,
        "rudder_deg": 15.0 + 0 * t, "sternplane_deg": 0 * t})


def _zigzag_ts() -> pd.DataFrame:
    t = np.linspace(0.0, 100.0, 2001)
    psi = 35 * np.sin(2 * np.pi * t / 9.5)
    return pd.DataFrame({
        "t_s": t, "x_m": 0.8 * t, "y_m": 0.6 * np.sin(2 * np.pi * t / 9.5 - 1.2),
        "z_m": 0.015 * t, "phi_deg": 0 * t, "theta_deg": 0 * t, "psi_deg": psi,
        "u_m_s": 0.8 + 0 * t, "v_m_s": 0 * t, "w_m_s": 0 * t, "p_deg_s": 0 * t,
        "q_deg_s": 0 * t, "r_deg_s": 0 * t,
        "rudder_deg": np.where(np.sin(2 * np.pi * t / 9.5 + 0.5) > 0, 20.0, -20.0),
        "sternplane_deg": 0 * t})


def _tick_overlaps(fig: Figure, ax) -> int:
    renderer = figure_base._renderer(fig)
    fig.draw_without_rendering()
    out = 0
    for axis in (ax.xaxis, ax.yaxis):
        boxes = [t.get_window_extent(renderer) for t in axis.get_ticklabels()
                 if t.get_visible() and t.get_text()]
        out += sum(a.overlaps(b) for a, b in combinations(boxes, 2))
    return out


def test_turning_figure_keeps_the_rudder_off_the_heading_axis():
    fig = manoeuvre_figure(_turning_ts(), "turning", "test")
    track, heading, controls, speed, depth = fig.axes
    assert track.get_aspect() == 1.0  # a circle at true scale
    lo, hi = heading.get_ylim()
    assert -200 <= lo and hi <= 200  # wrapped, not a −2000° axis
    y = heading.get_lines()[0].get_ydata()
    assert np.nanmin(y) >= -180 and np.nanmax(y) < 180 and np.isnan(y).sum() >= 5
    assert "[deg]" in heading.get_ylabel()
    rudder = next(ln for ln in controls.get_lines() if "rudder" in ln.get_label())
    assert np.all(rudder.get_ydata() == 15.0)
    clo, chi = controls.get_ylim()
    assert clo < -15 and 15 < chi < 30  # the deflection fills its own axis
    assert "[deg]" in controls.get_ylabel()
    assert "[m/s]" in speed.get_ylabel() and "[m]" in depth.get_ylabel()
    assert speed.get_ylim()[1] >= 1.5
    for ax in fig.axes:
        assert ax.get_ylabel() and _tick_overlaps(fig, ax) == 0
    for ax in (controls, speed):
        assert figure_base.data_under_legend(ax) == 0


def test_zigzag_track_is_readable_and_heading_has_its_own_panel():
    fig = manoeuvre_figure(_zigzag_ts(), "zigzag", "test")
    track, heading, controls, speed, depth = fig.axes
    renderer = figure_base._renderer(fig)
    fig.draw_without_rendering()
    box = track.get_window_extent(renderer)
    assert box.height > 0.2 * fig.bbox.height  # not a strip
    assert box.width > 0.6 * fig.bbox.width  # the long track across
    assert track.get_aspect() == 1.0 or "stretched" in track.get_ylabel()
    assert _tick_overlaps(fig, track) == 0
    assert len(track.get_xticklabels()) >= 4 and len(track.get_yticklabels()) >= 3
    assert "heading" in heading.get_ylabel() and heading.get_ylim()[1] < 60
    assert all("rudder" not in ln.get_label() for ln in heading.get_lines())


def test_wrapped_heading_breaks_the_line_at_each_wrap():
    psi = np.linspace(0.0, -2000.0, 4001)
    w = wrapped_heading(psi)
    finite = w[np.isfinite(w)]
    assert finite.min() >= -180 and finite.max() < 180
    assert np.isnan(w).sum() == 6  # −180° crossed at −180, −540, … −1980°
    assert np.nanmax(np.abs(np.diff(w))) < 1.0
