"""`diskfriction bifurcate`: outputs, --json, and one-line errors for bad input."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def bifurcate(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "diskfriction", "bifurcate", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def paper_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("bifurcate")
    return out, bifurcate("--out", str(out), "--json")


def test_writes_branch_collisions_and_diagram(paper_run):
    out, result = paper_run
    assert result.returncode == 0, result.stderr
    branch = np.load(out / "branch.npz")
    m = branch["F_x"].size
    assert {"F_x", "q", "xi", "eigenvalues", "n_complex", "residual", "leg"} <= set(branch.files)
    assert branch["q"].shape == (m, 30) and branch["xi"].shape == (m, 20)
    assert branch["eigenvalues"].shape == (m, 30) and branch["residual"].max() <= 1e-10
    records = json.loads((out / "collisions.json").read_text())
    assert records and all(r["kind"] in ("birth", "death") and r["matrix"] == "J" for r in records)
    assert all(0.0 < r["F_x"] < 0.12 and r["lambda_im"] == 0.0 for r in records)
    assert (out / "diagram.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_json_flag_prints_the_collision_list(paper_run):
    out, result = paper_run
    printed = json.loads(result.stdout)
    stored = json.loads((out / "collisions.json").read_text())
    assert printed == [{k: r[k] for k in ("F_x", "kind", "lambda_re", "lambda_im", "matrix")}
                       for r in stored]


BAD = [
    (["--fx", "0.1"], "--fx"),
    (["--fx", "a:b"], "--fx"),
    (["--fx", "0.1:0.1"], "--fx"),
    (["--fx", "-0.1:0.1"], "--fx"),
    (["--fx", "0:inf"], "--fx"),
    (["--matrix", "K"], "--matrix"),
    (["--ds-max", "-1"], "--ds-max"),
    (["missing.toml"], "missing.toml"),
]


@pytest.mark.parametrize("args, key", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_input_gets_one_line_and_exit_2(args, key, tmp_path):
    result = bifurcate(*args, "--out", str(tmp_path))
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and key in result.stderr
    assert "Traceback" not in result.stderr + result.stdout


def test_a_branch_that_cannot_start_fails_with_one_line(tmp_path):
    """mu = 0.1: the first load step already makes pairs slide and the relaxation stalls."""
    scene = tmp_path / "slippery.toml"
    scene.write_text("[contacts]\nmu = 0.1\n")
    result = bifurcate(str(scene), "--out", str(tmp_path))
    assert result.returncode == 1
    assert result.stderr.startswith("bifurcate error: ") and result.stderr.count("\n") == 1
    assert "Traceback" not in result.stderr
