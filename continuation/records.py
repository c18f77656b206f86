"""A branch as files, for every problem (a chain's sweep, a packing's shear, a problem file's
run), each written by one function from the one record (branch.Branch), in the problem's raw
units:

- branch.npz (save_branch, branch_arrays): the per-point arrays, the pieces' labels, the
  labelled points' locations and the names (docs/outputs.md);
- collisions.json (save_collisions, collisions_json): one object naming the parameter, its
  units, the matrix and the window, with one record per located collision (collision_record);
- a branch complete, to be read back (complete_arrays, branch_of): what a run that resumes
  needs, e.g. a packing's finished segments (models/packing/segments.py).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np

from diskfriction.continuation.branch import Branch, EventPoint, Piece, Stop, StopCode
from diskfriction.continuation.detection.detectors import Collision
from diskfriction.continuation.spectra.tracking import Kind
from diskfriction.files import save_json, save_npz

Array = np.ndarray

RECORD_KEYS = ("p", "kind", "lambda", "bracket", "resolved", "residual", "eigenvector",
               "jordan_vector", "condition", "condition_amplitude")
"""The keys of a collision's record in collisions.json (collision_record)."""
HEADER_KEYS = ("parameter", "units", "matrix", "eigenvalue_units", "window")
"""The keys of collisions.json besides "collisions" and what a caller adds (a packing's scene)."""
NAME_KEYS = ("parameter", "units", "state", "matrix", "eigenvalue_units", "window", "status")
"""The 0-d arrays of branch.npz that name what it holds (branch_arrays); the window is (2,)."""


def pair_condition(p: Array, condition: Optional[Array], c: Collision,
                   collisions: Sequence[Collision]):
    """([kappa before, kappa after], [amplitude before, amplitude after]) of collision c's
    pair at the accepted points p[k], p[k + 1] around it: kappa the larger condition number of
    its two members there (Branch.condition, columns = labels), amplitude = kappa sqrt|p -
    p_c| (kappa diverges like |p - p_c|^(-1/2) at a collision: the amplitude is the pair's
    non-normality, nearly the same on both sides for points close to p_c). None if the
    condition numbers are not known (None, or nan at either point) or no interval holds p_c.
    The amplitude is None where another of the branch's `collisions` in the same interval
    involves a member of the pair: kappa at the interval's ends then follows both collisions,
    not c's law alone."""
    if condition is None:
        return None
    around = np.flatnonzero((p[:-1] - c.p) * (p[1:] - c.p) <= 0.0)
    if not around.size:
        return None
    k = int(around[0])
    kappa = [float(np.max(condition[r, list(c.pair)])) for r in (k, k + 1)]
    if not np.all(np.isfinite(kappa)):
        return None
    lo, hi = sorted((p[k], p[k + 1]))
    if any(other is not c and lo <= other.p <= hi and set(other.pair) & set(c.pair) for other in collisions):
        return kappa, None
    return kappa, [float(kap * np.sqrt(abs(p[r] - c.p))) for kap, r in zip(kappa, (k, k + 1))]


def collision_record(c: Collision, condition=None) -> dict:
    """One located collision as a JSON object (RECORD_KEYS): p, the parameter there; kind,
    "birth" (two real eigenvalues leave the real axis as a complex pair, along the branch) or
    "death"; lambda, the double real eigenvalue (the pair's imaginary part is 0 there by
    definition); bracket, the parameter interval (width <= the detection's tol_p when
    resolved) across which the count of complex pairs changes; resolved, False where the
    step's detection budget ran out or the bracket could not be isolated; residual, max|G| at
    the located point; eigenvector and jordan_vector, the Jordan chain (A - lambda) v = 0,
    (A - lambda) w = v of the tracked matrix A; condition and condition_amplitude
    (pair_condition: [before, after]), None where not known."""
    kappa, amplitude = (None, None) if condition is None else condition
    return {"p": float(c.p), "kind": str(c.kind), "lambda": float(c.eigenvalue),
            "bracket": [float(b) for b in c.bracket], "resolved": bool(c.resolved),
            "residual": float(c.residual),
            "eigenvector": np.asarray(c.eigenvector, dtype=float).tolist(),
            "jordan_vector": np.asarray(c.generalized_eigenvector, dtype=float).tolist(),
            "condition": kappa, "condition_amplitude": amplitude}


def collision_records(branch: Branch) -> list[dict]:
    """The branch's collisions as records (collision_record), in branch order, with their
    pairs' condition numbers from the points of the pieces holding each (a chain's requested
    leg, a packing's segment: Branch.holding); none with a window, whose columns are not the
    pairs' labels."""
    known = branch.window is None and branch.condition is not None
    records = []
    for c in branch.collisions:
        condition = None
        if known:
            rows = branch.holding(min(c.step + 1, len(branch) - 1))  # the step's end: its own
            condition = pair_condition(branch.p[rows], branch.condition[rows], c, branch.collisions)
        records.append(collision_record(c, condition))
    return records


