"""Maps of packing scenes (issue 25 item 5): the packing's numeric keys, one cell against
bifurcate on the same scene, a cell that ends at a plastic event says so, and the options a
packing map does not take are refused in one line."""
from __future__ import annotations

import json

import numpy as np
import pytest
from commandline import error_line, run_cli, run_main

from diskfriction.scenes.load import SceneError, number_keys, with_values
from diskfriction.scenes.packing import PackingScene
from diskfriction.studies.packing_maps import PACKING_COLUMNS, PackingMapParams, packing_cell

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
    assert row["complex_fraction"] == np.mean(branch["n_complex"] > 0)
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
