"""`bifurcate PACKING_SCENE --damping D1,D2,... --dashpots` (docs/packings.md#contact-dashpots):
damped.json's points are contact_onsets.contact_hopfs' on the same branch, its unstable_fraction
the strain-weighted fraction of states whose largest growth rate (contact_damping.damped_spectrum
at each state, evaluated here) is clearly positive, and precursors.csv's growth at the event that
rate at the last state before it; any spectra and matrix serve (only the states are read); the
refusals in one line. The runs: tests/sheared_packing.py's 24 disks to gamma = 0.002 (no plastic
event; its branch is the session's `sheared` fixture's) and 16 disks (seed 3) to 0.004 (one
plastic event), as tests/reports/test_damped_outputs.py's."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from commandline import run_main
from sheared_packing import SCENE
from test_damped_outputs import bifurcate, read, scene_file, sheared24
from test_outputs import assert_documented, paths

from diskfriction.continuation.linalg.solves import blas_threads
from diskfriction.models.packing.contact_damping import ContactDamping, damped_spectrum
from diskfriction.models.packing.contact_onsets import contact_hopfs
from diskfriction.models.packing.damped import problem_at
from diskfriction.models.packing.equilibria import mass_diagonal
from diskfriction.models.packing.precursors import EVENT_COLUMNS
from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.shear import ShearParams, network_of, shear
from diskfriction.scenes.packing import PackingScene

RATES = (0.002, 0.01)
"""The dashpots' rates [omega_0]: 0.002 loses and regains damped stability on the 24-disk branch
(three points), 0.01 twice (test_contact_onsets)."""

ONE_EVENT = PackingScene(name="d16", N=16, seed=3, gamma_range=(0.0, 0.004))
"""test_damped_outputs' scene with one plastic event (its scene file's fields)."""


def dashpots(*rates: float) -> tuple[str, ...]:
    return "--damping", ",".join(f"{r:g}" for r in rates or RATES), "--dashpots"


def growth_and_scale(network, mass, branch, k: int, rate: float) -> tuple[float, float]:
    """(max Re s, max |s|) of state k with dashpots of `rate` omega_0 on its contacts, solved here
    from the state (damped_spectrum), on one BLAS thread as the command's own."""
    with blas_threads():
        spectrum = damped_spectrum(problem_at(network, mass, branch, k), branch.u[k],
                                   float(branch.p[k]), ContactDamping(rate * SCENE.omega_0))
    return spectrum.growth, float(np.abs(spectrum.exponents).max())


def strain_cells(gamma: np.ndarray) -> np.ndarray:
    """The strain each state of one segment stands for: half the steps on either side."""
    return np.diff(np.concatenate([gamma[:1], 0.5 * (gamma[1:] + gamma[:-1]), gamma[-1:]]))


@pytest.fixture(scope="module")
def network(sheared):
    packing, branch, _ = sheared(SCENE)
    net = network_of(SCENE, packing)
    return net, mass_diagonal(net, SCENE.m, SCENE.inertia), branch


@pytest.fixture(scope="module")
def dashpots24(tmp_path_factory) -> Path:
    """DIR of the 24-disk shear (spectra full) with --damping 0.002,0.01 --dashpots."""
    return sheared24(tmp_path_factory, "dashpots24", *dashpots())


def same_branch(out: Path, branch) -> None:
    """branch.npz in `out` holds the states of `branch`, bit for bit."""
    with np.load(out / "branch.npz") as saved:
        assert np.array_equal(saved["gamma"], branch.p)
        assert np.array_equal(saved["q"], branch.u)


@pytest.mark.slow
def test_the_points_are_contact_hopfs_on_the_same_branch(dashpots24, network):
    """damped.json (damping "dashpots") holds, per rate, contact_hopfs' points on the session's
    branch of the same scene: strain, kind, step and bracket bit for bit, the frequency, no
    eigenvalue, each found by refinement; and its keys are the documented ones."""
    net, mass, branch = network
    same_branch(dashpots24, branch)
    damped = read(dashpots24, "damped.json")
    assert damped["damping"] == "dashpots" and damped["spectra"] == "full"
    assert damped["sample_gamma"] is None
    assert_documented("damped.json (bifurcate PACKING_SCENE --damping)", paths(damped))
    assert [d["drag"] for d in damped["drags"]] == list(RATES)
    for record in damped["drags"]:
        eta = record["drag"] * SCENE.omega_0
        assert record["eta"] == pytest.approx(eta, rel=1e-15) and record["sample_growth"] is None
        theirs = contact_hopfs(net, mass, branch, ContactDamping(eta))
        assert theirs, "each rate loses damped stability somewhere on the branch"
        assert [(p["gamma"], p["kind"], p["step"], tuple(p["bracket"])) for p in record["points"]] == [
            (h.gamma, h.kind, h.step, h.bracket) for h in theirs]
        for p, h in zip(record["points"], theirs):
            assert p["eigenvalue"] is None and p["found"] == "refined"
            assert p["frequency"] == pytest.approx(h.frequency, rel=1e-12)