BRIEF_KEYS = ("p", "kind", "lambda")
"""What `bifurcate --json` prints of each collision's record (brief)."""


def brief(records: Sequence[dict]) -> list[dict]:
    """Collision records as `bifurcate --json` prints them: p, kind and lambda of each."""
    return [{key: r[key] for key in BRIEF_KEYS} for r in records]


def collisions_json(branch: Branch, **extra) -> dict:
    """collisions.json's object: parameter (its name), units (its units, "" for none), matrix
    (the tracked matrix's name), eigenvalue_units (its eigenvalues'), window ([lo, hi] of Re
    lambda tracked and certified, only collisions there listed, or None for the whole
    spectrum), what `extra` adds (a packing's scene record) and collisions (collision_records)."""
    window = None if branch.window is None else [float(w) for w in branch.window]
    return {"parameter": branch.parameter, "units": branch.units, "matrix": str(branch.matrix),
            "eigenvalue_units": branch.eigenvalue_units, "window": window, **extra,
            "collisions": collision_records(branch)}


def save_collisions(path: Path, branch: Branch, **extra) -> None:
    """collisions.json (collisions_json), strict JSON, written atomically."""
    save_json(Path(path), collisions_json(branch, **extra))


def location(point: Any, parameter: str) -> float:
    """Where a labelled point lies: its p, or its value under the parameter's name (a packing's
    PlasticEvent.gamma)."""
    return float(point.p if hasattr(point, "p") else getattr(point, parameter))


def branch_arrays(branch: Branch) -> dict[str, Array]:
    """branch.npz's arrays: the parameter's values and the states under their names (F_x or
    gamma and q; a problem's own and u), eigenvalues, condition, n_complex, residual, every
    column whose points share a shape (Branch.columns), each kind of piece as its labels
    (Branch.labels: leg, segment, run), each label of labelled points as their locations
    ("{label}_{parameter}", e.g. plastic_gamma), and NAME_KEYS as strings: parameter, units,
    state, matrix, eigenvalue_units, window [lo, hi] (nan nan for the whole spectrum) and
    status (how the run ended, in words: Stop.sentence)."""
    arrays = {branch.parameter: branch.p, branch.state: branch.u, "eigenvalues": branch.eigenvalues,
              "n_complex": branch.n_complex, "residual": branch.residual}
    if branch.condition is not None:
        arrays["condition"] = branch.condition
    arrays |= {name: column for name, column in branch.columns.items()
               if isinstance(column, np.ndarray)}
    arrays |= {kind: branch.labels(kind) for kind in dict.fromkeys(p.kind for p in branch.pieces)}
    arrays |= {f"{label}_{branch.parameter}": np.array([location(x, branch.parameter) for x in points],
                                                       dtype=float)
               for label, points in branch.labelled.items()}
    window = (np.nan, np.nan) if branch.window is None else branch.window
    return arrays | {"parameter": np.array(branch.parameter), "units": np.array(branch.units),
                     "state": np.array(branch.state), "matrix": np.array(str(branch.matrix)),
                     "eigenvalue_units": np.array(branch.eigenvalue_units),
                     "window": np.array(window, dtype=float),
                     "status": np.array(branch.status.sentence(len(branch)))}


def save_branch(path: Path, branch: Branch, **extra: Array) -> None:
    """branch.npz (branch_arrays, and the arrays `extra` adds: a scene's), written atomically."""
    save_npz(Path(path), **branch_arrays(branch), **extra)


_COLLISION_SCALARS = ("p", "eigenvalue", "left_right_overlap", "residual", "step", "resolved")
_COLLISION_VECTORS = ("eigenvector", "generalized_eigenvector", "u")


def _flat(arrays: Sequence) -> tuple[Array, Array]:
    """(the arrays' rows concatenated, the offsets of each: offsets[i]:offsets[i + 1])."""
    offsets = np.cumsum([0] + [len(a) for a in arrays])
    if not len(arrays):
        return np.zeros(0), offsets
    return np.concatenate([np.asarray(a) for a in arrays]), offsets


def _split(flat: Array, offsets: Array) -> list:
    """The arrays _flat joined."""
    return np.split(flat, offsets[1:-1])


def _stop_arrays(stops: Sequence[Stop]) -> tuple[Array, Array]:
    """((k, 2) str: code and reason, (k,) float: p, nan for None) of Stops."""
    words = np.array([[str(s.code), s.reason] for s in stops], dtype=str).reshape(len(stops), 2)
    return words, np.array([np.nan if s.p is None else s.p for s in stops], dtype=float)


def _stops(words: Array, at: Array) -> list[Stop]:
    """The Stops _stop_arrays wrote."""
    return [Stop(StopCode(str(code)), str(reason), None if np.isnan(p) else float(p))
            for (code, reason), p in zip(words, at)]


