"""bifurcate on a packing (issue 60): its outputs as one set that names its scene, an --out of
another scene refused, damaged segment files computed again, plastic.json, and Ctrl-C as one
line and exit 130 wherever it lands. 16 disks (seed 3) sheared to gamma = 0.004 pass one
plastic event in about a second."""
from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import numpy as np
import pytest

from diskfriction.cli.common import EXIT_BAD_INPUT, EXIT_INTERRUPTED
from diskfriction.cli.main import main

pytestmark = pytest.mark.slow  # whole runs of commands or examples: the slow tier (README, Tests)

SCENE = 'geometry = "packing"\nname = "{name}"\n[packing]\nN = 16\nseed = {seed}\n' \
        '[shear]\ngamma = [0.0, 0.004]\n'
OUTPUTS = ["branch.npz", "collisions.json", "diagram.png", "packing.npz", "plastic.json"]


def scene_file(directory: Path, name: str = "tiny", seed: int = 3) -> Path:
    path = directory / f"{name}.toml"
    path.write_text(SCENE.format(name=name, seed=seed), encoding="utf-8")
    return path


def bifurcate(scene: Path, out: Path, *options: str, workers: int = 0) -> int:
    return main(["bifurcate", str(scene), "--workers", str(workers), *options, "--out", str(out)])


def strict_json(path: Path):
    """The file's JSON, refusing NaN and Infinity (not JSON)."""
    def refuse(name):
        raise ValueError(f"{path}: {name} is not JSON")
    return json.loads(path.read_text(encoding="utf-8"), parse_constant=refuse)


def same_arrays(a: Path, b: Path) -> bool:
    with np.load(a) as x, np.load(b) as y:
        return x.files == y.files and all(
            np.array_equal(x[k], y[k], equal_nan=x[k].dtype.kind in "fc") for k in x.files)


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    """(scene file, DIR) of a bifurcate never interrupted."""
    root = tmp_path_factory.mktemp("whole")
    scene = scene_file(root)
    assert bifurcate(scene, root / "out") == 0
    return scene, root / "out"


def interrupt_after_first_segment(monkeypatch):
    """Ctrl-C right after the first segment file is written."""
    from diskfriction.models.packing import segments

    save = segments.save_segment

    def save_then_interrupt(*args):
        save(*args)
        raise KeyboardInterrupt

    monkeypatch.setattr(segments, "save_segment", save_then_interrupt)


def test_every_output_names_its_scene_and_the_set_is_written_once(whole):
    """packing.npz, branch.npz, collisions.json and plastic.json each name the scene (name, file,
    N, k_n, seed, every physics field); segments/ is gone once they are written."""
    from diskfriction.scenes.load import load_scene

    scene_path, out = whole
    scene = load_scene(scene_path)  # its spectra "auto", which the outputs record resolved
    physics = json.loads(json.dumps({**scene.physics_fields(), "spectra": scene.resolved_spectra}))
    assert physics["spectra"] == "full"  # 16 disks
    assert sorted(p.name for p in out.iterdir()) == OUTPUTS
    for name in ("packing.npz", "branch.npz"):
        with np.load(out / name, allow_pickle=False) as data:
            assert str(data["scene"]) == "tiny" and str(data["scene_file"]) == str(scene_path)
            assert (int(data["N"]), float(data["k_n"]), int(data["seed"])) == (16, 2000.0, 3)
            assert json.loads(str(data["scene_physics"])) == physics
    for name in ("collisions.json", "plastic.json"):
        record = strict_json(out / name)["scene"]
        assert record == {"name": "tiny", "file": str(scene_path), "N": 16, "k_n": 2000.0,
                          "seed": 3, "physics": physics}


def test_plastic_json_lists_each_event_with_the_complex_pairs_just_before_it(whole, capsys):
    """plastic.json: per plastic event the strain, kind, sigma_xy before and after and the drop
    (as the summary prints them), and at the branch's last point before it (the fold) the
    complex pairs of M^-1 J: their count (n_complex there) and the fastest growth rate
    |Im sqrt(lambda)| among them, recomputed here from branch.npz's eigenvalues."""
    _, out = whole
    events = strict_json(out / "plastic.json")["events"]
    assert len(events) == 1
    with np.load(out / "branch.npz") as branch:
        gamma, segment, n_complex = branch["gamma"], branch["segment"], branch["n_complex"]
        eigenvalues, stress = branch["eigenvalues"], branch["stress"]
    for k, event in enumerate(events):
        last = np.flatnonzero(segment == k)[-1]
        assert event["gamma"] == gamma[last] and event["kind"] == "fold"
        assert event["sigma_xy_before"] == stress[last, 2]
        assert event["sigma_xy_after"] < event["sigma_xy_before"]
        assert event["drop"] == pytest.approx(event["sigma_xy_before"] - event["sigma_xy_after"],
                                              rel=1e-12)
        lam = eigenvalues[last]
        pairs = lam[lam.imag > 1e-9 * np.abs(lam).max()]
        assert event["complex_pairs"] == n_complex[last] == pairs.size > 0
        assert event["growth_rate"] == pytest.approx(np.abs(np.sqrt(pairs).imag).max(), rel=1e-12)
        assert event["displacement"] > 0 and event["relaxation_steps"] > 0


