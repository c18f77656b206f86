"""map.png of a packing map (studies/packing_maps.py); map.csv and map.json are written as a
chain's are (reports/maps.py, with PACKING_COLUMNS).

    one key:  against the varied key, three panels: the fraction of the strain with a complex
              pair (and the mean number of pairs over the strain); the fastest pair's growth
              rate sigma / omega_c, median over the strain and largest; the collisions (left
              axis) and plastic events (right axis) per 1e-3 of strain, both linear from 0.
              An ended cell is drawn with open markers (its
              figures cover the strain it reached); a failed cell has no point, its reason
              is written under the panels.
    two keys: the fraction of the strain with a complex pair in the plane of the two keys.
Raw units (docs/packings.md: a packing has no paper units).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from diskfriction.reports.figures import new_figure, save_figure
from diskfriction.reports.maps import headline, key_label, plot_plane
from diskfriction.studies.maps import Axis, Cell


def per_strain(summary: dict, column: str) -> float:
    """A count of the summary per 1e-3 of the strain reached (nan without a branch)."""
    if summary["status"] == "failed" or summary["gamma_end"] <= 0:
        return np.nan
    return 1e-3 * summary[column] / summary["gamma_end"]


def value(summary: dict, column: str, scale: float = 1.0) -> float:
    """summary[column] / scale, nan where it is None."""
    return np.nan if summary[column] is None else summary[column] / scale


def plot_packing_bands(axis: Axis, cells: list[Cell], records: list[dict], path: Path,
                       title: str) -> None:
    """The one-key figure (module docstring)."""
    summaries = [r["summary"] for r in records]
    x = np.array([dict(c.values)[axis.key] for c in cells], dtype=float)
    ended = np.array([s["status"] == "ended" for s in summaries])
    fig, (frac, rate, counts) = new_figure(1, 3, figsize=(13, 4.2))

    def draw(ax, y, label, color, marker="o"):
        y = np.asarray(y, dtype=float)
        ax.plot(x, y, marker + "-", color=color, ms=5, label=label)
        if ended.any():
            ax.plot(x[ended], y[ended], marker, color="w", ms=3, zorder=3)

    draw(frac, [value(s, "complex_fraction") for s in summaries],
         "strain with a complex pair (fraction)", "C1")
    pairs = frac.twinx()
    draw(pairs, [value(s, "pairs_mean") for s in summaries], "complex pairs, mean over the strain (right)",
         "C0", "s")
    frac.set(ylim=(-0.03, 1.03), ylabel="fraction of strain")
    pairs.set(ylim=(0, None), ylabel="pairs (mean over strain)")
    frac.legend(handles=frac.lines[:1] + pairs.lines[:1], fontsize=7, loc="lower left")
    for column, color, label in (("sigma_median", "C3", "median"), ("sigma_max", "k", "largest")):
        draw(rate, [value(s, column, s["omega_c"] or 1.0) for s in summaries],
             rf"{label} $\sigma / \omega_c$ of the fastest pair", color)
    rate.set(yscale="log", ylabel=r"$\sigma / \omega_c$, $\sigma = |\mathrm{Im}\sqrt{\lambda}|$")
    rate.legend(fontsize=7)
    draw(counts, [per_strain(s, "collisions") for s in summaries],
         "collisions located per 1e-3 of strain", "C4")
    events = counts.twinx()
    draw(events, [per_strain(s, "plastic_events") for s in summaries],
         "plastic events per 1e-3 of strain (right)", "C2", "s")
    for ax, what in ((counts, "collisions"), (events, "plastic events")):
        top = max(ax.get_ylim()[1], 1e-3)
        ax.set(ylim=(-0.04 * top, top), ylabel=f"{what} per 1e-3 of strain")
    counts.legend(handles=counts.lines[:1] + events.lines[:1], fontsize=7, loc="center left")
    for ax in (frac, rate, counts):
        ax.set_xlabel(key_label(axis, "packing"))
        if axis.log:
            ax.set_xscale("log")
    notes = [f"{dict(c.values)[axis.key]:g}: {s['status']}: {headline(s['reason'], 110)}"
             for c, s in zip(cells, summaries) if s["status"] != "ok"]
    if notes:
        fig.text(0.01, 0.01, "open markers: ended before the strain range's end; "
                 + "; ".join(notes), fontsize=6, color="C3", va="bottom")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout(rect=(0, 0.05 if notes else 0, 1, 1))
    save_figure(fig, path)


def plot_packing_map(axes: list[Axis], cells: list[Cell], records: list[dict], path: Path,
                     title: str) -> None:
    """map.png of a packing map: plot_packing_bands for one key, the plane of
    complex_fraction for two."""
    if len(axes) == 1:
        plot_packing_bands(axes[0], cells, records, path, title)
    else:
        plot_plane(axes, cells, records, "complex_fraction",
                   "fraction of the strain with a complex pair", "no state",
                   path, title, "packing")
