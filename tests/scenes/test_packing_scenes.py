"""Packing scenes (issue 25): geometry = "packing" in a scene file, its schema and rules, and
the commands that do not take packings yet refusing one in one line."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
from commandline import error_line, run_cli, run_main

from diskfriction.scenes import Effects, SceneError, format_scene, load_scene
from diskfriction.scenes.load import PACKING_SCHEMA
from diskfriction.scenes.packing import PackingScene
from diskfriction.scenes.scene import SceneValueError

PACKAGED = Path(__file__).resolve().parents[2] / "scenes" / "packing.toml"


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "pack.toml"
    path.write_text('geometry = "packing"\n' + text, encoding="utf-8")
    return path


def test_the_packaged_packing_scene_is_what_the_scene_command_prints_for_it():
    scene = load_scene(PACKAGED)
    assert dataclasses.replace(scene, source="<defaults>") == PackingScene()
    printed = format_scene(scene)
    keys = printed[printed.index("\n") + 1:printed.index("\n# derived")]
    assert PACKAGED.read_text(encoding="utf-8").endswith(keys.rstrip("\n") + "\n")


def test_a_packing_scene_round_trips_through_format_scene(tmp_path):
    scene = PackingScene(N=17, size_ratio=1.25, fraction_small=0.3, pressure=0.02, seed=9,
                         mu=0.5, gamma_range=(0.01, 0.2), matrix="J", name="odd",
                         effects=Effects(normal="hooke", pair_friction=False, wall_friction=False))
    path = tmp_path / "round.toml"
    path.write_text(format_scene(scene), encoding="utf-8")
    assert dataclasses.replace(load_scene(path), source=scene.source) == scene


BAD = [("packing.N", "1", "must be >= 16"),
       ("packing.N", "15", "must be >= 16"),
       ("packing.size_ratio", "0.9", "must be >= 1"),
       ("packing.fraction_small", "1.5", "must be in [0, 1]"),
       ("packing.pressure", "-0.1", "must be > 0"),
       ("packing.seed", "-3", "must be >= 0"),
       ("packing.seed", "1.5", "expected an integer"),
       ("disks.R", "0", "must be > 0"),
       ("contacts.mu", "-1", "must be >= 0"),
       ("shear.gamma", "[0.1, 0.0]", "reversed range"),
       ("shear.gamma", "[-0.1, 0.1]", "must be >= 0"),
       ("shear.gamma", "[0.0, 1e6]", "must be <= 1"),
       ("packing.pressure", "1e6", "the typical overlap at this pressure"),
       ("contacts.k_n", "1e-3", "the typical overlap at this pressure"),
       ("shear.relaxation", '"quench"', "unknown effect"),
       ("shear.damping", "0", "must be > 0"),
       ("effects.friction", '["substrate"]', "a packing has no substrate"),
       ("effects.normal", '"coulomb"', "unknown effect"),
       ("stability.matrix", '"K"', "unknown effect")]


@pytest.mark.parametrize("key, value, what", BAD, ids=[f"{k}={v}" for k, v, _ in BAD])
def test_a_bad_packing_value_is_one_line_naming_file_key_and_value(tmp_path, key, value, what):
    table, name = key.split(".")
    path = write(tmp_path, f"[{table}]\n{name} = {value}\n")
    with pytest.raises(SceneError) as raised:
        load_scene(path)
    error = raised.value
    assert (error.file, error.key) == (str(path), key) and what in error.what
    assert "\n" not in str(error)


@pytest.mark.parametrize("text, key", [("[load]\nF_y = 0.1\n", "load"),
                                       ("[disks]\neps = 0.01\n", "disks.eps"),
                                       ("[effects]\nrotation = false\n", "effects.rotation")])
def test_chain_keys_are_unknown_in_a_packing_file(tmp_path, text, key):
    with pytest.raises(SceneError) as raised:
        load_scene(write(tmp_path, text))
    assert raised.value.key == key and "unknown" in raised.value.what


def test_an_unknown_geometry_is_refused(tmp_path):
    path = tmp_path / "g.toml"
    path.write_text('geometry = "hexagon"\n')
    with pytest.raises(SceneError) as raised:
        load_scene(path)
    assert raised.value.key == "geometry" and raised.value.value == "hexagon"


def test_the_packing_scene_checks_its_effects():
    with pytest.raises(SceneValueError, match="rotate"):
        PackingScene(effects=Effects(rotation=False))
    with pytest.raises(SceneValueError, match="conventions"):
        PackingScene(effects=Effects(conventions="lammps"))
    assert PackingScene(mu=0.0).resolved_effects.pair_law == "none"
    assert set(PACKING_SCHEMA) >= {"packing.N", "packing.pressure", "shear.gamma"}


@pytest.mark.parametrize("command", [["crosscheck", "lammps"],
                                     ["crosscheck", "lammps", "--fx", "0", "--t-end", "1"]])
def test_commands_without_packings_refuse_a_packing_scene_in_one_line(tmp_path, command):
    result = run_main(*command[:2], str(PACKAGED), *command[2:], "--out", str(tmp_path / "out"))
    command = command[0]
    assert result.returncode == 2 and result.stderr.count("\n") == 1
    line = error_line(result, command)
    assert str(PACKAGED) in line and 'geometry = "packing"' in line
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_prepare_writes_a_packing_that_a_second_run_reproduces_bit_for_bit(tmp_path):
    """`prepare` on a 32-disk scene: the target pressure to 1e-3, every disk balanced to
    F_TOL of a contact's force, z at least isostatic without rattlers; the same scene gives
    the same packing.npz bytes."""
    import json

    import numpy as np

    from diskfriction.models.packing.prepare import load_packing
    from diskfriction.models.packing.prepared import F_TOL

    scene = write(tmp_path, "[packing]\nN = 32\npressure = 0.05\n")
    first = run_cli("prepare", str(scene), "--out", str(tmp_path / "a"))
    second = run_cli("prepare", str(scene), "--out", str(tmp_path / "b"))
    assert first.returncode == 0 and second.returncode == 0, first.stderr
    summary = json.loads((tmp_path / "a" / "packing.json").read_text())
    assert abs(summary["pressure"] / 0.05 - 1) <= 1e-3 and 0.8 < summary["phi"] < 0.9
    jammed = 32 - summary["rattlers"]  # isostatic counting with P > 0: z >= 4 - 2 / jammed
    assert summary["max_force"] <= F_TOL * 0.05 * 1.0 and summary["z"] >= 4 - 2 / jammed
    a, b = (load_packing(tmp_path / d / "packing.npz") for d in "ab")
    assert np.array_equal(a.positions, b.positions) and a.L == b.L
    assert (tmp_path / "a" / "packing.npz").read_bytes() == (tmp_path / "b" / "packing.npz").read_bytes()


def test_prepare_refuses_a_chain_scene_in_one_line(tmp_path):
    result = run_cli("prepare", str(PACKAGED.with_name("paper.toml")), "--out", str(tmp_path / "out"))
    assert result.returncode == 2 and "prepare takes packing scenes" in error_line(result, "prepare")
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_bifurcate_shears_a_packing_scene_and_writes_its_branch(tmp_path):
    """`bifurcate` on a 24-disk packing to gamma = 0.002: exit 0, the files written, every
    collision in collisions.json within the range, the branch in force balance."""
    import json

    import numpy as np

    scene = write(tmp_path, "[packing]\nN = 24\nseed = 3\n[shear]\ngamma = [0.0, 0.002]\n")
    result = run_cli("bifurcate", str(scene), "--out", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    out = tmp_path / "out"
    assert {p.name for p in out.iterdir()} >= {"branch.npz", "collisions.json", "diagram.png",
                                               "packing.npz"}
    with np.load(out / "branch.npz") as branch:
        assert branch["gamma"][-1] == 0.002 and branch["residual"].max() <= 1e-11
        assert branch["eigenvalues"].shape == (branch["gamma"].size, 3 * 24)
    found = json.loads((out / "collisions.json").read_text())
    records = found["collisions"]
    assert (found["parameter"], found["units"], found["matrix"]) == ("gamma", "", "M^-1 J")
    assert records and all(0 <= r["p"] <= 0.002 for r in records)
    assert f"{len(records)} collisions" in result.stdout


@pytest.mark.slow
def test_bifurcate_says_how_many_collisions_are_only_bracketed(tmp_path, monkeypatch, capsys):
    """A detection whose solve budget runs out (1 solve a step here; 500 by default) leaves
    collisions bracketed but not located: bifurcate says how many in its summary, as
    collisions.json marks them (resolved: false), instead of listing them like the others."""
    import json

    from diskfriction.cli.main import main
    from diskfriction.continuation.detection import collisions

    budget = collisions.DetectionParams  # what bifurcate imports when it runs
    monkeypatch.setattr(collisions, "DetectionParams", lambda **kw: budget(max_solves=1, **kw))
    scene = write(tmp_path, "[packing]\nN = 24\nseed = 3\n[shear]\ngamma = [0.0, 0.001]\n")
    assert main(["bifurcate", str(scene), "--workers", "0", "--out", str(tmp_path / "out")]) == 0
    records = json.loads((tmp_path / "out" / "collisions.json").read_text())["collisions"]
    unlocated = sum(not r["resolved"] for r in records)
    assert unlocated >= 1
    out = capsys.readouterr().out
    summary = f"{len(records)} collisions (M^-1 J) with gamma >= 0, {unlocated} of them only bracketed"
    assert summary in out, out


@pytest.mark.slow
def test_bifurcate_with_a_window_lists_only_its_collisions(tmp_path):
    """`bifurcate PACKING --window 5:50` on 24 disks: exit 0, every collision's double
    eigenvalue in the window, the branch's spectrum stored as window columns (nan where a
    column holds no tracked eigenvalue), the window named in the summary."""
    import json

    import numpy as np

    scene = write(tmp_path, "[packing]\nN = 24\nseed = 3\n[shear]\ngamma = [0.0, 0.002]\n")
    result = run_cli("bifurcate", str(scene), "--window", "5:50", "--out", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    records = json.loads((tmp_path / "out" / "collisions.json").read_text())["collisions"]
    assert records and all(5 <= r["lambda"] <= 50 for r in records)
    with np.load(tmp_path / "out" / "branch.npz") as branch:
        lam = branch["eigenvalues"]
    assert np.isnan(lam).any() and np.isfinite(lam).any(axis=0).all()
    assert "Re lambda in [5, 50]" in result.stdout


@pytest.mark.parametrize("option, value", [("--fx", "0:0.1"), ("--ds-max", "0.1"),
                                           ("--window", "2:1")])
def test_bifurcate_refuses_chain_options_for_a_packing_in_one_line(tmp_path, option, value):
    result = run_main("bifurcate", str(PACKAGED), option, value, "--out", str(tmp_path / "out"))
    assert result.returncode == 2 and option in error_line(result, "bifurcate")
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_simulate_from_a_sheared_packing_grows_at_the_spectrums_rate(tmp_path):
    """`simulate PACKING --gamma 0.002`: the fastest complex pair's eigenvector, grown in the
    dynamics at the spectrum's sigma within 2 %; the energy budget drift below 1e-2 of the
    largest kinetic energy (the run ends in sliding, which the budget accounts for)."""
    import json

    scene = write(tmp_path, "[packing]\nN = 24\nseed = 3\n[shear]\ngamma = [0.0, 0.002]\n")
    result = run_cli("simulate", str(scene), "--gamma", "0.002", "--t-end", "400", "--out",
                     str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["perturbation"] == "eigenvector" and summary["complex_pairs"] >= 1
    assert abs(summary["sigma_measured"] / summary["sigma_predicted"] - 1) <= 0.02
    assert summary["budget_drift"] <= 1e-2 * summary["kinetic_max"]
    assert (tmp_path / "out" / "run.png").exists() and (tmp_path / "out" / "snapshot.png").exists()


@pytest.mark.parametrize("args, option", [(["--gamma", "0.001", "--fx", "0.1"], "--fx"),
                                          (["--t-end", "1"], "--gamma")])
def test_simulate_refuses_chain_options_for_a_packing_in_one_line(tmp_path, args, option):
    extra = [] if "--t-end" in args else ["--t-end", "1"]
    result = run_main("simulate", str(PACKAGED), *args, *extra, "--out", str(tmp_path / "out"))
    assert result.returncode == 2 and option in error_line(result, "simulate")


def test_simulate_on_a_chain_needs_fx_and_refuses_gamma(tmp_path):
    missing = run_main("simulate", "--t-end", "1", "--out", str(tmp_path / "a"))
    assert missing.returncode == 2 and "--fx" in error_line(missing, "simulate")
    gamma = run_main("simulate", "--fx", "0.01", "--gamma", "0.1", "--t-end", "1", "--out",
                     str(tmp_path / "b"))
    assert gamma.returncode == 2 and "--gamma" in error_line(gamma, "simulate")


@pytest.mark.slow
def test_report_on_a_packing_draws_its_figures_and_tells_a_complex_state_from_a_real_one(tmp_path):
    """`report PACKING` on 24 disks to gamma = 0.002: report.md and its four figures; from the
    state of fastest growth the random perturbation grows until contacts slide, from a state
    with every eigenvalue real it stays (its MSD at the end 1e-3 of the other's, no sliding)."""
    scene = write(tmp_path, "[packing]\nN = 24\nseed = 3\n[shear]\ngamma = [0.0, 0.002]\n")
    result = run_cli("report", str(scene), "--out", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    out = tmp_path / "out"
    assert {p.name for p in out.iterdir()} >= {"report.md", "stress.png", "spectrum.png",
                                               "snapshot.png", "msd.png"}
    rows = [line.split("|")[1:-1] for line in (out / "report.md").read_text().splitlines()
            if line.startswith("| complex") or line.startswith("| real")]
    (complex_run, real_run) = [[c.strip() for c in row] for row in rows]
    assert int(complex_run[2]) >= 1 and int(real_run[2]) == 0
    assert int(complex_run[5]) > 0 and int(real_run[5]) == 0
    assert float(real_run[4]) <= 1e-3 * float(complex_run[4])


def test_report_refuses_the_chains_options_for_a_packing_in_one_line(tmp_path):
    result = run_main("report", str(PACKAGED), "--only", "fig6", "--out", str(tmp_path / "out"))
    assert result.returncode == 2 and "--only" in error_line(result, "report")
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_verify_on_a_packing_measures_each_states_growth_against_its_spectrum(tmp_path):
    """`verify PACKING` on 24 disks to gamma = 0.002 (t_end 400): runs from states with complex
    pairs grow at the spectrum's rate (most within 2 %; two pairs of near rates may blur one)
    and some slide; runs from states with every eigenvalue real never slide, and relaxed at
    rest they come back to the state, while complex pairs' runs come back or change the state
    (rearrange the contact network, or slip: the stress drops by 1 % with the same contacts).
    Which of the two changes a grown run ends in is not asked: it hangs on the start at
    rounding level (a state 1.6e-16 away in strain, the same rates to 1e-5, relaxed once with
    two contacts opened and once with none, docs/packings.md)."""
    import json

    scene = write(tmp_path, "[packing]\nN = 24\nseed = 3\n[shear]\ngamma = [0.0, 0.002]\n")
    result = run_cli("verify", str(scene), "--t-end", "400", "--out", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    runs = json.loads((tmp_path / "out" / "verify.json").read_text())["runs"]
    grown = [r for r in runs if r["perturbation"] == "eigenvector"]
    still = [r for r in runs if r["perturbation"] == "random-velocity"]
    assert len(grown) >= 4 and still and all(not r["slid"] for r in still)
    close = [abs(r["sigma_measured"] / r["sigma_predicted"] - 1) <= 0.02 for r in grown]
    assert sum(close) >= len(grown) - 1 and any(r["slid"] for r in grown)
    # relaxed at rest: the real states come back; some complex pair rearranged the packing
    # (its contact network changed) and one dropped the stress by 1 % with the same contacts
    assert all(abs(r["stress_change_at_rest"]) <= 1e-6 for r in still)
    assert all(r["outcome"] == "came back" for r in still)
    assert min(r["stress_change_at_rest"] for r in grown) <= -1e-2
    outcomes = {r["outcome"] for r in grown}
    assert "came back" in outcomes and outcomes & {"rearranged", "slipped"}
    for r in grown:
        changed = r["contacts_opened_at_rest"] + r["contacts_formed_at_rest"] > 0
        assert (r["outcome"] == "rearranged") == changed
    text = (tmp_path / "out" / "verify.md").read_text()
    assert text.count("| eigenvector |") == len(grown)
    assert f"Runs from real states: {len(still)} came back." in text


@pytest.mark.slow
def test_simulate_a_packing_without_perturbation_runs_and_fits_no_growth(tmp_path):
    """--perturbation none (one of simulate's kinds) on a packing: the state as it is, no
    growth rate fitted, the energy budget closed; not a traceback."""
    import json

    scene = write(tmp_path, "[packing]\nN = 24\nseed = 3\n[shear]\ngamma = [0.0, 0.001]\n")
    result = run_cli("simulate", str(scene), "--gamma", "0.001", "--t-end", "10",
                     "--perturbation", "none", "--out", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["perturbation"] == "none" and summary["sigma_measured"] is None
    assert summary["sliding_updates"] == 0


@pytest.mark.slow
def test_an_interrupted_bifurcate_resumes_after_its_finished_segments(tmp_path, monkeypatch, capsys):
    """`bifurcate` on 32 disks (seed 2, to gamma = 0.0021, a plastic event passed), stopped by
    Ctrl-C right after its first segment was written to DIR/segments/: it says what it keeps;
    the rerun goes on after that segment and writes the same branch.npz arrays and
    collisions.json as a run never interrupted, and removes DIR/segments/."""
    import json

    import numpy as np

    from diskfriction.cli.common import EXIT_INTERRUPTED
    from diskfriction.cli.main import main
    from diskfriction.models.packing import segments

    scene = write(tmp_path, "[packing]\nN = 32\nseed = 2\n[shear]\ngamma = [0.0, 0.0021]\n")
    command = ["bifurcate", str(scene), "--workers", "0", "--window", "0:50", "--out"]
    assert main(command + [str(tmp_path / "whole")]) == 0
    save = segments.save_segment

    def save_then_interrupt(*args):
        save(*args)
        raise KeyboardInterrupt

    out = tmp_path / "resumed"
    monkeypatch.setattr(segments, "save_segment", save_then_interrupt)
    assert main(command + [str(out)]) == EXIT_INTERRUPTED
    kept = out / "segments"
    assert f"the finished segments are kept in {kept}" in capsys.readouterr().err
    assert sorted(p.name for p in kept.iterdir()) == ["scene.json", "segment-0000.npz"]
    monkeypatch.setattr(segments, "save_segment", save)
    assert main(command + [str(out)]) == 0
    assert "resumed after 1 segment, at gamma = " in capsys.readouterr().err
    assert not kept.exists()
    with np.load(tmp_path / "whole" / "branch.npz") as a, np.load(out / "branch.npz") as b:
        assert a.files == b.files
        assert all(np.array_equal(a[k], b[k], equal_nan=a[k].dtype.kind in "fc") for k in a.files)
    whole, resumed = (json.loads((d / "collisions.json").read_text()) for d in (tmp_path / "whole", out))
    assert resumed == whole and len(whole["collisions"]) > 0
