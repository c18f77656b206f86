"""The damped-stability study of packing maps (docs/packings-study.md): in every cell of a packing
map run with drags (PackingMapParams.damping, in units of omega_0), the damped Hopf points of its
shear at each drag (models/packing/damped.py), the plastic events against their precursors
(models/packing/precursors.py), and per drag a summary (DAMPED_COLUMNS); over the cells, the
same figures grouped by the physics keys with confidence intervals (precursor_groups).

A plastic event is "preceded" at a drag when a damped instability set in within its segment
before it (an onset between the plastic event before and this one), and "active" when the last
equilibrium before it is damped-unstable. Fractions of events get Wilson's 95 % interval (the
events of a group pooled: they are the trials); rates per unit strain get the mean over the
group's cells and 1.96 standard errors of that mean (the cells, one packing each, are the
independent samples).
"""
from __future__ import annotations

import math
from typing import Optional, Sequence

import numpy as np

DAMPED_COLUMNS = ("drag", "eta", "strain", "unstable_fraction", "growth_median", "onsets",
                  "onsets_per_disk_strain", "events", "preceded", "active", "gap_median",
                  "overlap_median")
"""A cell's damped summary at one drag: the drag [omega_0] and eta [1 / time]; the strain covered
and the fraction of it with a damped-unstable mode, the median of the fastest damped growth
rate over that strain [1 / time] (None without one) (models/packing/strain_statistics.py); the
onsets located and per disk per unit strain; the plastic events, how many were preceded and how
many active (module docstring), the median strain gap from the last onset to the event and the
median overlap of its mode with the event's field (None without any)."""

RUN_COLUMNS = ("drag", "gamma", "rate", "fold_gamma", "verdict", "time", "distance", "gained",
               "lost", "slides", "stress_change", "overlap")
"""A damped run from an onset (models/packing/causality.py): the drag [omega_0]; the onset
state's strain, the damped growth rate Re s of the mode run along [1 / time], the strain of the
plastic event ending its segment (None without one); the verdict (returned, slipped,
rearranged, saturated, or failed: FIRE could not relax its end), when it was reached [time], the
largest mass-weighted distance reached [length mass^(1/2)], the holding contacts gained and lost,
the sliding updates, the relative change of sigma_xy, and the overlap of its displacement with
that plastic event's (None without one)."""

Z_95 = 1.959963984540054
"""The standard normal's two-sided 95 % quantile."""


def _mean(values: list) -> float | None:
    return float(np.mean(values)) if values else None


def _median(values: list) -> float | None:
    return float(np.median(values)) if values else None


def damped_summary(statistics, drag: float, eta: float, index: int, hopfs: Sequence,
                   events: list[dict], N: int) -> dict:
    """DAMPED_COLUMNS of one cell at one drag: `statistics` its branch's StrainStatistics (at
    etas including eta, at `index`), `hopfs` the damped Hopf points there, `events` its rows of
    the precursor table at that drag."""
    onsets = sum(1 for h in hopfs if h.kind == "onset")
    strain = statistics.strain
    return {"drag": drag, "eta": eta, "strain": strain,
            "unstable_fraction": statistics.unstable_fraction[index],
            "growth_median": statistics.growth_median[index], "onsets": onsets,
            "onsets_per_disk_strain": onsets / (N * strain) if strain > 0 else None,
            "events": len(events), "preceded": sum(r["onset_gamma"] is not None for r in events),
            "active": sum(bool(r["unstable_at_event"]) for r in events),
            "gap_median": _median([r["strain_gap"] for r in events if r["strain_gap"] is not None]),
            "overlap_median": _median([r["overlap"] for r in events if r["overlap"] is not None])}


def run_rows(drag: float, found) -> list[dict]:
    """RUN_COLUMNS of every run of a causality.Causality at `drag` [omega_0], the failed ones
    (their strain only) after."""
    rows = [{"drag": drag, "gamma": float(g), "rate": float(r), "fold_gamma": None if np.isnan(f) else float(f),
             "verdict": o.verdict, "time": o.time, "distance": o.distance, "gained": o.gained, "lost": o.lost,
             "slides": o.slides, "stress_change": o.stress_change, "overlap": o.overlap}
            for g, r, f, o in zip(found.gamma, found.rates, found.folds, found.outcomes)]
    return rows + [dict.fromkeys(RUN_COLUMNS) | {"drag": drag, "gamma": g, "verdict": "failed"}
                   for g, _ in found.failed]


