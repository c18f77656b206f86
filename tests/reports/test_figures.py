"""The figures: what is drawn matches the data and the legend (issue 23 items 2, 9, 15)."""
from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def axes():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1)
    yield top, bottom
    plt.close(fig)


def windowed_spectrum():
    """A windowed branch as branch.npz holds it: column 0 and 1 a pair with Im up to 6.9e-4
    between the collisions at 0.3 and 0.7, column 2 real, column 3 nan (outside the window and
    its guard bands) but for three points, column 4 nan throughout."""
    F = np.linspace(0.0, 1.0, 21)
    im = np.where((F > 0.3) & (F < 0.7), 6.9e-4 * np.sin(np.pi * (F - 0.3) / 0.4), 0.0)
    re = 0.06 + 0.01 * F
    known = np.where(F < 0.15, 0.051 + 0j, np.nan)
    lam = np.column_stack([re + 1j * im, re - 1j * im, np.full(F.size, 0.055 + 0j), known,
                           np.full(F.size, np.nan + 0j)])
    return F, lam, [(0.3, "birth", 0.063), (0.7, "death", 0.067)]


def test_windowed_diagram_draws_the_pairs_and_scales_im_to_them(axes):
    """Item 2: nan columns must not hide the pairs; the Im axis fits their largest Im."""
    from matplotlib.collections import LineCollection

    from diskfriction.reports.bifurcation import draw_spectrum

    top, bottom = axes
    F, lam, collisions = windowed_spectrum()
    draw_spectrum(top, bottom, F, lam, np.ones(F.size, int), np.zeros(F.size, int), collisions,
                  "J", re_axis="linear")
    (pair,) = [c for c in top.collections if isinstance(c, LineCollection)]
    drawn = np.vstack(pair.get_segments())
    assert np.nanmax(drawn[:, 1]) == pytest.approx(lam.imag.max())
    low, high = top.get_ylim()
    assert low <= 0.0 and lam.imag.max() <= high <= 1.2 * lam.imag.max()


def test_nan_entries_do_not_change_which_eigenvalues_are_complex():
    from diskfriction.reports.analysis import eigen_status_rows, max_imag

    _, lam, _ = windowed_spectrum()
    status = eigen_status_rows(lam)
    assert (status[:, 0] == 1).sum() == (lam.imag[:, 0] > 1e-12).sum() > 0
    assert (status[:, 2:] == 0).all()
    assert max_imag(lam).max() == pytest.approx(lam.imag.max())


def test_legend_line_entries_are_the_drawn_line_kinds(axes):
    """Item 9: each legend line shows colours and the style of lines actually drawn (no black
    "loading" line where every line is coloured)."""
    from matplotlib.collections import LineCollection
    from matplotlib.colors import to_hex

    from diskfriction.reports.bifurcation import draw_spectrum

    top, bottom = axes
    F, lam, collisions = windowed_spectrum()
    handles = draw_spectrum(top, bottom, F, lam, np.ones(F.size, int), np.zeros(F.size, int), collisions, "J")
    drawn = {(to_hex(c, keep_alpha=True), "solid") for ax in (top, bottom)
             for coll in ax.collections if isinstance(coll, LineCollection)
             for c in coll.get_colors()}
    keys = [h for h in handles if isinstance(h, tuple)]
    assert keys, "the line kinds are keyed"
    for key in keys:
        for line in key:
            assert (to_hex(line.get_color(), keep_alpha=True), "solid") in drawn
            assert line.get_linestyle() == "-"
    assert all(to_hex(line.get_color()) != "#000000" for key in keys for line in key)


@pytest.mark.parametrize("values, scale", [
    (np.array([1e-5, 3e-4, 0.1, 0.16, 0.0, 1e-12]), "log"),  # the paper's J: decades, >= 0
    (np.array([-2e-8, -1e-4, -0.08]), "-log"),
    (np.array([3.3, 0.7, -0.7, -2.3]), "linear"),  # Ziegler: both signs
    (np.array([0.055, 0.08, np.nan]), "linear"),  # a window: under two decades
])
def test_the_re_axis_scale_follows_the_data(values, scale):
    from diskfriction.reports.figures import re_scale

    assert re_scale(values) == scale


def test_the_re_panel_is_never_symlog(axes):
    """Item 9: a symlog axis bends every line where its linear core meets its log part."""
    from diskfriction.reports.bifurcation import draw_spectrum

    top, bottom = axes
    F = np.linspace(0.0, 0.12, 13)
    lam = np.column_stack([1e-5 + F * 5e-3 + 0j, 0.05 + F + 0j])
    draw_spectrum(top, bottom, F, lam, np.ones(F.size, int), np.zeros(F.size, int), [], "J")
    assert bottom.get_yscale() == "log"
    low, high = bottom.get_ylim()
    assert low <= lam.real.min() and high >= lam.real.max()


