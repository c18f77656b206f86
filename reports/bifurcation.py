"""Bifurcation outputs: branch.npz, collisions.json and the diagram (the paper's Fig. 2).

Files hold raw units (docs/model.md#units: m = 1, 2R = 1, k_n = 2000); the diagram shows the paper's units
(reports/units.py: eigenvalues / k_n for the paper's scene) and F_x as the paper quotes it.
"""
from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np

from diskfriction.continuation.spectra.tracking import Kind
from diskfriction.continuation import records
from diskfriction.continuation.branch import Branch
from diskfriction.continuation.records import collision_records  # noqa: F401  (the commands')
from diskfriction.reports.figures import (legend, line_key, new_figure, re_scale, re_values,
                                          save_figure, set_re_axis)
from diskfriction.reports.units import F_X_LABEL, PaperUnits, eig_label
from diskfriction.scenes import Scene


def save_branch(out: Path, branch: Branch, scene: Scene) -> None:
    """DIR/branch.npz (continuation/records.branch_arrays: every accepted point's F_x, q, xi,
    eigenvalues, condition numbers, n_complex, residual, free rolling modes, leg and window run,
    and the names; with the scene's k_n and N) and DIR/collisions.json
    (records.save_collisions), each written atomically."""
    records.save_branch(Path(out) / "branch.npz", branch, k_n=np.array(scene.k_n),
                        N=np.array(scene.N))
    records.save_collisions(Path(out) / "collisions.json", branch)


LEG_LINES = {True: "-", False: "--"}
"""Line style of a leg: loading (F_x rising) solid, unloading dashed."""
BIRTH, DEATH, BUBBLE = ("^", "C3"), ("v", "C2"), ("D", "C4")
"""Marker and colour of a located birth, death, and of a bubble narrower than a pixel."""


COLUMN_COLORS = tuple(k for k in range(20) if k not in (14, 15))
"""tab20 without its two greys: grey is the preparation leg's."""


def column_color(k: int):
    """The colour of tracked eigenvalue column k (the same in both panels)."""
    import matplotlib

    return matplotlib.colormaps["tab20"](COLUMN_COLORS[k % len(COLUMN_COLORS)])


def narrow_bubbles(collisions: list[tuple[float, str, float]], pixel: float) -> list[int]:
    """Indices i where collision i is a birth and i + 1 the death of the same bubble, closer
    than `pixel` in F_x: drawn as one marker, since neither a line nor shading can show it."""
    return [i for i in range(len(collisions) - 1)
            if collisions[i][1] == Kind.BIRTH and collisions[i + 1][1] == Kind.DEATH
            and abs(collisions[i + 1][0] - collisions[i][0]) < pixel]


def pair_line(F: np.ndarray, im: np.ndarray, collisions: list[tuple[float, str, float]]
              ) -> tuple[np.ndarray, np.ndarray]:
    """(F, Im) of one tracked eigenvalue's line on the Im panel: its samples while it is the
    upper member of a complex pair (im finite, nan elsewhere), each run of them closed at
    Im = 0 by the located birth just before it and the death just after it (the collision
    nearest to the run within the interval between samples), runs separated by nan."""
    xs, ys = [], []
    inside = np.isfinite(im)
    starts = np.flatnonzero(inside & ~np.r_[False, inside[:-1]])
    stops = np.flatnonzero(inside & ~np.r_[inside[1:], False])

    def nearest(kind, lo, hi, to):
        found = [p for p, k, _ in collisions if k == kind and min(lo, hi) <= p <= max(lo, hi)]
        return min(found, key=lambda p: abs(p - to)) if found else None

    for a, b in zip(starts, stops):
        birth = nearest(Kind.BIRTH, F[a - 1], F[a], F[a]) if a > 0 else None
        death = nearest(Kind.DEATH, F[b], F[b + 1], F[b]) if b + 1 < F.size else None
        xs += ([birth] if birth is not None else []) + list(F[a:b + 1]) + \
            ([death] if death is not None else []) + [np.nan]
        ys += ([0.0] if birth is not None else []) + list(im[a:b + 1]) + \
            ([0.0] if death is not None else []) + [np.nan]
    return np.array(xs, dtype=float), np.array(ys, dtype=float)


