"""The outputs of a packing map run with drags (`map --damping`, studies/damped_study.py), beside
map.csv:

    events.csv      one row per plastic event, drag and cell: the cell's varied values, then
                    models/packing/precursors.EVENT_COLUMNS (raw units; empty: not known).
    damped.csv      one row per cell and drag: the varied values, then DAMPED_COLUMNS.
    runs.csv        (map --causality) one row per damped run from an onset: the varied values,
                    then RUN_COLUMNS.
    precursors.csv  the cells pooled over the seeds (every varied key but packing.seed) per drag:
                    GROUP_COLUMNS, fractions with Wilson's 95 % interval, rates with the mean's,
                    the runs counted per verdict (empty where none ran).
    precursors.png  the fraction of plastic events preceded by a damped instability against the
                    drag [omega_0], one line per group of the other keys, with the intervals,
                    and dotted the fraction chance gives.
Each file is written atomically (files.save_text); floats with repr, as map.csv (reports/maps.py: csv_table).
"""
from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np

from diskfriction.files import save_text
from diskfriction.models.packing.precursors import EVENT_COLUMNS
from diskfriction.reports.figures import new_figure, save_figure
from diskfriction.reports.maps import csv_table
from diskfriction.studies.damped_study import DAMPED_COLUMNS, GROUP_COLUMNS, RUN_COLUMNS, precursor_groups

SEED = "packing.seed"
"""The varied key pooled over (the seeds are the ensemble)."""


def study_cells(cells, records) -> list[tuple[dict, list[dict], list[dict], Optional[list[dict]]]]:
    """(values, damped summaries, event rows, run rows or None) of every cell (a failed cell
    carries none of them; a cell that ran no dynamics no run rows)."""
    return [(dict(cell.values), record.get("damped") or [], record.get("events") or [], record.get("runs"))
            for cell, record in zip(cells, records)]


def save_study(out: Path, axes, cells, records) -> list[str]:
    """events.csv, damped.csv, precursors.csv and precursors.png (module docstring); returns
    their names."""
    keys = [axis.key for axis in axes]
    study = study_cells(cells, records)
    save_text(out / "events.csv", csv_table(keys + list(EVENT_COLUMNS),
                                        [values | row for values, _, rows, _ in study for row in rows]))
    save_text(out / "damped.csv", csv_table(keys + list(DAMPED_COLUMNS),
                                        [values | s for values, summaries, _, _ in study for s in summaries]))
    names = ["events.csv", "damped.csv"]
    if any(runs is not None for *_, runs in study):
        save_text(out / "runs.csv", csv_table(keys + list(RUN_COLUMNS),
                                              [values | r for values, _, _, runs in study for r in runs or []]))
        names.append("runs.csv")
    pooled = [key for key in keys if key != SEED]
    groups = precursor_groups(study, pooled)
    save_text(out / "precursors.csv", csv_table(pooled + ["drag"] + list(GROUP_COLUMNS), groups))
    plot_precursors(groups, pooled, out / "precursors.png")
    return names + ["precursors.csv", "precursors.png"]


def plot_precursors(groups: list[dict], keys: list[str], path: Path) -> None:
    """The fraction of plastic events preceded by a damped instability against the drag, one
    colour per group of `keys`, Wilson's intervals as bars, and dotted in the same colour what
    chance gives (chance_preceded: the fraction an event at a strain drawn evenly from its
    segment would be preceded)."""
    fig, ax = new_figure(figsize=(6.4, 4.2))
    lines: dict[tuple, list[dict]] = {}
    for g in groups:
        lines.setdefault(tuple(g[k] for k in keys), []).append(g)
    for label, members in lines.items():
        members = [m for m in members if m["events"]]
        if not members:
            continue
        drag = np.array([m["drag"] for m in members])
        y = np.array([m["preceded_fraction"] for m in members])
        errors = np.clip([y - [m["preceded_lo"] for m in members], [m["preceded_hi"] for m in members] - y],
                         0.0, None)  # an interval holds its fraction: no negative bar from rounding
        text = ", ".join(f"{k.split('.')[-1]} = {v:g}" for k, v in zip(keys, label))
        line = ax.errorbar(drag, y, yerr=errors, fmt="-o", capsize=3, ms=4, label=f"{text or 'all'}")
        chance = [m["chance_preceded"] for m in members]
        if all(c is not None for c in chance):
            ax.plot(drag, chance, ":", color=line[0].get_color())
    ax.set_xlabel(r"drag $\eta$ [$\omega_0$]")
    ax.set_ylabel("fraction of plastic events preceded (dotted: by chance)")
    ax.set_ylim(-0.02, 1.02)
    if any(g["drag"] > 0 for g in groups):
        ax.set_xscale("symlog", linthresh=min(g["drag"] for g in groups if g["drag"] > 0))
        ax.set_xlim(left=0.0)
    ax.legend(fontsize=7)
    save_figure(fig, path)
