"""Maps of packing scenes (issue 25 item 5): the packing's numeric keys, one cell against
bifurcate on the same scene, a cell's summary per unit strain (issue 63 item 2), a cell that ends
at a plastic event says so, and the options a packing map does not take are refused in one
line."""
from __future__ import annotations

import json

import numpy as np
import pytest
from commandline import error_line, run_cli, run_main

from diskfriction.continuation.branch import Branch, Piece, Stop, StopCode
from diskfriction.continuation.detection.detectors.base import Collision
from diskfriction.continuation.spectra.tracking import Kind, count_complex_pairs
from diskfriction.models.packing.plastic import PlasticEvent
from diskfriction.scenes.load import SceneError, number_keys, with_values
from diskfriction.scenes.packing import PackingScene
from diskfriction.studies.packing_maps import PACKING_COLUMNS, PackingMapParams, branch_summary, packing_cell

SMALL = 'geometry = "packing"\nname = "small"\n[packing]\nN = 16\n[shear]\ngamma = [0.0, 0.002]\n'
"""16 disks to gamma = 0.002: some 30 states, complex pairs, one plastic event at mu = 10."""


def test_a_packing_map_varies_the_packing_keys_that_hold_one_number():
    keys = number_keys("packing")
    assert keys["packing.N"] is int and keys["packing.seed"] is int
    assert keys["packing.pressure"] is float and keys["contacts.mu"] is float
    assert "shear.gamma" not in keys and "disks.eps" not in keys and "name" not in keys
    assert "disks.eps" in number_keys()  # the chain's own


def test_a_packing_cell_scene_is_checked_as_a_file_would_be():
    base = PackingScene(name="base", source="base.toml")
    cell = with_values(base, {"contacts.mu": 0.3, "packing.seed": 4}, "base.toml")
    assert (cell.mu, cell.seed, cell.N) == (0.3, 4, base.N)
    assert (cell.name, cell.source) == ("base", "base.toml")
    with pytest.raises(SceneError) as raised:
        with_values(base, {"packing.N": 2.5}, "base.toml")
    assert raised.value.key == "packing.N" and "integer" in raised.value.what
    with pytest.raises(SceneError) as raised:
        with_values(base, {"disks.eps": 0.01}, "base.toml")
    assert raised.value.key == "disks.eps"


def trapezoid_fraction(gamma: np.ndarray, segment: np.ndarray, on: np.ndarray) -> float:
    """The fraction of the strain where `on` holds, each state standing for half its steps to
    its neighbours within its segment (labels per state)."""
    held = total = 0.0
    for label in np.unique(segment):
        g, o = gamma[segment == label], on[segment == label]
        steps = np.diff(g)
        held += 0.5 * float(np.sum(steps * o[1:]) + np.sum(steps * o[:-1]))
        total += float(g[-1] - g[0])
    return held / total


def toy_branch(matrix: str) -> Branch:
    """Two disks' branch of two segments, the states crowded at gamma 0.001-0.0012 where the
    pair 1 +- i b sits, a plastic event (sigma_xy 2 -> 1.5) between the segments, three
    collisions."""
    gamma = 0.01 * np.array([0.0, 0.1, 0.11, 0.12, 1.0, 1.5, 2.0])
    b = np.array([0.0, 0.5, 0.2, 1.0, 0.0, 0.0, 0.0])
    eigenvalues = np.array([[0, 1, 1 + 1j * x, 1 - 1j * x] for x in b])
    stop = Stop(StopCode.REACHED)
    collision = Collision(5e-4, Kind.BIRTH, 1.0, np.zeros(4), np.zeros(4), 0.0, (5e-4, 5e-4), 0.0,
                          np.zeros(6), 0, (2, 3))
    stress = np.zeros((7, 4))
    stress[:, 2] = [1.0, 1.2, 1.4, 1.6, 2.0, 1.5, 1.7]
    n_complex = np.array([count_complex_pairs(e) for e in eigenvalues])
    return Branch(gamma, np.zeros((7, 6)), eigenvalues, n_complex, np.zeros(7), (collision,) * 3, stop,
                  pieces=(Piece("segment", 0, 0, 5, stop), Piece("segment", 1, 5, 7, stop)),
                  labelled={"plastic": (PlasticEvent(0.01, 2.0, 1.5, 0.1, 10),)}, columns={"stress": stress},
                  parameter="gamma", matrix=matrix)