def draw_lines(ax, lines: list[np.ndarray], colors: list, style: str, width: float,
               marker_size: float = 0.0) -> None:
    """Polylines (each an (m, 2) array of x, y; nan breaks a line) in their colours, as one
    LineCollection (one plot call per eigenvalue took most of the diagram's time at N = 100),
    with a dot of marker_size at every finite vertex if > 0; the axes' limits include them."""
    from matplotlib.collections import LineCollection
    from matplotlib.colors import to_rgba_array

    if not lines:
        return
    colors = to_rgba_array(colors)
    ax.add_collection(LineCollection(lines, colors=colors, linestyles=style, linewidths=width,
                                     zorder=2))  # above the shaded windows, as plot lines are
    if marker_size > 0:
        points = np.vstack(lines)
        dot_colors = np.repeat(np.arange(len(lines)), [len(xy) for xy in lines])
        finite = np.isfinite(points).all(axis=1)
        ax.scatter(*points[finite].T, s=marker_size ** 2, marker=".", linewidths=1.0, zorder=2,
                   c=colors[dot_colors[finite]])
    ax.autoscale_view()


def leg_label(leg_id: int, F: np.ndarray) -> str:
    """"loading 0 -> 0.12", "unloading 0.12 -> 0"; leg 0 is the preparation from rest."""
    what = "loading" if F[-1] >= F[0] else "unloading"
    return f"{'preparation: ' if leg_id == 0 else ''}{what} {F[0]:.3g} -> {F[-1]:.3g}"