def verify_rows():
    """Four windows: slid, stayed, not resolved (slid None, accurate false), and an all-real
    interval that slid."""
    def row(a, b, pairs, slid, measured):
        return {"window": [a, b], "complex_pairs": pairs, "F_x": 0.5 * (a + b),
                "sigma_predicted": 0.1 * pairs, "sigma_measured": measured,
                "M_max": 1e-3 if slid else 1e-9, "accurate": slid is not None, "slid": slid}
    return [row(0.0, 0.2, 1, False, 0.1), row(0.2, 0.5, 2, True, 0.21),
            row(0.5, 0.7, 1, None, None), row(0.7, 1.0, 0, True, None)]


def test_verify_figure_shades_each_window_by_its_runs_outcome(axes):
    """Item 15: the shading of each window follows the table's slid column, and a run with slid
    None is shown as not resolved, not as stayed."""
    from matplotlib.colors import to_rgb

    from diskfriction.reports.figures import OUTCOME_STYLE, handle_label
    from diskfriction.reports.verify import draw_verify, shade_outcomes

    top, bottom = axes
    F, lam, collisions = windowed_spectrum()
    rows = verify_rows()
    handles = draw_verify(top, bottom, F, lam, np.ones(F.size, int), np.zeros(F.size, int),
                          collisions, rows, "J", 1.0)
    patches = shade_outcomes(top, rows)
    for patch, r in zip(patches, rows):
        style = OUTCOME_STYLE[r["slid"]]
        assert to_rgb(patch.get_facecolor()) == to_rgb(style["color"])
        assert patch.get_hatch() == (style["hatch"] or ("//" if r["complex_pairs"] == 0 else None))
        assert (patch.get_x(), patch.get_x() + patch.get_width()) == pytest.approx(r["window"])
    assert OUTCOME_STYLE[None]["color"] not in (OUTCOME_STYLE[True]["color"], OUTCOME_STYLE[False]["color"])
    assert any("not resolved" in handle_label(h) for h in handles)
    measured = [line for line in bottom.get_lines() if line.get_marker() == "o"]
    assert sorted(x for line in measured for x in line.get_xdata()) == [0.1, 0.35]


def test_slid_none_reads_not_resolved():
    from diskfriction.reports.verify import verify_table
    from diskfriction.reports.figures import slid_word

    assert [slid_word(s) for s in (True, False, None)] == ["yes", "no", "not resolved"]
    lines = verify_table(verify_rows(), "J").splitlines()
    assert [line.rsplit("|", 2)[1].strip() for line in lines[4:]] == ["no", "yes", "not resolved", "yes"]


def test_run_figure_shows_the_growth_fit_window(axes):
    """Item 9: the window of the sigma fit is on the M(t) panel, with sigma in 1/tau."""
    from diskfriction.reports.simulation import draw_growth
    from diskfriction.reports.units import PaperUnits
    from diskfriction.scenes import Scene

    top, _ = axes
    units = PaperUnits.of(Scene())
    t = np.linspace(0.0, 100.0, 2001)
    M = 1e-20 * np.exp(0.2 * t) * (1.5 + np.sin(3 * t))
    fit = {"sigma": 0.1, "t_start": 20.0, "t_end": 60.0, "period": 2.1, "blocks": 19, "reason": "ok"}
    draw_growth(top, t, M, {"fit": fit, "sigma_predicted": 0.1}, units)
    (span,) = top.patches
    assert (span.get_x(), span.get_x() + span.get_width()) == pytest.approx((20.0 / units.time, 60.0 / units.time))
    labels = [line.get_label() for line in top.get_lines()] + [span.get_label()]
    assert any("fit window" in label for label in labels)
    assert any(f"{0.1 * units.time:.4g}" in label for label in labels)


@pytest.mark.parametrize("ran, slid, says", [(True, True, "slid"), (True, False, "stayed"),
                                             (True, None, "not resolved"), (False, None, "n/a")])
def test_lammps_section_says_not_resolved_for_slid_none(ran, slid, says):
    """A run whose energy budget did not close (slid None) is neither "stayed" nor "n/a"."""
    from diskfriction.reports.sections.lammps import Reading, outcome

    reading = Reading({}, None, None, None, {}, {"J": 1, "M^-1 J": 2}, ran, slid)
    assert outcome(reading).endswith(f"; {says}")
    assert reading.claims_held() is (None if slid is None else reading.claims_held())


