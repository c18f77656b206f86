"""The damped study's pooling (studies/damped_study.py): Wilson's interval against its published
values and a brute-force coverage check, and the grouping of cells' precursor rows."""
from __future__ import annotations

import math

import numpy as np
import pytest

from diskfriction.studies.damped_study import GROUP_COLUMNS, mean_interval, precursor_groups, wilson


def test_wilson_interval_against_published_values():
    """Newcombe (1998), Table I: 81/263 -> 0.2553-0.3662; 15/148 -> 0.0624-0.1605; 0/20 -> 0-0.1611."""
    assert wilson(81, 263) == pytest.approx((0.2553, 0.3662), abs=5e-5)
    assert wilson(15, 148) == pytest.approx((0.0624, 0.1605), abs=5e-5)
    assert wilson(0, 20) == pytest.approx((0.0, 0.1611), abs=5e-5)
    assert all(math.isnan(x) for x in wilson(0, 0))
    for n in range(1, 200):  # none and all: the ends exactly, not up to rounding
        assert wilson(0, n)[0] == 0.0 and wilson(n, n)[1] == 1.0


def test_wilson_covers_the_true_fraction_about_95_percent_of_the_time():
    rng = np.random.default_rng(7)
    p, n = 0.3, 60
    hits = [lo <= p <= hi for lo, hi in (wilson(int(k), n) for k in rng.binomial(n, p, 4000))]
    assert 0.93 <= np.mean(hits) <= 0.97


def test_mean_interval():
    mean, lo, hi = mean_interval([1.0, 2.0, 3.0, None])
    assert mean == 2.0 and hi - mean == pytest.approx(1.959963984540054 / math.sqrt(3))
    assert mean_interval([4.0]) == (4.0, 4.0, 4.0)


def row(drag, onset, active, gap=None, overlap=None):
    return {"drag": drag, "onset_gamma": onset, "unstable_at_event": active, "strain_gap": gap,
            "overlap": overlap, "chance_preceded": 0.5 if onset else 0.0, "chance_gap": gap and 2 * gap}


def run(drag, verdict, overlap):
    return {"drag": drag, "verdict": verdict, "overlap": overlap}


def summary(drag, unstable, onsets):
    return {"drag": drag, "unstable_fraction": unstable, "onsets_per_disk_strain": onsets}


def test_groups_pool_seeds_and_split_drags():
    cells = [({"mu": 1.0, "seed": 1}, [summary(0.0, 0.8, 3.0), summary(0.1, 0.2, 1.0)],
              [row(0.0, 0.01, True, 0.001, 0.5), row(0.1, None, False)],
              [run(0.1, "rearranged", 0.9), run(0.1, "slipped", 0.2)]),
             ({"mu": 1.0, "seed": 2}, [summary(0.0, 0.6, 5.0), summary(0.1, 0.1, 0.5)],
              [row(0.0, 0.02, True, 0.003, 0.3), row(0.0, 0.03, False, 0.002, 0.1),
               row(0.1, 0.02, True, 0.004, 0.2), row(0.1, None, False)],
              [run(0.1, "rearranged", 0.7), run(0.1, "failed", None)])]
    groups = precursor_groups(cells, ["mu"])
    assert [(g["mu"], g["drag"], g["cells"], g["events"]) for g in groups] == [(1.0, 0.0, 2, 3),
                                                                                (1.0, 0.1, 2, 3)]
    undamped, damped = groups
    assert undamped["preceded_fraction"] == 1.0 and undamped["active_fraction"] == 2 / 3
    assert (undamped["preceded_lo"], undamped["preceded_hi"]) == wilson(3, 3)
    assert damped["preceded_fraction"] == 1 / 3 and damped["gap_median"] == 0.004
    assert undamped["gap_median"] == 0.002 and undamped["overlap_median"] == 0.3
    assert undamped["chance_preceded"] == 0.5 and undamped["chance_gap_median"] == 0.004
    assert damped["chance_preceded"] == pytest.approx(1 / 6)
    assert undamped["unstable_fraction"] == pytest.approx(0.7) and damped["onsets_per_disk_strain"] == 0.75
    assert set(GROUP_COLUMNS) <= set(undamped)
    assert undamped["runs"] is None and undamped["rearranged"] is None  # no run at drag 0
    assert (damped["runs"], damped["rearranged"], damped["slipped"], damped["failed"]) == (4, 2, 1, 1)
    assert (damped["rearranged_lo"], damped["rearranged_hi"]) == wilson(2, 3)
    assert damped["rearranged_overlap_median"] == pytest.approx(0.8)


def test_run_rows_hold_every_run_and_the_failed_ones():
    from diskfriction.models.packing.causality import Causality, Outcome
    from diskfriction.studies.damped_study import RUN_COLUMNS, run_rows

    outcome = Outcome("rearranged", 12.0, 3e-3, np.zeros(9), 1, 2, 40, 1e-9, -0.05, 0.97)
    found = Causality(0.5, np.array([4]), np.array([0.002]), np.array([0.3]), np.array([np.nan]),
                      (outcome,), ((0.003, "FIRE stopped"),))
    rows = run_rows(0.05, found)
    assert [tuple(r) for r in rows] == [RUN_COLUMNS, RUN_COLUMNS]
    assert rows[0] | {} == {"drag": 0.05, "gamma": 0.002, "rate": 0.3, "fold_gamma": None,
                            "verdict": "rearranged", "time": 12.0, "distance": 3e-3, "gained": 1,
                            "lost": 2, "slides": 40, "stress_change": -0.05, "overlap": 0.97}
    assert rows[1]["verdict"] == "failed" and rows[1]["gamma"] == 0.003 and rows[1]["rate"] is None
