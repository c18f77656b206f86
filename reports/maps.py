"""Outputs of a parameter map (studies/maps.py): the tidy table, its parameters, the figure.

    map.csv   one row per cell, in grid order (the first key slowest): the varied values, then
              studies.maps.COLUMNS. Raw units (F_x [force], sigma_max [1 / time], wall_time
              [s]); an empty field is a value not computed (no slide runs, no branch, nothing
              slid). Floats are written with repr, so that they read back to the same bits:
              pandas.read_csv("map.csv") loads it. Every column but wall_time is the same, bit
              for bit, whatever ran the cells in what order; wall_time measures the machine.
    map.json  the parameters (base scene, axes, F_x range, matrix, slide runs, code version)
              and the count of cells per status.
    map.png   one key: per cell, the complex windows and the windows whose run slid as bands
              against F_x, F_slide marked, failed cells with their reason; beside it mu_eff
              with the Coulomb limit mu_eff = mu (or, without slide runs, sigma_max).
              Two keys: F_slide (or, without slide runs, where the first complex window
              starts) in the plane of the two keys, failed and ended cells marked.
Figures use the paper's units (reports/units.py): F_x as the paper quotes it, rates in 1 / tau.
"""
from __future__ import annotations

import csv
import io
from collections import Counter
from dataclasses import asdict
from pathlib import Path

import numpy as np

from diskfriction.studies.maps import COLUMNS, Axis, Cell, MapParams
from diskfriction.models.chain.windows import Window, complex_spans
from diskfriction.files import save_json, save_text
from diskfriction.reports.figures import OUTCOME_STYLE, new_figure, save_figure
from diskfriction.reports.units import F_X_LABEL, PaperUnits
from diskfriction.scenes import Scene
from diskfriction.scenes.packing import PackingScene
STATUS_MARK = {"failed": "F", "ended": "E"}
"""How the plane shows a cell without a value: failed (no branch) and ended (branch stopped)."""


def table_rows(cells: list[Cell], records: list[dict], columns: tuple = COLUMNS) -> list[dict]:
    """One row per cell: its varied values, then its summary's `columns` (studies.maps.COLUMNS,
    or a packing's studies.packing_maps.PACKING_COLUMNS)."""
    return [dict(cell.values) | {c: record["summary"][c] for c in columns}
            for cell, record in zip(cells, records)]


def field(value) -> str:
    """A CSV field: "" for None, repr for a float (round-trips exactly), str otherwise."""
    if value is None:
        return ""
    return repr(value) if isinstance(value, float) else str(value)


def csv_text(axes: list[Axis], rows: list[dict], columns: tuple = COLUMNS) -> str:
    """The table as CSV: a header of the varied keys and `columns`, one line per row."""
    return csv_table([axis.key for axis in axes] + list(columns), rows)