def test_no_eigenvalue_is_drawn_in_the_preparation_legs_grey():
    from matplotlib.colors import to_rgb

    from diskfriction.reports.bifurcation import column_color

    colors = {to_rgb(column_color(k)) for k in range(40)}
    assert all(not (r == g == b) for r, g, b in colors)


def test_point_labels_keep_a_gap_or_are_left_out(axes):
    """accuracy.png: labels of coinciding points ('span/60' and 'tol_p 1e-08' at the default
    run, one series each) were placed over each other, reading 'span/601e-08'. Every two
    placed labels, of one call or two, are at least LABEL_GAP display pixels apart; a label
    with no free place is counted as left out."""
    from diskfriction.reports.figures import LABEL_GAP, label_points

    top, _ = axes
    top.plot([1.0, 2.0, 3.0], [1.0, 2.0, 3.0], "o")
    xs, ys = [2.0] * 6, [2.0] * 6  # two series, labelled by two calls, as accuracy.png does
    left_out = label_points(top, xs, ys, [f"span/{k}" for k in range(6)])
    left_out += label_points(top, xs, ys, [f"tol_p 1e-{k:02d}" for k in range(6)])
    renderer = top.figure.canvas.get_renderer()
    boxes = [text.get_window_extent(renderer) for text in top.texts]
    assert len(boxes) + left_out == 12 and len(boxes) >= 2
    for i, a in enumerate(boxes):
        for b in boxes[:i]:
            gap = max(b.x0 - a.x1, a.x0 - b.x1, b.y0 - a.y1, a.y0 - b.y1)
            assert gap >= LABEL_GAP - 1e-9


@pytest.mark.parametrize("lo, hi", [(0.155, 0.28), (5.5e-3, 2.3e-2), (1e-3, 10.0)])
def test_wall_time_log_axes_have_tick_labels_that_do_not_overlap(axes, lo, hi):
    """accuracy.png: a log axis of wall times within one decade got matplotlib's labels on
    every minor tick ('1.6 x 10^-1 1.8 x 10^-1 ...'), running into each other."""
    from diskfriction.reports.figures import readable_log_axis

    top, _ = axes
    top.loglog([lo, hi], [1.0, 2.0])
    readable_log_axis(top.xaxis)
    top.figure.canvas.draw()
    renderer = top.figure.canvas.get_renderer()
    labels = [t for t in top.xaxis.get_ticklabels(which="both") if t.get_visible() and t.get_text()
              and lo <= t.get_position()[0] <= hi]
    boxes = [t.get_window_extent(renderer) for t in labels]
    assert len(boxes) >= 1
    assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[:i])


def test_the_diagram_shades_the_windows_of_the_requested_leg_from_its_start(axes):
    """A sweep 0.5 -> 0.4 after loading to 0.5 (leg 0), its one pair dying at 0.48, inside the
    first unloading step: the shaded span is 0.48 .. 0.5, the windows verify runs in
    (disks.windows.leg_windows). The diagram counted the pairs from the first unloading
    point, after the death, and shaded nothing."""
    from matplotlib.patches import Polygon, Rectangle

    from diskfriction.models.chain.windows import leg_windows
    from diskfriction.reports.bifurcation import draw_spectrum

    F = np.array([0.0, 0.25, 0.5, 0.45, 0.4])
    leg, n_complex = np.array([0, 0, 0, 1, 1]), np.array([0, 1, 1, 0, 0])
    im = np.array([0.0, 1e-4, 2e-4, 0.0, 0.0])
    lam = np.column_stack([0.06 + 1j * im, 0.06 - 1j * im, np.full(F.size, 0.07 + 0j)])
    collisions = [(0.48, "death", 0.06)]
    assert leg_windows(F, n_complex, leg, [(0.48, "death")]) == [(0.5, 0.48, 1), (0.48, 0.4, 0)]
    top, bottom = axes
    draw_spectrum(top, bottom, F, lam, leg, n_complex, collisions, "J", re_axis="linear")
    ends = lambda p: ([p.get_x(), p.get_x() + p.get_width()] if isinstance(p, Rectangle)
                      else np.asarray(p.get_xy())[:, 0])
    xs = [sorted({round(float(x), 12) for x in ends(p)}) for p in top.patches
          if isinstance(p, (Polygon, Rectangle))]
    assert xs == [[0.48, 0.5]]