def test_plastic_records_give_no_growth_rate_for_j_or_without_a_pair(whole):
    """The growth rate is M^-1 J's: null for a branch of J, and null at a fold without a pair."""
    import dataclasses

    from diskfriction.matrices import Matrix
    from diskfriction.models.packing.prepared import prepare_scene
    from diskfriction.models.packing.shear import ShearParams, shear
    from diskfriction.reports.packing_outputs import plastic_records
    from diskfriction.scenes.load import load_scene

    scene = load_scene(whole[0])
    branch = shear(scene, prepare_scene(scene), ShearParams(workers=0), plastic_events=5)
    assert plastic_records(branch)[0]["growth_rate"] > 0
    assert plastic_records(dataclasses.replace(branch, matrix=Matrix.J))[0]["growth_rate"] is None
    last = np.flatnonzero(branch.segment == 0)[-1]
    n_complex = branch.n_complex.copy()
    n_complex[last] = 0
    record = plastic_records(dataclasses.replace(branch, n_complex=n_complex))[0]
    assert record["complex_pairs"] == 0 and record["growth_rate"] is None


def test_an_out_of_another_scene_is_refused_in_one_line(whole, tmp_path, capsys):
    """bifurcate and prepare refuse an --out holding another scene's results (exit 2, one line
    naming the file there, both scenes and how they differ), and leave its files as they were."""
    _, out = whole
    other = scene_file(tmp_path, "other", seed=4)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    for command in ("bifurcate", "prepare"):
        assert main([command, str(other), "--out", str(out)]) == EXIT_BAD_INPUT
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith(f"{command} error: --out: "), err
        assert "scene 'tiny'" in err and "'other'" in err and "seed 3 there, 4 here" in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_an_interrupted_run_writes_no_output_and_claims_its_directory(whole, tmp_path,
                                                                      monkeypatch, capsys):
    """Ctrl-C after the first segment: none of the outputs is written (packing.npz was, beside
    nothing or an older branch.npz), segments/scene.json names the scene of the shear under
    way, so another scene's run into DIR is refused; the rerun resumes and writes the same
    set as a run never interrupted."""
    scene, reference = whole
    out = tmp_path / "out"
    interrupt_after_first_segment(monkeypatch)
    assert bifurcate(scene, out) == EXIT_INTERRUPTED
    assert f"the finished segments are kept in {out / 'segments'}" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["segments"]
    assert strict_json(out / "segments" / "scene.json")["scene"]["name"] == "tiny"
    monkeypatch.undo()
    assert bifurcate(scene_file(tmp_path, "other", seed=4), out) == EXIT_BAD_INPUT
    assert "segments/scene.json there belongs to scene 'tiny'" in capsys.readouterr().err
    assert bifurcate(scene, out) == 0
    assert "resumed after 1 segment" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == OUTPUTS
    for name in ("branch.npz", "packing.npz"):
        assert same_arrays(out / name, reference / name), name
    for name in ("collisions.json", "plastic.json"):
        assert strict_json(out / name) == strict_json(reference / name), name