def draw_spectrum(top, bottom, F_x: np.ndarray, lam: np.ndarray, leg: np.ndarray,
                  n_complex: np.ndarray, collisions: list[tuple[float, str, float]],
                  matrix: str, x_label: str = F_X_LABEL, eig_unit: Optional[str] = None,
                  re_axis: Optional[str] = None, shade: bool = True) -> list:
    """Im (top) and Re (bottom) of every eigenvalue `lam` (rows: points at F_x, already in the
    paper's unit of `matrix`; columns tracked along the branch; nan where an eigenvalue is not
    known, e.g. outside a spectral window) against F_x. The Re axis is re_axis ("linear",
    "log", "-log": figures.re_scale), by default chosen from the data: log where Re spans
    decades with one sign, else linear. bottom None: the Im panel alone (x_label on it).

    Each tracked eigenvalue is a line in its own colour, on the top panel while it is the upper
    member of a complex pair; the requested leg (1) in colour, a preparation leg (0) in grey;
    loading legs solid, unloading dashed. Complex windows of the requested leg are shaded
    (unless not `shade`: the caller shades them), from its located collisions (F_x, "birth" | "death", double eigenvalue in the same unit):
    births ^, deaths v, and a bubble narrower than a pixel as one diamond. Returns the legend
    handles that key all of it (the caller places the legend). Axis labels: x_label, and
    Re / Im of `matrix` in eig_unit (default the paper's unit of `matrix`). Plots only: no
    physics."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from diskfriction.models.chain.windows import complex_spans, leg_windows
    from diskfriction.reports.analysis import eigen_status_rows

    upper = eigen_status_rows(lam) == 1
    scale = re_axis or re_scale(lam.real)
    pixel = np.ptp(F_x) / max(top.get_window_extent().width, 1.0)
    handles = []
    for leg_id in (0, 1):
        rows = np.flatnonzero(leg == leg_id)
        if not rows.size:
            continue
        if leg_id == 1 and rows[0] > 0:  # the requested leg starts where the preparation ended
            rows = np.r_[rows[0] - 1, rows]
        F = F_x[rows]
        style = LEG_LINES[bool(F[-1] >= F[0])]
        colors = ["0.7" if leg_id == 0 else column_color(k) for k in range(lam.shape[1])]
        pairs = [(k, pair_line(F, np.where(upper[rows, k], lam.imag[rows, k], np.nan),
                               collisions if leg_id == 1 else []))
                 for k in range(lam.shape[1]) if upper[rows, k].any()]
        draw_lines(top, [np.column_stack(xy) for _, xy in pairs], [colors[k] for k, _ in pairs],
                   style, 1.0, marker_size=2.5)
        drawn = ([k for k in range(lam.shape[1]) if np.isfinite(lam.real[rows, k]).any()]
                 if bottom is not None else [k for k, _ in pairs])
        if bottom is not None:
            draw_lines(bottom, [np.column_stack([F, re_values(lam.real[rows, k], scale)])
                                for k in drawn], [colors[k] for k in drawn], style, 0.7)
        handles.append(line_key([colors[k] for k in drawn],
                                style, leg_label(leg_id, F) + ("" if leg_id == 0 else
                                                               "\n(one colour per eigenvalue)")))
    windows = leg_windows(F_x, n_complex, leg, [(p, kind) for p, kind, _ in collisions])
    if shade:
        for a, b in complex_spans(windows):
            top.axvspan(min(a, b), max(a, b), color="C1", alpha=0.12, lw=0)
        handles.append(Patch(color="C1", alpha=0.25, label="a complex pair (located windows)"))
    bubbles = narrow_bubbles(collisions, pixel)
    in_bubble = {i for b in bubbles for i in (b, b + 1)}
    marks = {BIRTH: [], DEATH: [], BUBBLE: []}  # (F_x, Im on top, Re below) of each marker
    for i, (p, kind, value) in enumerate(collisions):
        if i not in in_bubble:
            marks[BIRTH if kind == Kind.BIRTH else DEATH].append((p, 0.0, value))
    for i in bubbles:
        (a, _, value), (b, _, _) = collisions[i], collisions[i + 1]
        inside = (F_x >= min(a, b)) & (F_x <= max(a, b)) & (leg == 1)
        height = float(np.max(np.where(upper[inside], lam.imag[inside], 0.0), initial=0.0))
        marks[BUBBLE].append((0.5 * (a + b), height, value))
    for (marker, color), points in marks.items():  # one line of markers per kind and panel
        if points:
            F, im, value = (np.array(column) for column in zip(*points))
            top.plot(F, im, marker, color=color, ms=5)
            if bottom is not None:
                bottom.plot(F, re_values(value, scale), marker, color=color, ms=5)
    counts = {kind: sum(c[1] == kind for c in collisions) for kind in Kind}
    handles += [Line2D([], [], ls="", marker=BIRTH[0], color=BIRTH[1],
                       label=f"birth of a pair ({counts[Kind.BIRTH]})"),
                Line2D([], [], ls="", marker=DEATH[0], color=DEATH[1],
                       label=f"death of a pair ({counts[Kind.DEATH]})")]
    if bubbles:
        handles.append(Line2D([], [], ls="", marker=BUBBLE[0], color=BUBBLE[1],
                              label=f"bubble narrower than a pixel ({len(bubbles)})"))
    top.set_ylabel(eig_label("Im", matrix, eig_unit))
    if bottom is None:
        top.set_xlabel(x_label)
        return handles
    set_re_axis(bottom, lam.real, scale, eig_label("Re", matrix, eig_unit)
                + (" (log axis)" if scale != "linear" else ""))
    bottom.set_xlabel(x_label)
    return handles


def diagram_axes():
    """A new figure of a bifurcation diagram: (figure, Im panel on top, Re panel below)."""
    fig, (top, bottom) = new_figure(2, 1, sharex=True, figsize=(10, 7))
    return fig, top, bottom


def save_diagram(fig, top, handles: list, title: str, path: Path) -> None:
    """Title, the legend right of the panels, written atomically as PNG, figure closed."""
    top.set_title(title, fontsize=9)
    legend(top, handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.subplots_adjust(left=0.095, right=0.76, bottom=0.08, top=0.95, hspace=0.06)  # fixed:
    # tight_layout would measure every label first, a third of the plot's time
    save_figure(fig, path)


def plot_diagram(branch: Branch, scene: Scene, path: Path) -> None:
    """Im(lambda) (top) and Re(lambda) (bottom) of every eigenvalue against F_x in the paper's
    units (lambda / k_n for the paper's scene): draw_spectrum."""
    unit = PaperUnits.of(scene).eigenvalue(branch.matrix)
    fig, top, bottom = diagram_axes()
    lam, title = branch.eigenvalues / unit, f"{scene.name}: spectrum of {branch.matrix}, N = {scene.N}"
    if branch.window is not None:  # only the window is certified: the rest is not drawn
        lo, hi = (w / unit for w in branch.window)
        lam = np.where((lam.real >= lo) & (lam.real <= hi), lam, np.nan)
        title += f", window {lo:.5g} <= Re <= {hi:.5g} (the rest of the spectrum not tracked)"
    handles = draw_spectrum(top, bottom, branch.F_x, lam, branch.leg, branch.n_complex,
                            [(c.p, c.kind, c.eigenvalue / unit) for c in branch.collisions],
                            branch.matrix, re_axis=None if branch.window is None else "linear")
    if branch.window is not None:
        bottom.set_ylim(lo, hi)
    save_diagram(fig, top, handles, title, path)