@pytest.mark.slow
def test_the_unstable_fraction_weighs_the_states_that_grow(dashpots24, network):
    """unstable_fraction per rate: the strain-weighted fraction (one segment: each state stands
    for half the steps on either side, from branch.npz's gamma) of the states whose largest
    growth rate, solved here at each state, exceeds 1e-9 of its largest |s|. It lies strictly
    between 0 and 1, and falls as the rate rises."""
    net, mass, branch = network
    with np.load(dashpots24 / "branch.npz") as saved:
        gamma = saved["gamma"]
    cells = strain_cells(gamma)
    fractions = []
    for record in read(dashpots24, "damped.json")["drags"]:
        rates = [growth_and_scale(net, mass, branch, k, record["drag"]) for k in range(len(gamma))]
        grows = np.array([g > 1e-9 * scale for g, scale in rates])
        fraction = np.sum(cells * grows) / (gamma[-1] - gamma[0])
        assert 0 < fraction < 1
        assert record["unstable_fraction"] == pytest.approx(fraction, abs=1e-12)
        fractions.append(fraction)
    assert fractions[1] < fractions[0]


@pytest.mark.slow
def test_without_spectra_and_with_the_matrix_j_the_points_are_the_same(dashpots24, network,
                                                                        tmp_path):
    """--spectra none --matrix J: the same states (branch.npz) and the same damped.json points
    and fractions as with spectra full (the dashpots read only the states); spectra "none"."""
    _, _, branch = network
    scene = scene_file(tmp_path, SCENE.N, SCENE.seed, SCENE.gamma_range[1])
    out = tmp_path / "out"
    assert bifurcate(scene, out, "--spectra", "none", "--matrix", "J", *dashpots(RATES[0])) == 0
    same_branch(out, branch)
    damped, full = read(out, "damped.json"), read(dashpots24, "damped.json")
    assert damped["spectra"] == "none" and damped["damping"] == "dashpots"
    assert damped["drags"] == full["drags"][:1]


@pytest.mark.slow
def test_a_plastic_events_growth_is_the_dashpots_at_its_last_state(tmp_path):
    """The 16-disk shear through one plastic event: per rate, growth_at_event is the largest
    growth rate solved here at the last state before the event (the same branch, sheared again),
    unstable_at_event its sign, and the onset columns the last onset of damped.json before it."""
    out = tmp_path / "out"
    assert bifurcate(scene_file(tmp_path, ONE_EVENT.N, ONE_EVENT.seed, ONE_EVENT.gamma_range[1]),
                     out, *dashpots()) == 0
    packing = prepare_scene(ONE_EVENT)
    branch = shear(ONE_EVENT, packing, ShearParams(workers=0), plastic_events=1000)
    same_branch(out, branch)
    net = network_of(ONE_EVENT, packing)
    mass = mass_diagonal(net, ONE_EVENT.m, ONE_EVENT.inertia)
    (event,) = read(out, "plastic.json")["events"]
    last = int(np.flatnonzero(branch.segment == 0)[-1])
    table = pd.read_csv(out / "precursors.csv")
    assert tuple(table.columns) == EVENT_COLUMNS and list(table["drag"]) == list(RATES)
    for row, record in zip(table.to_dict("records"), read(out, "damped.json")["drags"]):
        with blas_threads():
            growth = damped_spectrum(problem_at(net, mass, branch, last), branch.u[last],
                                     float(branch.p[last]),
                                     ContactDamping(record["eta"])).growth
        assert row["growth_at_event"] == growth
        assert row["unstable_at_event"] == (growth > 0)
        onsets = [p for p in record["points"] if p["kind"] == "onset" and p["gamma"] < event["gamma"]]
        if onsets:
            assert row["onset_gamma"] == onsets[-1]["gamma"]
            assert row["onset_frequency"] == onsets[-1]["frequency"]
            assert 0 <= row["overlap"] <= 1
        else:
            assert np.isnan(row["onset_gamma"]) and np.isnan(row["overlap"])
    assert not np.isnan(table["fold_lambda"]).any()


REFUSED = [
    (["--dashpots"], "--dashpots: only with --damping"),
    (["--damping", "0,0.01", "--dashpots"], "'0,0.01'"),
]


@pytest.mark.parametrize("options, says", REFUSED, ids=[" ".join(o) for o, _ in REFUSED])
def test_dashpots_without_a_rate_are_one_line_and_exit_2_before_any_work(tmp_path, options, says):
    """--dashpots without --damping, and a rate 0 (no damping: the undamped analysis is the
    drag 0's), are refused before any work."""
    scene = scene_file(tmp_path, SCENE.N, SCENE.seed, SCENE.gamma_range[1])
    result = run_main("bifurcate", str(scene), *options, "--out", str(tmp_path / "out"))
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr.count("\n") == 1
    assert result.stderr.startswith("bifurcate error: --dashpots: ") and says in result.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("options, flag", [(["--dashpots"], "--dashpots"),
                                           (["--damping", "0.1", "--dashpots"], "--damping")])
def test_a_chain_scene_refuses_dashpots_in_one_line(tmp_path, options, flag):
    result = run_main("bifurcate", *options, "--out", str(tmp_path / "out"))
    assert result.returncode == 2 and result.stderr.count("\n") == 1
    assert result.stderr.startswith(f"bifurcate error: {flag}: ")
    assert "Traceback" not in result.stderr and not (tmp_path / "out").exists()