def test_a_cells_summary_is_per_unit_strain_not_per_state():
    """Cells of strain 0.05, 0.055, 0.01, 0.445, 0.44 | 0.25, 0.25 (times 0.01; 1.5 in all, the
    plastic event's jump 0.5 left out): the pair over 0.51 of it, where 3 of 7 states hold one."""
    scene = PackingScene(gamma_range=(0.0, 0.02))  # its omega_c; the disks are the branch's
    summary = branch_summary(scene, toy_branch("M^-1 J"))
    assert set(summary) == set(PACKING_COLUMNS) - {"wall_time"}
    assert summary["complex_fraction"] == pytest.approx(0.51 / 1.5, rel=1e-12)
    assert summary["pairs_mean"] == pytest.approx(0.51 / 1.5, rel=1e-12)
    assert summary["collisions_per_disk_strain"] == pytest.approx(3 / (2 * 0.015), rel=1e-12)
    sigma = np.abs(np.sqrt(1 + 1j * np.array([0.2, 0.5, 1.0])).imag)  # in order, weights 0.01, 0.055, 0.445
    middle = (np.array([0.005, 0.0375, 0.2875]) / 0.51)  # each one's cumulative weight at its middle
    assert summary["sigma_median"] == pytest.approx(
        sigma[1] + (sigma[2] - sigma[1]) * (0.5 - middle[1]) / (middle[2] - middle[1]), rel=1e-12)
    assert summary["sigma_max"] == pytest.approx(sigma[2], rel=1e-12)
    assert summary["states"] == 7 and summary["collisions"] == 3 and summary["plastic_events"] == 1
    assert summary["max_drop"] == 0.25 and summary["sigma_xy_end"] == 1.7 and summary["status"] == "ok"
    of_J = branch_summary(scene, toy_branch("J"))
    assert of_J["sigma_median"] is None and of_J["sigma_max"] is None
    assert of_J["complex_fraction"] == summary["complex_fraction"]


