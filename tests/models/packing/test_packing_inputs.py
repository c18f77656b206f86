"""What a packing command refuses before any work (issue 60, items 1 and 8): a scene too large
for this machine's memory, one the preparation cannot make (too few disks, a box too narrow, a
pressure double precision does not resolve), a strain range past order one, --gamma beyond the
scene's strain, a run of too many time steps; each in one line, exit 2, at once, nothing
written. And the rough wall time every packing command prints before its work."""
from __future__ import annotations

import time
from pathlib import Path

import pytest

from diskfriction.cli.main import main

COMMANDS = {"bifurcate": [], "prepare": [], "simulate": ["--gamma", "0.01", "--t-end", "10"],
            "verify": [], "report": []}
"""Every command that takes a packing scene (map has its own tests), with what it needs."""


def scene(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "pack.toml"
    path.write_text('geometry = "packing"\n' + text, encoding="utf-8")
    return path


def refused(capsys, tmp_path: Path, command: str, *args: str, by: str = "") -> str:
    """Run `command ARGS --out DIR` in this process: it must exit 2 within seconds, write
    nothing into DIR and end stderr with one error line, which is returned: `by` "scene" for a
    scene's rule (``scene error: ...``), else the command's."""
    out = tmp_path / "out"
    start = time.perf_counter()
    code = main([command, *args, "--out", str(out)])
    seconds = time.perf_counter() - start
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert code == 2, err
    assert seconds < 10, f"{command} took {seconds:.1f} s to refuse"
    assert not out.exists() or not any(out.iterdir())
    assert lines and lines[-1].startswith(f"{by or command} error: "), err
    assert all(line.startswith(f"{command}: ") for line in lines[:-1]), err
    return lines[-1]


@pytest.mark.parametrize("command", ["bifurcate", "simulate", "verify", "report"])
@pytest.mark.parametrize("N", [100_000, 10_000_000])
def test_a_shear_too_large_for_the_memory_is_refused_naming_N_and_its_spectra(
        tmp_path, capsys, command, N):
    path = scene(tmp_path, f"[packing]\nN = {N}\n")
    line = refused(capsys, tmp_path, command, str(path), *COMMANDS[command])
    if command in ("bifurcate", "simulate"):  # bifurcate's auto spectra at this N, simulate's
        assert f"N = {N}: a shear storing about " in line and f"points of {3 * N} unknowns" in line
    else:  # every state's spectrum
        assert f"N = {N}: a shear with dense {3 * N} x {3 * N} spectra" in line
    assert "of memory, more than this machine's" in line and str(path) in line


def test_bifurcate_counts_the_dense_spectra_of_each_scan_worker(tmp_path, capsys):
    path = scene(tmp_path, "[packing]\nN = 100000\n")
    line = refused(capsys, tmp_path, "bifurcate", str(path), "--workers", "3", "--spectra", "full")
    assert "spectra in 4 processes" in line


def test_a_windowed_shear_counts_the_points_it_stores(tmp_path, capsys):
    path = scene(tmp_path, "[packing]\nN = 10000000\n")
    line = refused(capsys, tmp_path, "bifurcate", str(path), "--window=-3:8", "--spectra", "full")
    assert "N = 10000000: a shear storing about" in line and "with a window" in line
    assert "points of 30000000 unknowns" in line


def test_a_preparation_too_large_for_the_memory_is_refused(tmp_path, capsys, monkeypatch):
    """The preparation's own bytes (models/packing/memory.py) against a machine of 10 MB."""
    monkeypatch.setattr("diskfriction.memory.physical_memory", lambda: 10_000_000)
    path = scene(tmp_path, "[packing]\nN = 100000\n")
    line = refused(capsys, tmp_path, "prepare", str(path))
    assert "N = 100000: a preparation of 100000 disks needs about" in line


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("N", [2, 3, 15])
def test_too_few_disks_to_jam_are_refused_by_the_scene(tmp_path, capsys, command, N):
    path = scene(tmp_path, f"[packing]\nN = {N}\n")
    line = refused(capsys, tmp_path, command, str(path), *COMMANDS[command], by="scene")
    assert f"{path}: packing.N: must be >= 16" in line and f"(got {N})" in line


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("pressure", ["1e-300", "3e-4"])
def test_a_pressure_the_preparation_cannot_resolve_is_refused(tmp_path, capsys, command, pressure):
    """32 disks: FIRE stalls at phi = 0.88 below P = 5e-4 (models/packing/limits.py): the line names
    the pressure, N and the smallest pressure that prepares."""
    path = scene(tmp_path, f"[packing]\nN = 32\npressure = {pressure}\n")
    line = refused(capsys, tmp_path, command, str(path), *COMMANDS[command])
    assert f"packing.pressure = {float(pressure)!r}" in line
    assert "the smallest pressure it prepares with N = 32, k_n = 2000 and R = 0.5 is about" in line


def test_a_pressure_whose_overlap_is_not_small_is_refused_by_the_scene(tmp_path, capsys):
    path = scene(tmp_path, "[packing]\nN = 32\npressure = 50\n")
    line = refused(capsys, tmp_path, "prepare", str(path), by="scene")
    assert "packing.pressure: the typical overlap at this pressure" in line
    assert "more than 0.1 R" in line and "the largest pressure with this k_n and R is 22.4" in line


def test_a_box_too_narrow_for_its_largest_disks_is_refused(tmp_path, capsys):
    """16 disks, one of radius 10 R: at phi = 0.88 the box (10.1) is narrower than twice the
    largest contact distance (11), and FIRE stalled there at max |F| = 604."""
    path = scene(tmp_path, "[packing]\nN = 16\nfraction_small = 0.9375\nsize_ratio = 10\n")
    line = refused(capsys, tmp_path, "prepare", str(path))
    assert "packing.N = 16: the preparation's box at phi = 0.88 is 10.1 wide" in line


@pytest.mark.parametrize("command", COMMANDS)
def test_a_strain_range_past_order_one_is_refused_by_the_scene(tmp_path, capsys, command):
    path = scene(tmp_path, "[packing]\nN = 32\n[shear]\ngamma = [0.0, 1e6]\n")
    line = refused(capsys, tmp_path, command, str(path), *COMMANDS[command], by="scene")
    assert "shear.gamma: must be <= 1" in line


def test_simulate_refuses_a_strain_beyond_the_scenes(tmp_path, capsys):
    path = scene(tmp_path, "[packing]\nN = 32\n[shear]\ngamma = [0.0, 0.002]\n")
    for gamma in ("1e6", "0.0021"):
        line = refused(capsys, tmp_path, "simulate", str(path), "--gamma", gamma, "--t-end", "10")
        assert "--gamma: beyond the scene's strain range [0, 0.002]" in line
        assert f"(got {float(gamma)!r})" in line


@pytest.mark.parametrize("command, args", [("simulate", ["--gamma", "0.001"]), ("verify", [])])
def test_a_run_of_too_many_time_steps_is_refused(tmp_path, capsys, command, args):
    path = scene(tmp_path, "[packing]\nN = 32\n[shear]\ngamma = [0.0, 0.002]\n")
    line = refused(capsys, tmp_path, command, str(path), *args, "--t-end", "1e15")
    assert "--t-end: a run to t = 1e+15 takes about 2.5e+17 time steps" in line
    assert "more than the 1e+08 a run may take" in line


def test_a_time_step_too_small_for_its_run_is_refused_naming_dt(tmp_path, capsys):
    path = scene(tmp_path, "[packing]\nN = 32\n[shear]\ngamma = [0.0, 0.002]\n")
    line = refused(capsys, tmp_path, "simulate", str(path), "--gamma", "0.001", "--t-end", "1000",
                   "--dt", "1e-9")
    assert "--dt: a run to t = 1000 takes about 1e+12 time steps (--dt = 1e-09)" in line


@pytest.mark.parametrize("command", ["bifurcate", "simulate", "verify", "report"])
def test_every_packing_command_says_how_long_it_will_take_before_it_starts(
        tmp_path, capsys, monkeypatch, command):
    """The estimate is the first line on stderr, before any work: the work itself is stopped
    at its start (the preparation), so that the test takes no time."""
    from diskfriction.models.packing import prepared

    def stop(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(prepared, "prepare_scene", stop)
    for module in ("diskfriction.models.packing.commands", "diskfriction.models.packing.shear",
                   "diskfriction.reports.packing_report"):
        monkeypatch.setattr(f"{module}.prepare_scene", stop, raising=False)
    path = scene(tmp_path, "[packing]\nN = 256\n[shear]\ngamma = [0.0, 0.05]\n")
    args = ["--gamma", "0.05", "--t-end", "1000"] if command == "simulate" else []
    main([command, str(path), *args, "--out", str(tmp_path / "out")])
    first = capsys.readouterr().err.splitlines()[0]
    assert first.startswith(f"{command}: about ") and "(a rough estimate) to prepare 256 disks" in first
    shear = {"bifurcate": "with the spectrum every 0.0005",  # auto for 256 disks
             "simulate": "without spectra"}.get(command, "with every eigenvalue")
    assert f"shear them to gamma = 0.05 {shear}" in first
    if command in ("simulate", "verify"):
        runs = "once" if command == "simulate" else "up to 10 times"
        assert f"run {runs} for about 2.5e+05 time steps" in first


def test_prepare_says_how_long_it_will_take(tmp_path, capsys):
    path = scene(tmp_path, "[packing]\nN = 16\n")
    assert main(["prepare", str(path), "--out", str(tmp_path / "out")]) == 0
    first = capsys.readouterr().err.splitlines()[0]
    assert first.startswith("prepare: about ") and first.endswith(
        "s (a rough estimate) to prepare 16 disks")


@pytest.mark.parametrize(("command", "args", "option"), [
    ("bifurcate", ["--workers", "-1"], "--workers"),
    ("bifurcate", ["--matrix", "K"], "--matrix"),
    ("bifurcate", ["--fx", "0:1"], "--fx"),
    ("bifurcate", ["--p", "0:1"], "--p"),
    ("simulate", ["--gamma", "0.001", "--t-end", "10", "--amplitude", "-1"], "--amplitude"),
    ("simulate", ["--gamma", "0.001", "--t-end", "10", "--seed", "-1"], "--seed"),
    ("verify", ["--matrix", "J"], "--matrix"),
    ("verify", ["--amplitude", "-1"], "--amplitude"),
])
def test_a_bad_option_is_the_only_line_no_estimate_before_it(tmp_path, capsys, command, args,
                                                             option):
    """An option a packing command refuses is refused before it estimates its work: stderr is
    that one line (the estimate line came first)."""
    path = scene(tmp_path, "[packing]\nN = 16\n[shear]\ngamma = [0.0, 0.002]\n")
    out = tmp_path / "out"
    assert main([command, str(path), *args, "--out", str(out)]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"{command} error: {option}: "), lines
