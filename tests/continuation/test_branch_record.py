"""The one branch record (continuation/branch.py) and its files (continuation/records.py): a
branch answers its parameter, state, columns, labelled points and pieces by name; a record hook
gives its columns; collisions.json names the parameter; a branch's complete arrays read back
value for value."""
from __future__ import annotations

import dataclasses
import json
import pickle

import numpy as np
import pytest

from diskfriction.continuation import solve_branch
from diskfriction.continuation.branch import Branch, Piece, Stop, StopCode, column_of
from diskfriction.continuation.records import (branch_arrays, branch_of, collisions_json,
                                               complete_arrays)
from diskfriction.files import json_text
from diskfriction.models.packing.plastic import PlasticEvent

from gallery import load_example

REACHED = Stop(StopCode.REACHED)


def small_branch(**names) -> Branch:
    """Four points in two legs, with a ragged and a stacked column and labelled points."""
    rows = (np.zeros((1, 4), int), np.ones((2, 4), int), np.ones((2, 4), int), np.zeros((3, 4), int))
    return Branch(p=np.array([0.0, 0.1, 0.2, 0.15]), u=np.arange(8.0).reshape(4, 2),
                  eigenvalues=np.ones((4, 2), complex), n_complex=np.array([0, 0, 1, 0]),
                  residual=np.full(4, 1e-12), collisions=(), status=Stop(StopCode.FOLD, "folded", 0.15),
                  columns={"xi": np.arange(4.0)[:, None], "rows": column_of(rows, ragged=True)},
                  pieces=(Piece("leg", 0, 0, 2, REACHED), Piece("leg", 1, 2, 4, Stop(StopCode.FOLD))),
                  labelled={"plastic": (PlasticEvent(0.15, 1.0, 0.5, 0.1, 10),)},
                  **names)


def test_a_branch_answers_its_names_columns_labelled_points_and_pieces():
    branch = small_branch(parameter="gamma", state="q")
    assert branch.gamma is branch.p and branch.q is branch.u and branch.xi.shape == (4, 1)
    assert isinstance(branch.rows, tuple) and [r.shape[0] for r in branch.rows] == [1, 2, 2, 3]
    assert branch.plastic[0].gamma == 0.15
    assert branch.leg.tolist() == [0, 0, 1, 1] and branch.holding(2).tolist() == [2, 3]
    with pytest.raises(AttributeError, match="'F_x'"):
        branch.F_x
    again = pickle.loads(pickle.dumps(branch))  # whole, its attributes by name too
    assert np.array_equal(again.gamma, branch.gamma) and again.leg.tolist() == [0, 0, 1, 1]


@pytest.mark.parametrize("names", [dict(parameter="tangent"), dict(state="q", parameter="q"),
                                   dict(parameter="xi")])
def test_a_branch_refuses_names_that_hide_another(names):
    with pytest.raises(ValueError, match="must differ"):
        small_branch(**names)


def test_a_column_is_stacked_where_its_points_share_a_shape():
    assert column_of([np.zeros(3), np.ones(3)]).shape == (2, 3)
    assert isinstance(column_of([np.zeros(3), np.ones(2)]), tuple)
    assert isinstance(column_of([np.zeros(3), np.ones(3)], ragged=True), tuple)


def test_a_record_hook_gives_the_columns_and_may_give_the_residual():
    """Ziegler's column (examples/ziegler.py) with a record of |u|^2 and a residual of its own:
    one value per accepted point, in order, the residual replaced."""
    spec = load_example("ziegler").problem
    result = solve_branch(spec.problem, spec.start(0.0), (0.0, 6.0), spec.options,
                          record=lambda p, u: {"norm2": float(u @ u), "residual": -p})
    branch = result.branch
    assert np.array_equal(branch.norm2, np.einsum("ij,ij->i", branch.u, branch.u))
    assert np.array_equal(branch.residual, -branch.p)


def test_collisions_json_names_the_parameter_and_a_branch_reads_back_value_for_value(tmp_path):
    """The problem's branch with its names: collisions.json's object (strict JSON, each
    collision keyed p), branch.npz's arrays under the parameter's name, and the complete
    arrays back through an .npz as the same branch."""
    from diskfriction.files import save_npz
    from diskfriction.reports.problem import problem_branch

    example = load_example("ziegler")
    spec = example.problem
    branch = problem_branch(spec.solve((0.0, 6.0)), spec)
    found = json.loads(json_text(collisions_json(branch, scene={"name": "ziegler"})))
    assert (found["parameter"], found["units"], found["matrix"]) == ("P", "k/l", "M^-1 K")
    assert found["window"] is None and found["scene"] == {"name": "ziegler"}
    assert [(c["p"], c["kind"], c["lambda"]) for c in found["collisions"]] == [
        (c.p, str(c.kind), c.eigenvalue) for c in branch.collisions] and len(branch.collisions) == 2
    arrays = branch_arrays(branch)
    assert arrays["P"] is branch.p and str(arrays["parameter"]) == "P" and str(arrays["state"]) == "u"
    assert np.isnan(arrays["window"]).all() and str(arrays["status"]) == "reached"
    ragged = dataclasses.replace(small_branch(parameter="gamma", state="q"),
                                 collisions=branch.collisions)
    for original in (dataclasses.replace(branch, labelled={}), dataclasses.replace(ragged, labelled={})):
        save_npz(tmp_path / "b.npz", **complete_arrays(original))
        with np.load(tmp_path / "b.npz", allow_pickle=False) as data:
            back = branch_of({name: data[name] for name in data.files})
        for f in dataclasses.fields(Branch):
            if f.name in ("ds", "newton_iterations", "tangent", "detection_solves", "continued",
                          "warnings"):  # the core run's own: a joined branch has none
                continue
            a, b = getattr(original, f.name), getattr(back, f.name)
            if f.name == "columns":
                assert a.keys() == b.keys()
                for name in a:
                    assert type(a[name]) is type(b[name])
                    assert all(np.array_equal(x, y) for x, y in zip(a[name], b[name]))
            elif isinstance(a, np.ndarray):
                assert np.array_equal(a, b, equal_nan=True) and a.dtype == b.dtype, f.name
            elif f.name == "collisions":
                assert [(c.p, c.kind, c.pair, c.step) for c in a] == [(c.p, c.kind, c.pair, c.step) for c in b]
                assert all(np.array_equal(x.eigenvector, y.eigenvector) for x, y in zip(a, b))
            else:
                assert a == b, f.name
