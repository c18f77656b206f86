"""`diskfriction bifurcate --problem FILE.py[:NAME]`: a problem from the user's file, its
outputs in the problem's own names, and one line naming the file for everything wrong."""
from __future__ import annotations

import json
import textwrap

import numpy as np
import pytest
from commandline import error_line, run_cli

from diskfriction.cli.main import main

from gallery import EXAMPLES

HEADER = """
import numpy as np
from diskfriction.continuation import BifurcationProblem, problem_from_functions
"""
LINEAR = """
def make(G=lambda u, p: u - p, dG_du=lambda u, p: np.eye(2), **names):
    return BifurcationProblem(problem_from_functions(G, dG_du=dG_du, dG_dp=lambda u, p: -np.ones(2)),
                              u0=np.zeros(2), **names)
"""


@pytest.mark.slow
def test_ziegler_file_writes_the_outputs_in_its_own_names_and_units(tmp_path):
    """One run of the gallery's Ziegler file in a fresh interpreter: exit 0, progress one line
    per stage, branch.npz keyed P, collisions.json records keyed P at (7/2 -+ sqrt 2) k/l,
    special_points.json, the diagram, and --json on stdout."""
    out = tmp_path / "ziegler"
    result = run_cli("bifurcate", "--problem", str(EXAMPLES / "ziegler.py"), "--p", "0:6",
                     "--out", str(out), "--json")
    assert result.returncode == 0, result.stderr
    assert [line.split(": ")[1].split(" ")[0] for line in result.stderr.splitlines()] == [
        "continuation", "writing", "plotting"]
    branch = np.load(out / "branch.npz", allow_pickle=False)
    assert {"P", "u", "eigenvalues", "n_complex", "residual"} <= set(branch.files)
    assert (str(branch["parameter"]), str(branch["units"]), str(branch["matrix"])) == ("P", "k/l", "M^-1 K")
    assert branch["P"][0] == 0.0 and branch["P"][-1] == 6.0 and branch["u"].shape == (branch["P"].size, 2)
    found = json.loads((out / "collisions.json").read_text())
    assert (found["parameter"], found["units"], found["matrix"]) == ("P", "k/l", "M^-1 K")
    records = found["collisions"]
    assert [r["kind"] for r in records] == ["birth", "death"]
    assert [r["p"] for r in records] == pytest.approx([3.5 - np.sqrt(2), 3.5 + np.sqrt(2)], abs=1e-10)
    assert json.loads(result.stdout) == [{k: r[k] for k in ("p", "kind", "lambda")} for r in records]
    special = json.loads((out / "special_points.json").read_text())
    assert special["parameter"] == "P" and special["special_points"] == []
    assert (out / "diagram.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow
def test_a_file_that_fails_to_import_is_one_line_and_exit_2_in_a_fresh_interpreter(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("import numpy\n\nraise RuntimeError('no lattice here')\n")
    result = run_cli("bifurcate", "--problem", str(bad), "--out", str(tmp_path / "out"))
    assert result.returncode == 2
    assert error_line(result, "bifurcate") == (f"bifurcate error: {bad}: failed to import: "
                                               "RuntimeError: no lattice here (line 3)")
    assert not (tmp_path / "out" / "branch.npz").exists()


def run_in_process(capsys, *args: str) -> tuple[int, str]:
    """(exit code, last stderr line) of `diskfriction bifurcate ARGS` run in this process."""
    code = main(["bifurcate", *args])
    return code, capsys.readouterr().err.strip().splitlines()[-1]


BAD_FILES = {
    "syntax": ("def G(u, p):\n    return (u\n", "failed to import: SyntaxError: '(' was never closed (line 2)"),
    "raises": ("import numpy\nx = 1 / 0\n", "failed to import: ZeroDivisionError: division by zero (line 2)"),
    "exits": ("import sys\nsys.exit(3)\n", "failed to import: SystemExit: 3 (line 2)"),
    "nothing": ("x = 1\n", "no object named 'problem'; it defines no BifurcationProblem"),
    "other_name": (HEADER + LINEAR + "second = make(p_span=(0, 1))\n",
                   "no object named 'problem'; it defines second"),
    "wrong_type": ("problem = [1, 2]\n", "problem is a list, not a diskfriction.continuation.BifurcationProblem"),
    "residual_shape": (HEADER + LINEAR + "problem = make(G=lambda u, p: np.zeros(3), p_span=(0, 1))\n",
                       "problem: G(u, p) returned shape (3,), expected (2,) (u0 has 2 entries)"),
    "jacobian_shape": (HEADER + LINEAR + "problem = make(dG_du=lambda u, p: np.ones((2, 3)), p_span=(0, 1))\n",
                       "problem: dG/du returned shape (2, 3), expected (2, 2)"),
    "raises_inside": (HEADER + LINEAR + "problem = make(G=lambda u, p: u[7], p_span=(0, 1))\n",
                      "problem: G(u, p) raised IndexError at p = 0: index 7 is out of bounds"),
    "reserved": (HEADER + LINEAR + "problem = make(p_span=(0, 1), parameter='eigenvalues')\n",
                 "problem: parameter name 'eigenvalues' clashes with the outputs' keys"),
    "not_a_name": (HEADER + LINEAR + "problem = make(p_span=(0, 1), parameter='P [N]')\n",
                   "failed to import: ValueError: parameter must be a name such as P, F_x or I"),
}


@pytest.mark.parametrize("name", BAD_FILES)
def test_a_bad_problem_file_is_one_line_naming_the_file_and_exit_2(tmp_path, capsys, name):
    text, what = BAD_FILES[name]
    path = tmp_path / f"{name}.py"
    path.write_text(text)
    code, line = run_in_process(capsys, "--problem", str(path), "--out", str(tmp_path / "out"))
    assert code == 2
    assert line.startswith(f"bifurcate error: {path}") and what in line, line
    assert not (tmp_path / "out" / "branch.npz").exists()


@pytest.mark.parametrize("target, args, what", [
    ("missing.py", (), "missing.py: no such file"),
    ("notes.txt", (), "notes.txt: not a Python file (.py)"),
    ("two.py:third", (), "two.py: no object named 'third'; it defines first, second"),
    ("two.py:first", (), "--p: needed, {dir}/two.py:first has no p_span"),
    ("two.py:second", ("--p", "1:1"), "--p: empty range (got '1:1')"),
    ("two.py:second", ("--fx", "0:1"), "--problem: takes no --fx"),
    ("two.py:second", ("--window", "0:1"), "--problem: takes no --window"),  # was ignored (issue 23)
    ("two.py:second", ("--workers", "2", "--detection", "exhaustive"), "--workers: scan workers"),
    ("two.py:second", ("--p", "a:b"), "--p: expected A:B with two numbers"),
])
def test_targets_and_options_are_checked_before_anything_runs(tmp_path, capsys, target, args, what):
    (tmp_path / "notes.txt").write_text("P = 1\n")
    (tmp_path / "two.py").write_text(HEADER + LINEAR + "first = make()\nsecond = make(p_span=(0, 1))\n")
    code, line = run_in_process(capsys, "--problem", str(tmp_path / target), *args)
    assert code == 2 and what.format(dir=tmp_path) in line, line


def test_p_is_refused_without_a_problem(capsys):
    code, line = run_in_process(capsys, "--p", "0:1")
    assert code == 2 and line.startswith("bifurcate error: --p: ") and "--problem" in line


@pytest.mark.slow
def test_name_selects_the_problem_and_p_its_span(tmp_path, capsys):
    """FILE.py:NAME runs NAME; --p overrides its span, negative values included."""
    path = tmp_path / "two.py"
    path.write_text(HEADER + LINEAR + textwrap.dedent("""
        first = make(p_span=(0, 1))
        second = make(p_span=(0, 1), parameter="T", units="K")
    """))
    assert main(["bifurcate", "--problem", f"{path}:second", "--p=-1:2", "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert "T -1 -> 2 K" in out
    branch = np.load(tmp_path / "o" / "branch.npz", allow_pickle=False)
    assert branch["T"][[0, -1]].tolist() == [-1.0, 2.0]
    assert np.allclose(branch["u"], branch["T"][:, None], atol=1e-10)


def test_a_problem_that_fails_inside_the_run_ends_it_with_one_line_and_exit_1(tmp_path, capsys):
    """G raises only beyond p = 0.5: the start is fine, the run stops there with one line
    saying where, and nothing is written."""
    path = tmp_path / "late.py"
    path.write_text(HEADER + LINEAR + textwrap.dedent("""
        def G(u, p):
            if p > 0.5:
                raise FloatingPointError("the model is not defined beyond 0.5")
            return u - p

        problem = make(G=G, p_span=(0, 1))
    """))
    code, line = run_in_process(capsys, "--problem", str(path), "--out", str(tmp_path / "out"))
    assert code == 1
    assert line.startswith(f"bifurcate error: {path}:problem: the run stopped at p = 0.")
    assert line.endswith("FloatingPointError: the model is not defined beyond 0.5")
    assert not (tmp_path / "out" / "branch.npz").exists()


@pytest.mark.slow
def test_detection_applies_to_a_problem_file(tmp_path, capsys):
    """--detection exhaustive (bisection with full spectra) on Ziegler's file: the same two
    collisions to 1e-10; an unknown detection is refused before the file is imported."""
    target = str(EXAMPLES / "ziegler.py")
    assert main(["bifurcate", "--problem", target, "--detection", "exhaustive", "--json",
                 "--out", str(tmp_path / "z")]) == 0
    records = json.loads(capsys.readouterr().out)
    assert [r["p"] for r in records] == pytest.approx([3.5 - np.sqrt(2), 3.5 + np.sqrt(2)], abs=1e-10)
    code, line = run_in_process(capsys, "--problem", str(tmp_path / "missing.py"), "--detection", "slow")
    assert code == 2 and line.startswith("bifurcate error: --detection: ") and "'slow'" in line


@pytest.mark.slow
def test_a_branch_that_folds_back_out_of_its_span_exits_1_with_one_line(tmp_path):
    """G = u^2 - p from p = 1 towards -1 (issue 23): the branch turns at the fold p = 0 and
    leaves the span at p = 1 again, never reaching -1. What it reached is written and printed
    (the parameter's path through the fold), and the command fails with one line."""
    source = tmp_path / "fold.py"
    source.write_text(HEADER + textwrap.dedent("""
        problem = BifurcationProblem(
            problem_from_functions(lambda u, p: np.array([u[0] ** 2 - p]),
                                   dG_du=lambda u, p: np.array([[2 * u[0]]]),
                                   dG_dp=lambda u, p: np.array([-1.0])),
            u0=np.array([1.0]), p_span=(1.0, -1.0))
        """))
    out = tmp_path / "out"
    result = run_cli("bifurcate", "--problem", str(source), "--out", str(out))
    assert result.returncode == 1
    line = error_line(result, "bifurcate")
    assert "did not reach p = -1" in line and "folded" in line
    first = result.stdout.splitlines()[0]
    assert " p 1 -> " in first and first.split(" -> ")[2].startswith("1,")  # back to 1
    assert abs(float(first.split(" -> ")[1])) < 1e-9  # through the located fold
    assert (out / "branch.npz").exists()


@pytest.mark.slow
def test_only_the_problem_that_runs_says_its_derivatives_are_differenced(tmp_path, capsys):
    """Two problems without derivatives in one file: one warning line, naming the one run."""
    path = tmp_path / "two.py"
    path.write_text(HEADER + textwrap.dedent("""
        def make():
            return BifurcationProblem(problem_from_functions(lambda u, p: u - p),
                                      u0=np.zeros(2), p_span=(0, 1))
        first, second = make(), make()
    """))
    assert main(["bifurcate", "--problem", f"{path}:second", "--out", str(tmp_path / "o")]) == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert len(lines) == 1 and f"{path}:second: dG/du and dG/dp not given" in lines[0]


def test_a_sparse_jacobian_gives_the_branch_of_the_dense_one():
    """Bratu's discrete problem, u'' + lambda e^u = 0 on n = 40 points, with dG/du as a
    scipy.sparse matrix (refused before, 'setting an array element with a sequence') and as
    its dense array: the same points and the same fold."""
    import scipy.sparse as sp

    from diskfriction.continuation import Options, problem_from_functions, solve_branch

    n = 40
    L = sp.diags([np.ones(n - 1), -2.0 * np.ones(n), np.ones(n - 1)], [-1, 0, 1]) * (n + 1) ** 2

    def run(dG_du):
        problem = problem_from_functions(lambda u, lam: L @ u + lam * np.exp(u), dG_du=dG_du,
                                         dG_dp=lambda u, lam: np.exp(u))
        return solve_branch(problem, np.zeros(n), (0.0, 3.6),
                            Options(ds_max=0.5, max_steps=40, special_points=("fold",)))

    sparse = run(lambda u, lam: (L + sp.diags(lam * np.exp(u))).tocsr())
    dense = run(lambda u, lam: (L + sp.diags(lam * np.exp(u))).toarray())
    assert len(sparse.folds) == len(dense.folds) == 1 and 3.4 < sparse.folds[0].p < 3.6
    assert abs(sparse.folds[0].p - dense.folds[0].p) <= 1e-10
    assert sparse.p.size == dense.p.size and np.allclose(sparse.u, dense.u, rtol=0, atol=1e-9)
