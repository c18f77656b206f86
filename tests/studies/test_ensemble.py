"""Ensembles: front speeds, the V_cm fit, resuming, and the simulate / verify commands."""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from commandline import run_cli, run_main

from diskfriction.studies.ensemble import (EnsembleMismatch, RunSpec, pending, aggregate, breach_speed,
                                           check_directory, code_version, front_slope,
                                           parameters, run_ensemble, sliding_speed)
from diskfriction.scenes import Scene


def synthetic(V1, V2, V_cm, N=10, slid=True, accurate=True):
    """A summary whose breach front runs forward at V1 and sliding front backward at V2."""
    x = np.arange(N) + 0.5
    return {"first_breach": {"t": list(x / V1), "x": list(x)},
            "onset": {"t": list((N - x) / V2), "x": list(x)}, "V_cm": V_cm,
            "slid": slid if accurate else None, "accurate": accurate}


def test_front_speeds_and_centre_of_mass_fit_are_recovered():
    summaries = {F: [synthetic(0.1 + F, 2.0, -1e-3 + 0.03 * F + e) for e in (-1e-5, 1e-5)]
                 for F in (0.08, 0.09, 0.10)}
    ens = aggregate(summaries)
    assert ens.V1[0.09].value == pytest.approx(0.19) and ens.V1[0.09].n == 2
    assert ens.V2.value == pytest.approx(2.0) and ens.V2.n == 6
    a, b = ens.V_cm_fit
    assert a.value == pytest.approx(-1e-3, abs=1e-12) and b.value == pytest.approx(0.03)


def test_realizations_whose_budget_does_not_close_are_left_out_of_the_aggregates():
    """An unresolved run (summary accurate false, slid None) carries no fronts or V_cm."""
    good = [synthetic(0.2, 2.0, 1e-3)]
    ens = aggregate({0.09: good + [synthetic(50.0, 90.0, 7.0, accurate=False)]})
    assert ens.V1[0.09].n == 1 and ens.V1[0.09].value == pytest.approx(0.2)
    assert ens.V2.n == 1 and ens.V_cm[0.09].value == pytest.approx(1e-3)


def test_fronts_need_three_disks_and_missing_values_are_skipped():
    assert front_slope([1.0, None and 0, np.nan], [1, 2, 3]) is None
    s = synthetic(0.5, 1.0, 0.0)
    s["first_breach"]["t"][3] = None
    assert breach_speed(s) == pytest.approx(0.5)
    assert sliding_speed(s) == pytest.approx(1.0)


@pytest.fixture(scope="module")
def scheduler():
    """The address of one local dask cluster for the three ensembles of the resume test (the
    scheduler a run may be given, as --scheduler does): a cluster of each run's own costs ~2-4 s
    to start and warm its workers, against 0.1 s for the realizations themselves. The local
    cluster each command starts is exercised by test_outputs and test_commands."""
    import logging

    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=logging.CRITICAL) as cluster:
        yield cluster.scheduler_address


@pytest.mark.slow
def test_resumed_ensemble_equals_an_uninterrupted_one(tmp_path, scheduler):
    """Run 1 realization, then rerun asking for 3: the first is reused from disk, and the
    result equals a run of 3 in one go (the integrator is deterministic). F_x = 0.087 on the
    paper's scene breaches and slides within t = 150, so the fronts are real numbers."""
    scene = Scene()
    kw = dict(t_end=150.0, amplitude=1e-5, scheduler=scheduler)
    whole = run_ensemble(scene, [0.087], 3, out=tmp_path / "whole", **kw)
    assert whole.V1[0.087].n == 3 and whole.V2.n == 3
    run_ensemble(scene, [0.087], 1, out=tmp_path / "resumed", **kw)
    first = sorted((tmp_path / "resumed" / "runs").rglob("*.json"))
    stamp = first[0].stat().st_mtime_ns
    todo, done = pending(scene, [0.087], 3, RunSpec(150.0, 1e-5), tmp_path / "resumed")
    assert [spec.seed for _, spec, _ in todo] == [1, 2] and len(done[0.087]) == 1
    resumed = run_ensemble(scene, [0.087], 3, out=tmp_path / "resumed", **kw)
    assert first[0].stat().st_mtime_ns == stamp
    assert resumed.as_dict() == whole.as_dict()
    record = json.loads((tmp_path / "resumed" / "ensemble.json").read_text())
    assert record == json.loads((tmp_path / "whole" / "ensemble.json").read_text())
    assert {k: record["parameters"][k] for k in ("t_end", "amplitude", "kind", "loads", "seeds")} \
        == {"t_end": 150.0, "amplitude": 1e-5, "kind": "random-velocity", "loads": [0.087],
            "seeds": [0, 2]}
    assert record["parameters"]["code"] == code_version()
    key = lambda s: json.dumps(s, sort_keys=True)
    assert sorted(map(key, resumed.summaries[0.087])) == sorted(map(key, whole.summaries[0.087]))


