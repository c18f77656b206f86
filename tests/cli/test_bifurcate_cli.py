"""`diskfriction bifurcate`: outputs, --json, and one-line errors for bad input."""
from __future__ import annotations

import json

import numpy as np
import pytest
from commandline import error_line, run_cli, run_main
from invariants import unaccounted_pair_changes


@pytest.fixture(scope="module")
def paper_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("bifurcate")
    return out, run_cli("bifurcate", "--out", str(out), "--json")


@pytest.mark.slow
def test_writes_branch_collisions_and_diagram(paper_run):
    out, result = paper_run
    assert result.returncode == 0, result.stderr
    branch = np.load(out / "branch.npz")
    m = branch["F_x"].size
    assert {"F_x", "q", "xi", "eigenvalues", "n_complex", "residual", "leg"} <= set(branch.files)
    assert branch["q"].shape == (m, 30) and branch["xi"].shape == (m, 20)
    assert branch["eigenvalues"].shape == (m, 30) and branch["residual"].max() <= 1e-10
    found = json.loads((out / "collisions.json").read_text())
    assert (found["parameter"], found["units"], found["matrix"]) == ("F_x", "force", "J")
    records = found["collisions"]
    assert records and all(r["kind"] in ("birth", "death") for r in records)
    assert all(0.0 < r["p"] < 0.12 for r in records)
    # the records account for every change of the pair count between consecutive points
    assert unaccounted_pair_changes(branch["F_x"], branch["n_complex"],
                                    [(r["p"], r["kind"]) for r in records]) == []
    assert (out / "diagram.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow
def test_progress_is_one_line_per_stage_when_stderr_is_not_a_terminal(paper_run):
    out, result = paper_run
    stages = [line.split(": ", 1)[1] for line in result.stderr.splitlines()]
    assert all(line.startswith("bifurcate: ") for line in result.stderr.splitlines())
    assert stages[0].startswith("kernels: ") and stages[-3].startswith("sweep F_x 0 -> 0.12")
    assert stages[-2].startswith("writing ") and stages[-1] == f"plotting {out}/diagram.png"
    assert len(stages) == len(set(stages))


@pytest.mark.slow
def test_the_diagram_draws_lines_windows_bubbles_and_a_key():
    """Two tracked columns form a pair between the collisions at 0.2 and 0.6 (sampled every
    0.1), and a bubble 1e-9 wide sits at 0.8: the pair is one line closed at Im = 0 by its
    collisions, its window shaded, the bubble one diamond, and the legend keys all of it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    from diskfriction.reports.bifurcation import draw_spectrum, narrow_bubbles, pair_line
    from diskfriction.reports.figures import handle_label

    F = np.linspace(0.0, 1.0, 11)
    im = np.where((F > 0.2) & (F < 0.6), 1e-3, 0.0)
    lam = np.column_stack([1 + 1j * im, 1 - 1j * im, np.full(F.size, 2.0 + 0j)])
    collisions = [(0.2, "birth", 1.0), (0.6, "death", 1.0), (0.8, "birth", 2.0),
                  (0.8 + 1e-9, "death", 2.0)]
    xs, ys = pair_line(F, np.where(im > 0, im, np.nan), collisions)
    assert list(xs[:2]) == [0.2, F[3]] and ys[0] == 0.0 and (xs[-2], ys[-2]) == (0.6, 0.0)
    assert narrow_bubbles(collisions, pixel=1e-3) == [2]
    fig, (top, bottom) = plt.subplots(2, 1)
    handles = draw_spectrum(top, bottom, F, lam, np.ones(F.size, int), np.zeros(F.size, int),
                            collisions, "J")
    labels = [handle_label(h) for h in handles]
    assert labels == ["loading 0 -> 1\n(one colour per eigenvalue)", "a complex pair (located windows)", "birth of a pair (2)",
                      "death of a pair (2)", "bubble narrower than a pixel (1)"]
    assert [line.get_xdata()[0] for line in top.get_lines() if line.get_marker() == "D"] == [0.8 + 5e-10]
    (pair,), re_lines = (c.get_segments() for ax in (top, bottom) for c in ax.collections
                         if isinstance(c, LineCollection))
    assert (pair[0].tolist(), pair[-1].tolist()) == ([0.2, 0.0], [0.6, 0.0])  # closed at both
    assert [xy[:, 1].tolist() for xy in re_lines] == [lam.real[:, k].tolist() for k in range(3)]
    assert top.get_ylim()[1] >= 1e-3 and bottom.get_ylim()[1] >= 2.0  # autoscaled to the lines
    spans = [p.get_x() for p in top.patches]
    assert spans == pytest.approx([0.2, 0.8])  # the window, and the bubble's (below a pixel)
    plt.close(fig)


@pytest.mark.slow
def test_json_flag_prints_the_collision_list(paper_run):
    out, result = paper_run
    printed = json.loads(result.stdout)
    stored = json.loads((out / "collisions.json").read_text())["collisions"]
    assert printed == [{k: r[k] for k in ("p", "kind", "lambda")} for r in stored]


BAD = [
    (["--fx", "0.1"], "--fx"),
    (["--fx", "a:b"], "--fx"),
    (["--fx", "0.1:0.1"], "--fx"),
    (["--fx", "-0.1:0.1"], "--fx"),
    (["--fx", "0:inf"], "--fx"),
    (["--matrix", "K"], "--matrix"),
    (["--ds-max", "-1"], "--ds-max"),
    (["--workers", "-1"], "--workers"),
    (["--workers", "2", "--detection", "exhaustive"], "--workers"),  # was ignored (issue 23)
    (["missing.toml"], "missing.toml"),
]


@pytest.mark.parametrize("args, key", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_input_gets_one_line_and_exit_2(args, key, tmp_path):
    result = run_main("bifurcate", *args, "--out", str(tmp_path))
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and key in result.stderr
    assert "Traceback" not in result.stderr + result.stdout


@pytest.mark.slow
def test_a_branch_that_cannot_start_fails_with_one_line(tmp_path):
    """mu = 0.1: the first load step already makes pairs slide and the relaxation stalls."""
    scene = tmp_path / "slippery.toml"
    scene.write_text("[contacts]\nmu = 0.1\n")
    result = run_cli("bifurcate", str(scene), "--out", str(tmp_path))
    assert result.returncode == 1
    assert "relaxation did not converge" in error_line(result, "bifurcate")


@pytest.mark.slow
def test_a_loading_and_unloading_sweep_says_what_each_leg_did(tmp_path):
    """--fx 0.06:0 loads from rest to 0.06, then unloads (issue 23: the summary said "F_x
    1e-05 .. 1e-05 ... status p_end, p_end")."""
    result = run_cli("bifurcate", "--fx", "0.06:0", "--out", str(tmp_path))
    assert result.returncode == 0, result.stderr
    legs = [line.strip() for line in result.stdout.splitlines() if line.strip().startswith("leg ")]
    assert len(legs) == 2
    assert legs[0].startswith("leg 0, preparation: loading from rest: F_x 1e-05 -> 0.06,")
    assert legs[1].startswith("leg 1, unloading: F_x 0.06 -> 1e-05,") and "reached" in legs[1]
    branch = np.load(tmp_path / "branch.npz")
    counts = [int(leg.split(" equilibria")[0].rsplit(", ", 1)[1]) for leg in legs]
    assert counts == [int((branch["leg"] == 0).sum()), int((branch["leg"] == 1).sum())]


@pytest.mark.slow
def test_a_sweep_stops_at_a_leg_that_ends_short_and_says_where(tmp_path):
    """A preparation leg that ends before its load (a 4-disk chain with mu = 1 folds over at
    F_x ~ 3e-5) is the sweep's last: no unloading from a load never reached; exit 1, one line."""
    scene = tmp_path / "short.toml"
    scene.write_text("[disks]\nN = 4\n[contacts]\nmu = 1.0\n")
    result = run_cli("bifurcate", str(scene), "--fx", "0.2:0", "--out", str(tmp_path / "out"))
    assert result.returncode == 1
    line = error_line(result, "bifurcate")
    assert "the sweep ended at F_x = " in line and "short of 0" in line and "there " in line
    branch = np.load(tmp_path / "out" / "branch.npz")
    assert set(branch["leg"].tolist()) == {0} and branch["F_x"][-1] < 1e-4


@pytest.mark.slow
def test_a_window_no_eigenvalue_enters_is_refused_with_one_line(tmp_path):
    """--window 5:6 lies above the whole spectrum (lambda / k_n <= 0.17): bifurcate used to say
    "0 collisions" for a band it never saw (issue 23); it fails with one line and writes nothing."""
    result = run_cli("bifurcate", "--window", "5:6", "--out", str(tmp_path / "out"))
    assert result.returncode == 1
    line = error_line(result, "bifurcate")
    assert "--window" in line and "no eigenvalue of J" in line and "'5:6'" in line
    assert not (tmp_path / "out" / "collisions.json").exists()


@pytest.mark.slow
def test_collisions_only_bracketed_are_counted_and_marked(tmp_path, monkeypatch, capsys):
    """With the detection's solve budget at 1 a step (500 by default), the paper's scene keeps
    some collisions bracketed but not located: the summary says how many, and each such line
    gives its bracket instead of passing for a located collision."""
    from diskfriction.cli.main import main
    from diskfriction.continuation.detection import collisions

    budget = collisions.DetectionParams  # what bifurcate imports when it runs
    monkeypatch.setattr(collisions, "DetectionParams", lambda **kw: budget(max_solves=1, **kw))
    assert main(["bifurcate", "--workers", "0", "--out", str(tmp_path)]) == 0
    records = json.loads((tmp_path / "collisions.json").read_text())["collisions"]
    unlocated = [r for r in records if not r["resolved"]]
    out = capsys.readouterr().out
    summary = f"{len(records)} collisions (J), {len(unlocated)} of them only bracketed"
    assert unlocated and summary in out, out
    assert out.count("bracketed only: F_x in [") == len(unlocated)