def complete_arrays(branch: Branch) -> dict[str, Array]:
    """The branch as arrays that branch_of reads back value for value (no pickle): branch_arrays,
    the columns whose points differ in shape (flat, "ragged_NAME" with offsets
    "ragged_NAME_at"), the pieces (piece_*), the collisions (collision_*: the Jordan chain and
    the state u of each too), the event points' rows, the status, events and widenings. The other
    labelled points are the model's to write (their records are its own)."""
    arrays = branch_arrays(branch)
    arrays["column_names"] = np.array([n for n, c in branch.columns.items()
                                       if isinstance(c, np.ndarray)], dtype=str)
    for name, column in branch.columns.items():
        if not isinstance(column, np.ndarray):
            arrays[f"ragged_{name}"], arrays[f"ragged_{name}_at"] = _flat(column)
    arrays["stop"], arrays["stop_p"] = (a[0] for a in _stop_arrays([branch.status]))
    P = branch.pieces
    arrays["piece_kind"] = np.array([p.kind for p in P], dtype=str)
    arrays["piece_rows"] = np.array([(p.label, p.start, p.stop) for p in P], dtype=np.int64).reshape(len(P), 3)
    arrays["piece_stop"], arrays["piece_stop_p"] = _stop_arrays([p.status for p in P])
    C = branch.collisions
    arrays["collision_kind"] = np.array([str(c.kind) for c in C], dtype=str)
    arrays["collision_bracket"] = np.array([c.bracket for c in C]).reshape(len(C), 2)
    arrays["collision_pair"] = np.array([c.pair for c in C], dtype=np.int64).reshape(len(C), 2)
    for name in _COLLISION_SCALARS:
        arrays[f"collision_{name}"] = np.array([getattr(c, name) for c in C])
    for name in _COLLISION_VECTORS:
        arrays[f"collision_{name}"], arrays[f"collision_{name}_at"] = _flat([getattr(c, name) for c in C])
    if "event" in branch.labelled:
        arrays["event_rows"] = np.array([e.row for e in branch.event], dtype=np.int64)
    arrays["events"], arrays["widenings"] = np.array(branch.events), np.array(branch.widenings)
    return arrays


def branch_of(d: dict[str, Array], labelled: Optional[dict] = None) -> Branch:
    """The Branch complete_arrays wrote, its event points and the labelled points `labelled` (the
    model's); a
    KeyError, IndexError or ValueError for arrays that are not such a branch's."""
    parameter, state = str(d["parameter"]), str(d["state"])
    columns = {str(name): d[str(name)] for name in d["column_names"]}
    columns |= {name[len("ragged_"):]: tuple(_split(d[name], d[f"{name}_at"])) for name in d
                if name.startswith("ragged_") and not name.endswith("_at")}
    kinds, rows = d["piece_kind"], d["piece_rows"]
    pieces = tuple(Piece(str(kind), int(label), int(start), int(stop), status) for kind, (label, start, stop), status
                   in zip(kinds, rows, _stops(d["piece_stop"], d["piece_stop_p"])))
    vectors = {name: _split(d[f"collision_{name}"], d[f"collision_{name}_at"]) for name in _COLLISION_VECTORS}
    collisions = tuple(
        Collision(p=float(d["collision_p"][i]), kind=Kind(str(d["collision_kind"][i])),
                  eigenvalue=float(d["collision_eigenvalue"][i]), eigenvector=vectors["eigenvector"][i],
                  generalized_eigenvector=vectors["generalized_eigenvector"][i],
                  left_right_overlap=float(d["collision_left_right_overlap"][i]),
                  bracket=tuple(float(b) for b in d["collision_bracket"][i]),
                  residual=float(d["collision_residual"][i]), u=vectors["u"][i],
                  step=int(d["collision_step"][i]), pair=tuple(int(k) for k in d["collision_pair"][i]),
                  resolved=bool(d["collision_resolved"][i]))
        for i in range(d["collision_p"].size))
    window = tuple(float(w) for w in d["window"])
    return Branch(d[parameter], d[state], d["eigenvalues"], d["n_complex"], d["residual"], collisions,
                  _stops(d["stop"][None], d["stop_p"][None])[0], d.get("condition"), columns, pieces,
                  _event_points(d, parameter) | (labelled or {}), events=int(d["events"]), window=None if np.isnan(window).all() else window,
                  widenings=int(d["widenings"]), parameter=parameter, units=str(d["units"]), state=state,
                  matrix=str(d["matrix"]), eigenvalue_units=str(d["eigenvalue_units"]))


def _event_points(d: dict[str, Array], parameter: str) -> dict[str, tuple]:
    """{"event": the EventPoints complete_arrays wrote}, or {} for a branch without them."""
    if "event_rows" not in d:
        return {}
    return {"event": tuple(EventPoint(float(d[parameter][k]), int(k)) for k in d["event_rows"])}