def test_an_ensemble_says_how_long_its_missing_runs_take_before_it_starts(tmp_path):
    """The estimate counts the runs not on disk, and grows with t_end (the paper's scene: a
    run to t = 1e9 is 1.7e11 steps, hours on 2 workers even for one load)."""
    from types import SimpleNamespace

    from diskfriction.models.chain.commands import ensemble_estimate

    args = lambda t_end: SimpleNamespace(t_end=t_end, amplitude=1e-5, perturbation=None, seed=0,
                                         scheduler=None)
    short = ensemble_estimate(Scene(), [0.083, 0.09], 3, args(300.0), tmp_path)
    assert re.fullmatch(r"6 runs to do, about [0-9.]+ s on \d+ workers? \(a rough estimate\)", short)
    assert " h on 2 workers" in ensemble_estimate(Scene(), [0.083], 2, args(1e9), tmp_path)
    remote = SimpleNamespace(**{**vars(args(300.0)), "scheduler": "tcp://host:8786"})
    assert "divided by the scheduler's workers" in ensemble_estimate(Scene(), [0.09], 1, remote, tmp_path)


def test_an_ensemble_folder_refuses_runs_with_other_parameters(tmp_path):
    """More realizations (or other loads and seeds) extend a folder; another t_end, amplitude,
    perturbation or scene would mix incomparable runs, and is refused with one line."""
    scene = Scene(N=3)
    record = lambda spec, K=2, loads=(0.05,): json.loads(json.dumps(
        parameters(scene, list(loads), K, spec, code_version())))
    check_directory(tmp_path, record(RunSpec(150.0)))  # an empty folder takes anything
    (tmp_path / "ensemble.json").write_text(json.dumps({"parameters": record(RunSpec(150.0))}))
    check_directory(tmp_path, record(RunSpec(150.0), K=5, loads=(0.05, 0.06)))
    for other, says in [(record(RunSpec(200.0)), "t_end = 150.0 (this run: 200.0)"),
                        (record(RunSpec(150.0, amplitude=1e-3)), "amplitude"),
                        (record(RunSpec(150.0, kind="random-position")), "kind")]:
        with pytest.raises(EnsembleMismatch, match=r"choose another output directory") as raised:
            check_directory(tmp_path, other)
        assert says in str(raised.value) and "\n" not in str(raised.value)
    (tmp_path / "ensemble.json").write_text(json.dumps({"V1": {}}))  # written before parameters
    with pytest.raises(EnsembleMismatch, match="records no run parameters"):
        check_directory(tmp_path, record(RunSpec(150.0)))


@pytest.mark.slow
def test_simulate_writes_trajectory_summary_and_plot(tmp_path):
    result = run_cli("simulate", "--fx", "0.087", "--t-end", "50", "--out", str(tmp_path))
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert {"slid", "sigma_measured", "sigma_predicted", "V_cm", "first_breach"} <= set(summary)
    assert set(summary["first_breach"]) == {"t", "x"} and len(summary["first_breach"]["t"]) == 10
    data = np.load(tmp_path / "trajectory.npz")
    assert data["q"].shape[1] == 30 and data["t"][-1] == pytest.approx(50, rel=1e-3)
    assert (tmp_path / "run.png").read_bytes()[:4] == b"\x89PNG"