def wilson(k: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """Wilson's score interval for k successes in n trials (nan, nan for n = 0); its ends are 0
    and 1 exactly for k = 0 and k = n, where the formula gives them up to rounding."""
    if n == 0:
        return math.nan, math.nan
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (0.0 if k == 0 else max(0.0, centre - half)), (1.0 if k == n else min(1.0, centre + half))


def mean_interval(values: Sequence[float], z: float = Z_95) -> tuple[float, float, float]:
    """(mean, lo, hi): the mean and mean -+ z standard errors (lo = hi = mean for one value,
    nan for none)."""
    x = np.asarray([v for v in values if v is not None], dtype=float)
    if not x.size:
        return math.nan, math.nan, math.nan
    mean = float(x.mean())
    error = float(z * x.std(ddof=1) / math.sqrt(x.size)) if x.size > 1 else 0.0
    return mean, mean - error, mean + error


GROUP_COLUMNS = ("cells", "events", "preceded_fraction", "preceded_lo", "preceded_hi",
                 "active_fraction", "active_lo", "active_hi", "unstable_fraction", "unstable_lo",
                 "unstable_hi", "onsets_per_disk_strain", "onsets_lo", "onsets_hi", "gap_median",
                 "overlap_median", "chance_preceded", "chance_gap_median", "runs", "returned", "slipped", "rearranged", "saturated",
                 "failed", "rearranged_lo", "rearranged_hi", "rearranged_overlap_median")
"""precursor_groups' figures per group (after its keys and drag): the cells and events pooled;
the fractions of events preceded and active with Wilson's interval; the fraction of strain
damped-unstable (its interval clipped to [0, 1]) and the onsets per disk per unit strain, mean
and interval over the cells; the
median strain gap and overlap over the group's events; their chance baselines (precursors.chance:
the mean fraction of an event's segment preceded by an onset, the median chance gap); the damped runs from the onsets (None
where the cells ran none): how many, per verdict, the fraction rearranged with Wilson's
interval, and the median overlap of the rearranged ones' displacement with the next plastic
event's."""


def precursor_groups(cells: Sequence[tuple[dict, list[dict], list[dict], Optional[list[dict]]]],
                     keys: Sequence[str]) -> list[dict]:
    """The study's table: cells = (values, damped summaries, event rows, run rows or None) per
    finished cell (values: the cell's key -> value), grouped by the values of `keys` (the seed
    left out pools the seeds) and the drag, in order of first appearance; GROUP_COLUMNS per
    group."""
    groups: dict[tuple, list] = {}
    for values, summaries, events, runs in cells:
        for summary in summaries:
            group = tuple(values[k] for k in keys) + (summary["drag"],)
            at_drag = [r for r in events if r["drag"] == summary["drag"]]
            ran = None if runs is None else [r for r in runs if r["drag"] == summary["drag"]]
            groups.setdefault(group, []).append((summary, at_drag, ran))
    table = []
    for group, members in groups.items():
        events = [r for _, rows, _ in members for r in rows]
        ran = [r for _, _, rows in members if rows is not None for r in rows]
        counted = any(rows is not None for _, _, rows in members) and group[-1] > 0
        preceded = sum(r["onset_gamma"] is not None for r in events)
        active = sum(bool(r["unstable_at_event"]) for r in events)
        unstable = mean_interval([s["unstable_fraction"] for s, _, _ in members])
        onsets = mean_interval([s["onsets_per_disk_strain"] for s, _, _ in members])
        verdicts = {v: sum(r["verdict"] == v for r in ran) if counted else None
                    for v in ("returned", "slipped", "rearranged", "saturated", "failed")}
        judged = len(ran) - (verdicts["failed"] or 0)
        rearranged = wilson(verdicts["rearranged"], judged) if counted and judged else (None, None)
        table.append(dict(zip((*keys, "drag"), group)) | {
            "cells": len(members), "events": len(events),
            "preceded_fraction": preceded / len(events) if events else None,
            "preceded_lo": wilson(preceded, len(events))[0] if events else None,
            "preceded_hi": wilson(preceded, len(events))[1] if events else None,
            "active_fraction": active / len(events) if events else None,
            "active_lo": wilson(active, len(events))[0] if events else None,
            "active_hi": wilson(active, len(events))[1] if events else None,
            "unstable_fraction": unstable[0], "unstable_lo": max(0.0, unstable[1]),
            "unstable_hi": min(1.0, unstable[2]),
            "onsets_per_disk_strain": onsets[0], "onsets_lo": onsets[1], "onsets_hi": onsets[2],
            "gap_median": _median([r["strain_gap"] for r in events if r["strain_gap"] is not None]),
            "overlap_median": _median([r["overlap"] for r in events if r["overlap"] is not None]),
            "chance_preceded": _mean([r["chance_preceded"] for r in events if r.get("chance_preceded") is not None]),
            "chance_gap_median": _median([r["chance_gap"] for r in events if r.get("chance_gap") is not None]),
            "runs": len(ran) if counted else None, **verdicts,
            "rearranged_lo": rearranged[0], "rearranged_hi": rearranged[1],
            "rearranged_overlap_median": _median([r["overlap"] for r in ran if r["verdict"] == "rearranged"
                                                  and r["overlap"] is not None]) if counted else None})
    return table
