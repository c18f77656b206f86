"""`bifurcate PACKING_SCENE --damping D1,D2,...` (docs/packings.md#damped-stability): damped.json
and precursors.csv written with the other outputs, checked against collisions.json, branch.npz
and plastic.json beside them and against the closed form of s^2 + eta s + lambda = 0; the
refusals in one line; and the outputs without --damping as before. The runs: tests/
sheared_packing.py's 24 disks to gamma = 0.002 (no plastic event) and 16 disks (seed 3) to
0.004 (one plastic event), with full and sampled spectra."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from commandline import run_main
from sheared_packing import SCENE
from test_outputs import assert_documented, paths

from diskfriction.cli.main import main
from diskfriction.models.packing.precursors import EVENT_COLUMNS
from diskfriction.reports.packing_outputs import DAMPED_OUTPUTS, OUTPUTS

TOML = 'geometry = "packing"\nname = "{name}"\n[packing]\nN = {N}\nseed = {seed}\n' \
       '[shear]\ngamma = [0.0, {gamma}]\n'
DRAGS = (0.0, 0.01)
"""The drags [omega_0]: the undamped analysis and one below the 24-disk branch's median
critical damping (0.007 omega_0: test_packing_damped)."""


def scene_file(directory: Path, N: int, seed: int, gamma: float) -> Path:
    path = directory / f"d{N}.toml"
    path.write_text(TOML.format(name=f"d{N}", N=N, seed=seed, gamma=gamma), encoding="utf-8")
    return path


def bifurcate(scene: Path, out: Path, *options: str) -> int:
    return main(["bifurcate", str(scene), "--workers", "0", *options, "--out", str(out)])


def damping() -> tuple[str, str]:
    return "--damping", ",".join(f"{d:g}" for d in DRAGS)


def read(out: Path, name: str):
    return json.loads((out / name).read_text(encoding="utf-8"))


def unstable(eigenvalues: np.ndarray, eta: float) -> np.ndarray:
    """Per row, whether a complex pair a + i b has b^2 > eta^2 a (damped-unstable: the closed
    form, not the growth rates)."""
    lam = np.where(np.isfinite(eigenvalues), eigenvalues, 0.0)
    pairs = np.abs(lam.imag) > 1e-9 * np.abs(lam).max(axis=1, keepdims=True)
    return (pairs & (lam.imag ** 2 > eta ** 2 * lam.real)).any(axis=1)


def fastest_root(eigenvalues: np.ndarray, eta: float) -> np.ndarray:
    """Per row, max Re s over the roots of s^2 + eta s + lambda = 0, s = (-eta + sqrt(eta^2 - 4
    lambda)) / 2 (the principal root has the larger real part), every eigenvalue but the zeros
    (|lambda| <= 1e-9 max|lambda|, the translations'), one with |Im| below that taken as real."""
    rows = []
    for row in eigenvalues:
        lam = row[np.isfinite(row)].astype(complex)
        floor = 1e-9 * np.abs(lam).max()
        lam = np.where(np.abs(lam.imag) > floor, lam, lam.real)
        lam = lam[np.abs(lam) > floor]
        rows.append(((-eta + np.sqrt(eta ** 2 - 4 * lam)).real / 2).max())
    return np.array(rows)


def sheared24(tmp_path_factory, name: str, *flags: str) -> Path:
    """DIR of bifurcate on the 24-disk scene (sheared_packing.SCENE) with `flags`."""
    root = tmp_path_factory.mktemp(name)
    scene = scene_file(root, SCENE.N, SCENE.seed, SCENE.gamma_range[1])
    assert bifurcate(scene, root / "out", *flags) == 0
    return root / "out"


@pytest.fixture(scope="module")
def full24(tmp_path_factory) -> Path:
    """DIR of the 24-disk shear with --damping 0,0.01."""
    return sheared24(tmp_path_factory, "full24", *damping())


@pytest.fixture(scope="module")
def one_event(tmp_path_factory) -> tuple[Path, Path]:
    """(scene file, DIR) of 16 disks sheared through one plastic event with --damping 0,0.01."""
    root = tmp_path_factory.mktemp("one_event")
    scene = scene_file(root, 16, 3, 0.004)
    assert bifurcate(scene, root / "out", *damping()) == 0
    return scene, root / "out"


@pytest.mark.slow
def test_at_drag_zero_the_points_are_the_collisions(full24):
    """damped.json's points at drag 0 are collisions.json's collisions: their strains, a birth an
    onset and a death an end, the double real eigenvalue."""
    damped, collisions = read(full24, "damped.json"), read(full24, "collisions.json")["collisions"]
    assert damped["spectra"] == "full" and damped["sample_gamma"] is None
    assert damped["damping"] == "drag"
    assert [d["drag"] for d in damped["drags"]] == list(DRAGS)
    points = damped["drags"][0]["points"]
    assert len(collisions) > 10
    kind = {"birth": "onset", "death": "end"}
    assert [(p["gamma"], p["kind"], p["eigenvalue"]) for p in points] == [
        (c["p"], kind[c["kind"]], [c["lambda"], 0.0]) for c in collisions]


@pytest.mark.slow
def test_each_drag_is_marginal_at_its_points_and_weighs_the_unstable_strain(full24):
    """At every point s = i w: Re lambda = w^2 and Im lambda = eta w (drag 0: the collisions'
    real lambda), and it lies in its step; unstable_fraction is the strain-weighted fraction of
    branch.npz's states with a pair b^2 > eta^2 a (one segment: each state stands for half the
    steps on either side)."""
    damped = read(full24, "damped.json")
    with np.load(full24 / "branch.npz") as branch:
        gamma, eigenvalues = branch["gamma"], branch["eigenvalues"]
    assert damped["omega_0"] == SCENE.omega_0
    for record in damped["drags"]:
        eta = record["drag"] * SCENE.omega_0
        assert record["eta"] == pytest.approx(eta, rel=1e-15)
        cells = np.diff(np.concatenate([gamma[:1], 0.5 * (gamma[1:] + gamma[:-1]), gamma[-1:]]))
        fraction = np.sum(cells * unstable(eigenvalues, eta)) / (gamma[-1] - gamma[0])
        assert record["unstable_fraction"] == pytest.approx(fraction, abs=1e-12)
        for p in record["points"]:
            re, im = p["eigenvalue"]
            assert re == pytest.approx(p["frequency"] ** 2, rel=1e-12)
            # the interpolated root of a bracket <= 1e-10 wide: Im lambda moves 1.4e-8 across it
            assert im == pytest.approx(eta * p["frequency"], rel=1e-7, abs=1e-12)
            assert gamma[p["step"]] <= p["gamma"] <= gamma[p["step"] + 1]
    damped_points = damped["drags"][1]["points"]
    assert damped_points and len(damped_points) < len(damped["drags"][0]["points"])
    assert damped["drags"][1]["unstable_fraction"] < damped["drags"][0]["unstable_fraction"]


@pytest.mark.slow
def test_the_files_are_documented_and_the_table_has_its_columns(full24):
    """damped.json's keys and precursors.csv's columns as docs/outputs.md lists them; without a
    plastic event precursors.csv is its header alone."""
    assert sorted(p.name for p in full24.iterdir()) == sorted(OUTPUTS + DAMPED_OUTPUTS)
    damped = read(full24, "damped.json")
    assert_documented("damped.json (bifurcate PACKING_SCENE --damping)", paths(damped))
    assert damped["scene"] == read(full24, "collisions.json")["scene"]
    table = pd.read_csv(full24 / "precursors.csv")
    assert tuple(table.columns) == EVENT_COLUMNS and table.empty
    assert_documented("precursors.csv (bifurcate PACKING_SCENE --damping)", set(table.columns))


@pytest.mark.slow
def test_a_plastic_event_is_one_row_per_drag_with_its_last_onset(one_event):
    """One row per drag for the one plastic event: its strain and stresses as plastic.json's, its
    onset the last one of damped.json before it, at the drag's eta."""
    _, out = one_event
    (event,) = read(out, "plastic.json")["events"]
    damped = read(out, "damped.json")
    table = pd.read_csv(out / "precursors.csv")
    assert list(table["drag"]) == list(DRAGS) and (table["event"] == 0).all()
    for row, record in zip(table.to_dict("records"), damped["drags"]):
        assert (row["gamma"], row["kind"], row["sigma_xy_before"]) == (
            event["gamma"], event["kind"], event["sigma_xy_before"])
        assert row["drop"] == pytest.approx(event["drop"], rel=1e-12)
        assert row["eta"] == record["eta"]
        onsets = [p for p in record["points"]
                  if p["kind"] == "onset" and p["gamma"] < event["gamma"]]
        assert row["onset_gamma"] == onsets[-1]["gamma"]
        assert row["strain_gap"] == pytest.approx(event["gamma"] - onsets[-1]["gamma"], rel=1e-12)
        assert row["onset_frequency"] == onsets[-1]["frequency"]
        assert 0 <= row["overlap"] <= 1 and row["random_overlap"] == pytest.approx(0.25)
        assert row["unstable_at_event"] == (row["growth_at_event"] > 0)


@pytest.mark.slow
def test_without_damping_the_outputs_are_as_before(one_event, tmp_path):
    """The same shear without --damping over a copy of the damped run's DIR: OUTPUTS alone (the
    damped files removed: they described the earlier run's branch), the branch, collisions and
    plastic events the same bit for bit."""
    scene, out = one_event
    again = tmp_path / "out"
    shutil.copytree(out, again)
    assert bifurcate(scene, again) == 0
    assert sorted(p.name for p in again.iterdir()) == sorted(OUTPUTS)
    for name in ("collisions.json", "plastic.json"):
        assert (again / name).read_bytes() == (out / name).read_bytes()
    with np.load(again / "branch.npz") as a, np.load(out / "branch.npz") as b:
        assert a.files == b.files and all(
            np.array_equal(a[k], b[k], equal_nan=a[k].dtype.kind in "fc") for k in a.files)


@pytest.mark.slow
def test_sampled_spectra_give_each_samples_damped_growth_and_no_onset(tmp_path):
    """spectra sample: per drag each grid strain's fastest root of s^2 + eta s + lambda (null
    without a complex pair), points null; precursors.csv's onset columns empty."""
    out = tmp_path / "out"
    scene = scene_file(tmp_path, 16, 3, 0.004)
    assert bifurcate(scene, out, "--spectra", "sample:0.001", *damping()) == 0
    damped = read(out, "damped.json")
    with np.load(out / "branch.npz") as branch:
        sample_gamma, eigenvalues = branch["sample_gamma"], branch["sample_eigenvalues"]
    assert damped["spectra"] == "sample:0.001" and damped["sample_gamma"] == sample_gamma.tolist()
    assert_documented("damped.json (bifurcate PACKING_SCENE --damping)", paths(damped))
    for record in damped["drags"]:
        assert record["points"] is None
        expected = fastest_root(eigenvalues, record["eta"])
        growth = np.array([np.nan if g is None else g for g in record["sample_growth"]])
        np.testing.assert_allclose(growth, expected, rtol=1e-9, atol=1e-12)
        assert 0.0 <= record["unstable_fraction"] <= 1.0
    table = pd.read_csv(out / "precursors.csv")
    assert len(table) == len(DRAGS) and tuple(table.columns) == EVENT_COLUMNS
    empty = ["fold_lambda", "unstable_at_event", "growth_at_event", "onset_gamma", "strain_gap",
             "onset_frequency", "overlap"]
    assert table[empty].isna().all().all() and table["displacement"].notna().all()


REFUSED = [
    (["--damping=-1"], "'-1'"),
    (["--damping", ""], "''"),
    (["--damping", "0.1,x"], "'0.1,x'"),
    (["--damping", "0.1,0.1"], "'0.1,0.1'"),
    (["--damping", "0.1", "--matrix", "J"], "M^-1 J"),
    (["--damping", "0.1", "--spectra", "none"], "--spectra full or sample:DGAMMA"),
]


@pytest.mark.parametrize("options, says", REFUSED, ids=[" ".join(o) for o, _ in REFUSED])
def test_a_bad_damping_is_one_line_and_exit_2_before_any_work(tmp_path, options, says):
    scene = scene_file(tmp_path, SCENE.N, SCENE.seed, SCENE.gamma_range[1])
    result = run_main("bifurcate", str(scene), *options, "--out", str(tmp_path / "out"))
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr.count("\n") == 1
    assert result.stderr.startswith("bifurcate error: --damping: ")
    assert says in result.stderr and "Traceback" not in result.stderr
    assert not (tmp_path / "out").exists()


def test_a_chain_scene_refuses_damping_in_one_line(tmp_path):
    result = run_main("bifurcate", "--damping", "0.1", "--out", str(tmp_path / "out"))
    assert result.returncode == 2 and result.stderr.count("\n") == 1
    assert result.stderr.startswith("bifurcate error: --damping: ") and "'0.1'" in result.stderr
    assert "packing" in result.stderr and not (tmp_path / "out").exists()