BAD = [(["simulate", "--fx", "0.08", "--t-end", "-1"], "--t-end"),
       (["simulate", "--fx", "x", "--t-end", "10"], "--fx"),
       (["simulate", "--fx", "0.08,-1", "--t-end", "10"], "--fx"),
       (["simulate", "--fx", "0.08", "--t-end", "10", "--realizations", "0"], "--realizations"),
       (["simulate", "--fx", "0.08", "--t-end", "10", "--perturbation", "kick"], "--perturbation"),
       (["simulate", "--t-end", "10"], "--fx"),
       (["verify", "--t-end", "0"], "--t-end"),
       (["verify", "--matrix", "K"], "--matrix")]


@pytest.mark.parametrize("args, key", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_input_gets_one_line_and_exit_2(args, key, tmp_path):
    result = run_main(*args, "--out", str(tmp_path))
    assert result.returncode == 2 and result.stderr.count("\n") == 1 and key in result.stderr
    assert "Traceback" not in result.stderr


def test_an_interrupt_ends_with_one_line_that_says_whether_a_rerun_resumes(capsys):
    """Only a command that keeps what it finished (args.keeps) promises that a rerun resumes
    (issue 23: every command said so)."""
    import argparse

    from diskfriction.cli.common import EXIT_INTERRUPTED, run_command

    def interrupted(args):
        raise KeyboardInterrupt

    def interrupted_after_planning(args):
        args.keeps = ("cells", Path("out/map/cells"))
        raise KeyboardInterrupt

    assert run_command(argparse.Namespace(run=interrupted, command="verify")) == EXIT_INTERRUPTED
    err = capsys.readouterr().err
    assert err == "interrupted: verify does not resume; run it again to get its results\n"
    run_command(argparse.Namespace(run=interrupted_after_planning, command="map"))
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cells are kept in out/map/cells; rerun the same command to resume" in err


def test_windows_are_the_intervals_between_collisions_with_their_pair_count():
    from types import SimpleNamespace

    from diskfriction.studies.verify import windows

    c = lambda p, kind: SimpleNamespace(p=p, kind=kind)
    branch = SimpleNamespace(F_x=np.array([0.0, 0.5, 1.0]), n_complex=np.array([1, 2, 0]),
                             leg=np.array([1, 1, 1]),
                             collisions=[c(0.2, "birth"), c(0.4, "death"), c(0.7, "death")])
    assert windows(branch) == [(0.0, 0.2, 1), (0.2, 0.4, 2), (0.4, 0.7, 1), (0.7, 1.0, 0)]
    # a sweep 0.5 -> 1 first loads from rest to 0.5 (leg 0): its windows start at 0.5
    prepared = SimpleNamespace(F_x=np.array([0.0, 0.25, 0.5, 0.75, 1.0]),
                               n_complex=np.array([0, 1, 3, 3, 2]), leg=np.array([0, 0, 0, 1, 1]),
                               collisions=[c(0.9, "death")])
    assert windows(prepared) == [(0.5, 0.9, 3), (0.9, 1.0, 2)]


@pytest.mark.slow
def test_verify_runs_every_window_and_writes_its_table(tmp_path):
    scene = tmp_path / "four.toml"
    scene.write_text("[disks]\nN = 4\n[load]\nF_x = [0.0, 0.05]\n")
    result = run_cli("verify", str(scene), "--t-end", "100", "--out", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    rows = json.loads((tmp_path / "out" / "verify.json").read_text())
    assert len(rows) >= 2 and all(r["window"][0] < r["F_x"] < r["window"][1] for r in rows)
    for r in rows:  # an unstable window's growth is measured and matches the spectrum
        if r["sigma_predicted"] > 0 and r["sigma_measured"] is not None:
            assert r["sigma_measured"] == pytest.approx(r["sigma_predicted"], rel=0.05)
    assert any(r["sigma_measured"] is not None for r in rows)
    assert "| window F_x |" in (tmp_path / "out" / "verify.md").read_text()
    assert (tmp_path / "out" / "verify.png").read_bytes()[:4] == b"\x89PNG"
    assert "verify.png" in result.stdout