@pytest.mark.slow
def test_a_packing_map_of_one_cell_equals_bifurcate_on_the_same_scene(tmp_path):
    scene = tmp_path / "small.toml"
    scene.write_text(SMALL)
    alone = run_cli("bifurcate", str(scene), "--out", str(tmp_path / "b"))
    mapped = run_cli("map", str(scene), "--vary", "contacts.mu=10:10:1", "--workers", "1",
                     "--out", str(tmp_path / "m"))
    assert alone.returncode == 0 and mapped.returncode == 0, alone.stderr + mapped.stderr
    assert "1 cell: prepare and shear gamma 0 -> 0.002" in mapped.stderr
    collisions = json.loads((tmp_path / "b" / "collisions.json").read_text())["collisions"]
    branch = np.load(tmp_path / "b" / "branch.npz")
    (cell,) = (tmp_path / "m" / "cells").glob("*.json")
    cell = json.loads(cell.read_text())
    assert collisions and cell["collisions"] == collisions  # the same run, bit for bit
    import pandas

    table = pandas.read_csv(tmp_path / "m" / "map.csv")
    assert list(table.columns) == ["contacts.mu", *PACKING_COLUMNS] and len(table) == 1
    row = table.iloc[0]
    assert row["status"] == "ok" and row["gamma_end"] == branch["gamma"][-1]
    assert row["states"] == branch["gamma"].size and row["collisions"] == len(collisions)
    on = branch["n_complex"] > 0
    per_strain = trapezoid_fraction(branch["gamma"], branch["segment"], on)
    assert row["complex_fraction"] == pytest.approx(per_strain, rel=1e-12)
    assert row["collisions_per_disk_strain"] == pytest.approx(
        len(collisions) / (16 * sum(np.ptp(branch["gamma"][branch["segment"] == s])
                                    for s in np.unique(branch["segment"]))), rel=1e-12)
    assert row["plastic_events"] == branch["plastic_gamma"].size
    assert row["sigma_xy_end"] == branch["stress"][-1, 2]
    assert 0 < row["sigma_median"] <= row["sigma_max"] < row["omega_c"]
    assert "contacts.mu = 10: ok to gamma = 0.002" in mapped.stdout
    assert (tmp_path / "m" / "map.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.slow
def test_a_cell_that_may_pass_no_plastic_event_ends_at_the_first_and_says_so():
    scene = PackingScene(N=16, gamma_range=(0.0, 0.002))
    record = packing_cell(scene, PackingMapParams("M^-1 J", plastic_events=0))
    summary = record["summary"]
    assert summary["status"] == "ended" and summary["plastic_events"] == 0
    assert 0 < summary["gamma_end"] < 0.002
    assert summary["reason"].startswith(f"shear ended at gamma = {summary['gamma_end']:.9g}")
    assert "plastic event" in summary["reason"] and summary["wall_time"] > 0


BAD = [
    (["--fx", "0:1"], "--fx: a packing's load is its strain"),
    (["--slide"], "--slide: a packing map runs no dynamics"),
    (["--amplitude", "1e-9"], "--amplitude: a packing map runs no dynamics"),
    (["--window", "3:1"], "--window: expected LO:HI"),
    (["--vary", "disks.eps=0:0.01:2"], "disks.eps is no scene key of a packing"),
    (["--vary", "shear.gamma=0:0.01:2"], "shear.gamma is not a numeric scene key of a packing"),
    (["--vary", "packing.N=16:17:3"], "cell packing.N = 16.5: expected an integer"),
    (["--vary", "shear.damping=0.1:2:3"], "shear.damping acts only where [shear] relaxation = \"damped\""),
    (["--damping", "0,-1"], "--damping: expected D1,D2,... with numbers >= 0"),
    (["--damping", "0.1", "--matrix", "J"], "--damping: the damped modes"),
    (["--causality"], "--causality: runs the dynamics from the damped onsets; add --damping"),
    (["--vary", "packing.pressure=1e-300:1e-299:2"],
     "cell packing.pressure = 1e-300: packing.pressure: the preparation relaxes first"),
]


@pytest.mark.parametrize("args, says", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_a_packing_map_refuses_what_it_does_not_take_in_one_line(tmp_path, args, says):
    scene = tmp_path / "small.toml"
    scene.write_text(SMALL)
    vary = [] if "--vary" in args else ["--vary", "contacts.mu=1:10:2"]
    result = run_main("map", str(scene), *vary, *args, "--out", str(tmp_path / "out"))
    assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
    assert says in error_line(result, "map")
    assert not (tmp_path / "out").exists()


def test_a_chain_map_refuses_a_window(tmp_path):
    result = run_main("map", "--vary", "contacts.mu=1:10:2", "--window=-1:1",
                      "--out", str(tmp_path / "out"))
    assert result.returncode == 2 and "--window: for packing scenes only" in error_line(result, "map")


@pytest.mark.slow
def test_a_damped_cell_tables_its_plastic_event_at_every_drag():
    """32 disks, seed 2, to gamma = 0.0021 (one fold: tests/models/packing/test_packing_plastic.py)
    at the drags 0 and 0.05 omega_0: one precursor row per drag, the summaries counting them, the
    undamped onsets the births located, and a record that JSON holds strictly (no nan, no inf)."""
    scene = PackingScene(N=32, seed=2, gamma_range=(0.0, 0.0021))
    record = packing_cell(scene, PackingMapParams("M^-1 J", damping=(0.0, 0.05)))
    undamped, damped = record["damped"]
    assert [s["drag"] for s in record["damped"]] == [0.0, 0.05]
    assert [r["drag"] for r in record["events"]] == [0.0, 0.05] and record["summary"]["plastic_events"] == 1
    assert undamped["events"] == damped["events"] == 1
    assert undamped["onsets"] == sum(c["kind"] == "birth" for c in record["collisions"])
    assert damped["onsets"] < undamped["onsets"] and 0 < damped["unstable_fraction"] < undamped["unstable_fraction"]
    assert undamped["unstable_fraction"] == pytest.approx(record["summary"]["complex_fraction"], abs=1e-12)
    json.dumps(record, allow_nan=False)


@pytest.mark.slow
def test_a_damped_map_writes_the_study_beside_the_map(tmp_path):
    """Two seeds at mu = 0 (frictionless: no pair, the baseline) and mu = 10, 16 disks to gamma =
    0.002, drags 0 and 0.05: the study's files hold every cell, pool the two seeds, and the
    frictionless cells have no onset."""
    import pandas

    scene = tmp_path / "small.toml"
    scene.write_text(SMALL)
    mapped = run_cli("map", str(scene), "--vary", "contacts.mu=0,10", "--vary", "packing.seed=1,2",
                     "--damping", "0,0.05", "--workers", "1", "--out", str(tmp_path / "m"))
    assert mapped.returncode == 0, mapped.stderr
    assert "the damped study at 2 drags" in mapped.stderr
    out = tmp_path / "m"
    cells = [json.loads(p.read_text()) for p in (out / "cells").glob("*.json")]
    damped = pandas.read_csv(out / "damped.csv")
    assert len(damped) == 8 and list(damped.columns[:3]) == ["contacts.mu", "packing.seed", "drag"]
    assert (damped[damped["contacts.mu"] == 0]["onsets"] == 0).all()
    events = pandas.read_csv(out / "events.csv")
    assert len(events) == 2 * sum(c["summary"]["plastic_events"] for c in cells)
    pooled = pandas.read_csv(out / "precursors.csv")
    assert pooled[["contacts.mu", "drag", "cells"]].values.tolist() == [[0, 0, 2], [0, 0.05, 2],
                                                                         [10, 0, 2], [10, 0.05, 2]]
    assert (out / "precursors.png").read_bytes()[:4] == b"\x89PNG"
