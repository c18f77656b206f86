"""The study's files beside a packing map (reports/packing_study.py): every row of every cell,
the pooled table over the seeds, and the figure."""
from __future__ import annotations

import pandas as pd

from diskfriction.models.packing.precursors import EVENT_COLUMNS
from diskfriction.reports.packing_study import save_study
from diskfriction.studies.damped_study import DAMPED_COLUMNS, GROUP_COLUMNS, RUN_COLUMNS
from diskfriction.studies.maps import Axis, Cell


def event(drag, onset):
    row = dict.fromkeys(EVENT_COLUMNS)
    return row | {"event": 0, "kind": "fold", "drag": drag, "onset_gamma": onset,
                  "unstable_at_event": onset is not None, "strain_gap": None if onset is None else 1e-4,
                  "chance_preceded": 0.5}


def damped(drag, unstable):
    return dict.fromkeys(DAMPED_COLUMNS) | {"drag": drag, "unstable_fraction": unstable,
                                            "onsets_per_disk_strain": 2.0}


def test_the_files_hold_every_cell_and_pool_the_seeds(tmp_path):
    axes = [Axis("contacts.mu", (0.3, 10.0)), Axis("packing.seed", (1, 2))]
    cells, records = [], []
    for i, mu in enumerate((0.3, 10.0)):
        for j, seed in enumerate((1, 2)):
            cells.append(Cell((i, j), (("contacts.mu", mu), ("packing.seed", seed)), None))
            records.append({"summary": {}, "damped": [damped(0.0, 0.9), damped(0.1, 0.2)],
                            "events": [event(0.0, 0.001), event(0.1, 0.001 if (mu, seed) == (0.3, 1) else None),
                                       event(0.0, 0.002), event(0.1, None)]})
    records[0]["runs"] = [dict.fromkeys(RUN_COLUMNS) | {"drag": 0.1, "gamma": 0.002, "verdict": "rearranged",
                                                        "overlap": 0.9}]
    records[-1] = {"summary": {"status": "failed"}, "damped": [], "events": []}  # a failed cell
    names = save_study(tmp_path, axes, cells, records)
    assert all((tmp_path / name).exists() for name in names)
    events = pd.read_csv(tmp_path / "events.csv")
    assert list(events.columns) == ["contacts.mu", "packing.seed", *EVENT_COLUMNS] and len(events) == 12
    assert len(pd.read_csv(tmp_path / "damped.csv")) == 6
    runs = pd.read_csv(tmp_path / "runs.csv")
    assert len(runs) == 1 and runs["verdict"].tolist() == ["rearranged"] and "runs.csv" in names
    pooled = pd.read_csv(tmp_path / "precursors.csv")
    assert list(pooled.columns) == ["contacts.mu", "drag", *GROUP_COLUMNS]
    assert pooled[["contacts.mu", "drag", "cells", "events"]].values.tolist() == [
        [0.3, 0.0, 2, 4], [0.3, 0.1, 2, 4], [10.0, 0.0, 1, 2], [10.0, 0.1, 1, 2]]
    assert pooled["preceded_fraction"].tolist() == [1.0, 0.25, 1.0, 0.0]  # none preceded: drawn too