def csv_table(header: list[str], rows: list[dict]) -> str:
    """CSV text: `header`, then each row's values under it (field)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    writer.writerows([field(row[name]) for name in header] for row in rows)
    return buffer.getvalue()


def save_map(out: Path, scene: Scene | PackingScene, axes: list[Axis], params, version: str,
             cells: list[Cell], records: list[dict], columns: tuple = COLUMNS) -> None:
    """OUT/map.csv and OUT/map.json (module docstring; a packing's params and `columns` are
    studies/packing_maps.py's), each written atomically."""
    rows = table_rows(cells, records, columns)
    save_text(Path(out) / "map.csv", csv_text(axes, rows, columns))
    save_json(Path(out) / "map.json", {
        "scene": scene.physics_fields(), "scene_file": scene.source,
        "axes": [asdict(axis) for axis in axes], "params": asdict(params), "code": version,
        "cells": len(cells), "status": dict(sorted(Counter(r["status"] for r in rows).items()))})


# ---- figures (plots only: every number comes from the records) --------------------------------

def key_label(axis: Axis, geometry: str = "chain") -> str:
    """Axis label of a varied key: its dotted name and its unit from the geometry's scene
    schema."""
    from diskfriction.scenes.schema import SCHEMAS

    unit = SCHEMAS[geometry][axis.key].unit
    return f"{axis.key} {unit}".strip() + (" (log grid)" if axis.log else "")


def headline(reason: str, width: int = 150) -> str:
    """The first two clauses of a cell's reason (where and why the branch ended, and the
    contacts there), cut to `width` characters for a figure; map.csv keeps all of it."""
    text = "; ".join(reason.split("; ")[:2])
    return text if len(text) <= width else text[:width - 3] + "..."


def draw_bands(ax, y: float, record: dict, params: MapParams) -> None:
    """One cell's row at height y: its branch's extent (grey line, x where it ended), complex
    windows (orange), windows whose run slid (red, thinner; adjacent ones merged as complex
    windows are, models.chain.windows.complex_spans) and those whose run is not resolved
    (slid None: grey, hatched), F_slide (black triangle); a failed or ended cell says why."""
    s = record["summary"]
    if s["status"] == "failed":
        ax.text(params.F_from, y, f"  failed: {headline(s['reason'])}", va="center", fontsize=6,
                color="C3")
        return
    ax.plot([record["windows"][0][0], s["F_end"]], [y, y], color="0.6", lw=0.8, zorder=1)
    if s["status"] == "ended":
        ax.plot(s["F_end"], y, "x", color="k", ms=6, zorder=4)
        ax.text(s["F_end"], y, f"  {headline(s['reason'])}", va="center", fontsize=6, color="C3")
    for a, b in complex_spans(Window(*w) for w in record["windows"]):
        ax.broken_barh([(a, b - a)], (y - 0.3, 0.6), facecolors="C1", edgecolors="C1",
                       linewidth=0.6, alpha=0.6, zorder=2)
    for outcome in (True, None):
        style = OUTCOME_STYLE[outcome]
        for a, b in complex_spans(Window(*r["window"], int(r["slid"] is outcome))
                                  for r in record["runs"]):
            ax.broken_barh([(a, b - a)], (y - 0.12, 0.24), facecolors=style["color"],
                           edgecolors=style["color"], hatch=style["hatch"], linewidth=0.6, zorder=3)
    if s["F_slide"] is not None:
        ax.plot(s["F_slide"], y + 0.42, "v", color="k", ms=5, zorder=4)


def draw_mu_eff(ax, x: list, cells: list[Cell], records: list[dict]) -> None:
    """mu_eff = F_slide / (N F_y) against the varied key (log), the Coulomb limit mu_eff = mu,
    and, where no window's run slid on a branch that reached the range's end, the lower
    bound F_end / (N F_y) (open triangle up)."""
    s = [r["summary"] for r in records]
    scale = [c.scene.N * c.scene.F_y for c in cells]
    mu_eff = [np.nan if v["mu_eff"] is None else v["mu_eff"] for v in s]
    above = [v["F_end"] / n if v["status"] == "ok" and v["runs"] and v["F_slide"] is None
             else np.nan for v, n in zip(s, scale)]
    ax.semilogy(x, mu_eff, "o-", color="k", ms=4, label=r"$\mu_{eff} = F_{slide} / (N F_y)$")
    if np.isfinite(above).any():
        ax.semilogy(x, above, "^", mfc="none", color="k", ms=6,
                    label=r"no run slid up to $F_{end}$: $\mu_{eff} > F_{end} / (N F_y)$")
    ax.semilogy(x, [c.scene.mu for c in cells], "--", color="C0",
                label=r"Coulomb limit $\mu_{eff} = \mu$")
    ax.set_ylabel(r"$\mu_{eff}$ (dimensionless)")


def plot_bands(axis: Axis, cells: list[Cell], records: list[dict], params: MapParams,
               path: Path, title: str) -> None:
    """The one-key figure (module docstring)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    fig, (bands, right) = new_figure(1, 2, figsize=(12, 1.6 + 0.32 * len(cells)),
                                     gridspec_kw={"width_ratios": [2.2, 1]})
    for y, record in enumerate(records):
        draw_bands(bands, y, record, params)
    labels = [f"{dict(c.values)[axis.key]:g}" for c in cells]
    bands.set(yticks=range(len(cells)), yticklabels=labels, ylim=(-0.7, len(cells) - 0.3),
              xlim=(params.F_from, params.F_to), xlabel=F_X_LABEL, ylabel=key_label(axis))
    handles = [Patch(color="C1", alpha=0.6, label=f"complex pair(s) of {params.matrix}"),
               Line2D([], [], color="0.6", label="branch (x: ended before the range's end)")]
    if params.slide is not None:
        handles += [Patch(color=OUTCOME_STYLE[True]["color"], label="window whose run slid"),
                    Patch(facecolor=OUTCOME_STYLE[None]["color"], hatch=OUTCOME_STYLE[None]["hatch"],
                          label="run not resolved (energy budget did not close)"),
                    Line2D([], [], ls="", marker="v", color="k", label="F_slide")]
    bands.legend(handles=handles, fontsize=7, loc="lower left", bbox_to_anchor=(0.0, 1.01),
                 ncol=len(handles), frameon=False)
    x = [dict(c.values)[axis.key] for c in cells]
    if params.slide is not None:
        draw_mu_eff(right, x, cells, records)
    else:
        sigma = [r["summary"]["sigma_max"] for r in records]
        right.plot(x, [np.nan if s is None else s * PaperUnits.of(c.scene).time
                       for s, c in zip(sigma, cells)], "o-", color="k", ms=4,
                   label=r"max $\sigma$ of $M^{-1}J$ on the branch")
        right.set_ylabel(r"$\sigma_{max}$ [$1/\tau$]")
    if axis.log:
        right.set_xscale("log")
    right.set_xlabel(key_label(axis))
    right.legend(fontsize=7)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    save_figure(fig, path)


def plot_plane(axes: list[Axis], cells: list[Cell], records: list[dict], what: str, label: str,
               absent: str, path: Path, title: str, geometry: str = "chain") -> None:
    """The two-key figure (module docstring): the first key along x, the second along y, one
    square per cell (evenly, whatever the spacing of the values) with the value of its summary's
    `what` (colour bar `label`), failed and ended cells marked F and E, a cell without a value
    "-" (`absent` says what that means)."""
    shape = tuple(len(axis.values) for axis in axes)
    value = np.full(shape, np.nan)
    fig, ax = new_figure(figsize=(max(6.0, 2.8 + 0.8 * shape[0]), max(4.0, 2.0 + 0.45 * shape[1])))
    for cell, record in zip(cells, records):
        s = record["summary"]
        if s[what] is not None:
            value[cell.index] = s[what]
        mark = STATUS_MARK.get(s["status"], "-" if s[what] is None else f"{s[what]:.3g}")
        ax.text(*cell.index, mark, ha="center", va="center", fontsize=7,
                bbox={"facecolor": "w", "alpha": 0.7, "linewidth": 0})
    mesh = ax.pcolormesh(np.arange(shape[0] + 1) - 0.5, np.arange(shape[1] + 1) - 0.5,
                         np.ma.masked_invalid(value).T, cmap="viridis", shading="flat")
    fig.colorbar(mesh, ax=ax, label=label)
    ax.set(xticks=range(shape[0]), xticklabels=[f"{v:g}" for v in axes[0].values],
           yticks=range(shape[1]), yticklabels=[f"{v:g}" for v in axes[1].values],
           xlabel=key_label(axes[0], geometry), ylabel=key_label(axes[1], geometry),
           facecolor="0.85")
    ax.set_title(f"{title}\nF: failed (no branch), E: branch ended, -: {absent}", fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)


def plot_map(axes: list[Axis], cells: list[Cell], records: list[dict], params: MapParams,
             path: Path, title: str) -> None:
    """map.png: plot_bands for one key, plot_plane for two."""
    if len(axes) == 1:
        plot_bands(axes[0], cells, records, params, path, title)
    else:
        slide = params.slide is not None
        label = ("F_slide, the lowest load whose run slid" if slide else
                 "F_x where the first complex window starts")
        plot_plane(axes, cells, records, "F_slide" if slide else "F_complex",
                   f"{label}\n[raw force, as the paper quotes it]",
                   "no run slid" if slide else "no complex window", path, title)