@pytest.mark.parametrize("damage", ["empty", "truncated", "corrupted"])
def test_a_damaged_segment_file_is_computed_again(whole, tmp_path, capsys, damage):
    """An empty, truncated or corrupted DIR/segments/segment-0000.npz: the rerun says it cannot
    read it, computes that segment again and writes the set of a run never interrupted."""
    scene, reference = whole
    out = tmp_path / "out"
    data = (reference / "branch.npz").read_bytes()
    damaged = {"empty": b"", "truncated": data[:len(data) // 2],
               "corrupted": data[:300] + b"x" * 64 + data[364:]}[damage]
    (out / "segments").mkdir(parents=True)
    (out / "segments" / "segment-0000.npz").write_bytes(damaged)
    assert bifurcate(scene, out) == 0
    err = capsys.readouterr().err
    assert "computed again: " in err and "segment-0000.npz: unreadable (" in err, err
    assert "Traceback" not in err and max(len(line) for line in err.splitlines()) < 400
    assert sorted(p.name for p in out.iterdir()) == OUTPUTS
    assert same_arrays(out / "branch.npz", reference / "branch.npz")


@pytest.mark.parametrize("inside_the_check", [True, False])
def test_ctrl_c_landing_in_a_compiled_functions_first_call_is_one_line_and_130(
        tmp_path, monkeypatch, capsys, inside_the_check):
    """Ctrl-C while numba unpickles a compiled function's constants on its first call (the
    stability matrices' assembly, early in the shear) comes out of the call as a SystemError
    raised from the KeyboardInterrupt (about one run in twelve interrupted early, a 93-line
    traceback and exit 1): as it is (a call of the continuation), or wrapped by the
    continuation's check of the problem at its start ("dG/du raised SystemError", exit 2). One
    line, exit 130, and before the first segment it says that nothing is kept."""
    import traceback

    from diskfriction.models.packing import assembly

    linear_map, calls = assembly._linear_map, []

    def interrupted(*args, **kwargs):
        calls.append(1)
        in_check = "check_problem" in {frame.name for frame in traceback.extract_stack()}
        if in_check != inside_the_check:
            return linear_map(*args, **kwargs)
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as error:
            raise SystemError("CPUDispatcher(<function _linear_map>) returned a result with an "
                              "exception set") from error

    monkeypatch.setattr(assembly, "_linear_map", interrupted)
    out = tmp_path / "out"
    assert bifurcate(scene_file(tmp_path), out) == EXIT_INTERRUPTED
    err = capsys.readouterr().err.splitlines()
    assert err[-1] == ("interrupted before any of the segments was finished: nothing is kept; "
                       "rerun the same command to start again")
    assert all(line.startswith("bifurcate: ") for line in err[:-1]), err
    assert not (out / "segments").exists() and list(out.iterdir()) == []
    assert len(calls) == 1 if inside_the_check else len(calls) > 1


def test_prepare_takes_the_packaged_packing_scene_by_default(capsys):
    """prepare's FILE defaults to the packaged packing scene, as its --help says (it said the
    paper's chain scene, which prepare refuses)."""
    from diskfriction.cli.main import build_parser
    from diskfriction.scenes.load import load_scene
    from diskfriction.scenes.packing import PackingScene

    with pytest.raises(SystemExit) as exit_:
        main(["prepare", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert exit_.value.code == 0 and "scenes/packing.toml" in text and "paper" not in text
    args = build_parser().parse_args(["prepare"])
    assert isinstance(load_scene(args.scene), PackingScene)


def test_bifurcate_p_on_a_packing_names_its_strain(tmp_path, capsys):
    """--p on a packing scene: one line saying a packing's load is its strain, not the chain's
    --fx."""
    out = tmp_path / "out"
    assert bifurcate(scene_file(tmp_path), out, "--p", "0:1") == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("bifurcate error: --p: ")
    assert "[shear] gamma" in err and "--fx" not in err
    assert not out.exists()


FORK_INTERRUPTS = []
"""Armed: the next fork of this process sends it SIGINT from an at-fork callback (a callback
cannot be unregistered: this one is registered once and does nothing unarmed)."""
if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_parent=lambda: FORK_INTERRUPTS and (
        FORK_INTERRUPTS.clear(), os.kill(os.getpid(), signal.SIGINT)))


def test_ctrl_c_during_the_fork_of_a_scan_worker_ends_the_run(tmp_path, capsys):
    """Ctrl-C while a scan worker is forked, handled in an at-fork callback, was printed as an
    ignored exception and dropped, and the run went on to its end: it is one line and exit
    130."""
    out = tmp_path / "out"
    FORK_INTERRUPTS.append(1)
    try:
        code = bifurcate(scene_file(tmp_path), out, workers=1)
    finally:
        FORK_INTERRUPTS.clear()
    err = capsys.readouterr().err
    assert code == EXIT_INTERRUPTED, err
    assert "Traceback" not in err and "ignored" not in err
    assert err.splitlines()[-1].startswith("interrupted before any of the segments was finished")


def test_simulate_and_verify_refuse_another_scenes_out_and_keep_their_own(tmp_path, capsys):
    """simulate's and verify's outputs name the scene as given (not the shear to --gamma that
    simulate runs): a rerun with another --gamma writes over its own files, another scene's
    run into the same --out is refused in one line, exit 2."""
    from diskfriction.cli.main import main

    mine, other = tmp_path / "mine.toml", tmp_path / "other.toml"
    text = 'geometry = "packing"\nname = "{}"\n[packing]\nN = 16\nseed = {}\n[shear]\ngamma = [0.0, 0.002]\n'
    mine.write_text(text.format("mine", 3))
    other.write_text(text.format("other", 4))
    out = tmp_path / "out"
    for gamma in ("0.001", "0.002"):
        assert main(["simulate", str(mine), "--gamma", gamma, "--t-end", "5", "--out", str(out)]) == 0
    summary = strict_json(out / "summary.json")
    assert summary["gamma"] == 0.002 and summary["scene"]["physics"]["gamma_range"] == [0.0, 0.002]
    capsys.readouterr()
    for argv in (["simulate", str(other), "--gamma", "0.001", "--t-end", "5"],
                 ["verify", str(other), "--t-end", "5"]):
        assert main([*argv, "--out", str(out)]) == 2
        lines = capsys.readouterr().err.splitlines()
        assert len(lines) == 1 and "belongs to scene 'mine'" in lines[0], lines
