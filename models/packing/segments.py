"""The segments of a shear run (models/packing/shear.py), and one as a file a rerun resumes from.

A segment is the branch between two plastic events: it starts from a relaxed state (the
prepared packing, or the state past a fold: models/packing/plastic.py) and is a function of that
state, the scene and the run's options alone (its window is sized at its start, its scans and
its labels are its own). So a run resumed after its finished segments, from the state where
the next one starts, gives the same branch as a run that was never interrupted, value for
value (tests/test_packing_shear.py). The file of a finished segment is an .npz read back with
allow_pickle=False (nothing in it is evaluated as code): per point arrays, and the ragged
ones (contact rows, histories, eigenvalues, condition numbers, a collision's vectors) as one
flat array with offsets.
"""
from __future__ import annotations

import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

from diskfriction.continuation.branch import Stop, StopCode
from diskfriction.continuation.detection.collisions import Collision, Kind
from diskfriction.files import save_npz
from diskfriction.models.packing.plastic import PlasticEvent


@dataclass(frozen=True)
class Point:
    """An accepted point of a shear run: strain, state q, the committed contact rows and their
    histories, the tracked eigenvalues, max|F| [force], active contacts, loose disks, stress
    (sigma_xx, sigma_yy, sigma_xy, sigma_yx) [force / length], the segment and the window
    block (a stretch with one window size) it belongs to, and the eigenvalues' condition
    numbers."""

    gamma: float
    q: np.ndarray
    rows: np.ndarray
    xi: np.ndarray
    eigenvalues: np.ndarray
    residual: float
    contacts: int
    loose: int
    stress: np.ndarray
    segment: int
    block: int
    condition: np.ndarray


@dataclass(frozen=True)
class ShearSegment:
    """What one segment of a shear run found: its points, collisions (all, the scene's gamma
    range applied later), the steps cut at contact events, Branch.continued rows per window
    block, how often its window was widened, how it ended (status: the last run's Stop), and
    where it was passed: the plastic event at its end and the state (q, xi, rows, gamma) the
    next segment starts from (None while it is the run's last)."""

    points: tuple[Point, ...]
    collisions: tuple[Collision, ...]
    events: int
    continued: dict
    widenings: int
    status: Stop
    plastic: Optional[PlasticEvent] = None
    next_start: Optional[tuple] = None


_POINT_SCALARS = ("gamma", "residual", "contacts", "loose", "segment", "block")
_POINT_RAGGED = ("rows", "xi", "eigenvalues", "condition")
_COLLISION_SCALARS = ("p", "eigenvalue", "left_right_overlap", "residual", "step", "resolved")
_COLLISION_RAGGED = ("eigenvector", "generalized_eigenvector", "u")
_PLASTIC_NUMBERS = ("gamma", "stress_before", "stress_after", "displacement", "steps")


def _flat(arrays: list) -> tuple[np.ndarray, np.ndarray]:
    """(the arrays' rows concatenated, the offsets of each: offsets[i]:offsets[i + 1])."""
    offsets = np.cumsum([0] + [len(a) for a in arrays])
    if not arrays:
        return np.zeros(0), offsets
    return np.concatenate([np.asarray(a) for a in arrays]), offsets


def _split(flat: np.ndarray, offsets: np.ndarray) -> list:
    """The arrays _flat joined."""
    return np.split(flat, offsets[1:-1])


def save_segment(path: Path, segment: ShearSegment, key: str) -> None:
    """A finished segment (passed: plastic and next_start set) as an .npz, written atomically,
    tagged with `key` (what the caller's results depend on: load_segment refuses another)."""
    P, C = segment.points, segment.collisions
    status = segment.status
    arrays = {"key": np.array(key), "events": np.array(segment.events),
              "widenings": np.array(segment.widenings),
              "status": np.array([str(status.code), status.reason]),
              "status_p": np.array(np.nan if status.p is None else status.p),
              "q": np.array([p.q for p in P]), "stress": np.array([p.stress for p in P])}
    for name in _POINT_SCALARS:
        arrays[f"point_{name}"] = np.array([getattr(p, name) for p in P])
    for name in _POINT_RAGGED:
        arrays[f"point_{name}"], arrays[f"point_{name}_at"] = _flat([getattr(p, name) for p in P])
    arrays["collision_kind"] = np.array([str(c.kind) for c in C], dtype=str)
    arrays["collision_bracket"] = np.array([c.bracket for c in C]).reshape(len(C), 2)
    arrays["collision_pair"] = np.array([c.pair for c in C], dtype=np.int64).reshape(len(C), 2)
    for name in _COLLISION_SCALARS:
        arrays[f"collision_{name}"] = np.array([getattr(c, name) for c in C])
    for name in _COLLISION_RAGGED:
        arrays[f"collision_{name}"], arrays[f"collision_{name}_at"] = _flat([getattr(c, name)
                                                                             for c in C])
    blocks = sorted(segment.continued)
    arrays["continued_blocks"] = np.array(blocks, dtype=np.int64)
    for b in blocks:  # None: the block's run tracked every eigenvalue (no window)
        if segment.continued[b] is not None:
            arrays[f"continued_{b}"] = np.array(segment.continued[b], dtype=bool)
    event = segment.plastic
    arrays["plastic"] = np.array([getattr(event, name) for name in _PLASTIC_NUMBERS], dtype=float)
    arrays["plastic_kind"] = np.array(event.kind)
    q, xi, rows, gamma = segment.next_start
    arrays.update(next_q=q, next_xi=xi, next_rows=rows, next_gamma=np.array(gamma))
    save_npz(path, **arrays)


class SegmentFileError(ValueError):
    """A segment file that cannot be read, or was written for other inputs or code."""


def load_segment(path: Path, key: str) -> ShearSegment:
    """The segment save_segment wrote at `path` with `key`; SegmentFileError otherwise (a
    missing, empty, truncated or damaged file included)."""
    try:
        with np.load(path, allow_pickle=False) as data:
            d = {name: data[name] for name in data.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as error:
        reason = (str(error).splitlines() or [type(error).__name__])[0]
        reason = reason if len(reason) <= 80 else reason[:77] + "..."  # a zip's message quotes its bytes
        raise SegmentFileError(f"{path}: unreadable ({reason})") from None
    if str(d.get("key")) != key:
        raise SegmentFileError(f"{path}: written for other inputs or another code version")
    try:
        return _segment_of(d)
    except (KeyError, IndexError, ValueError, TypeError) as error:
        raise SegmentFileError(f"{path}: incomplete ({error})") from None


def _segment_of(d: dict) -> ShearSegment:
    """The ShearSegment of a segment file's arrays (load_segment)."""
    ragged = {name: _split(d[f"point_{name}"], d[f"point_{name}_at"]) for name in _POINT_RAGGED}
    points = tuple(Point(gamma=float(d["point_gamma"][i]), q=d["q"][i], rows=ragged["rows"][i],
                         xi=ragged["xi"][i], eigenvalues=ragged["eigenvalues"][i],
                         residual=float(d["point_residual"][i]), contacts=int(d["point_contacts"][i]),
                         loose=int(d["point_loose"][i]), stress=d["stress"][i],
                         segment=int(d["point_segment"][i]), block=int(d["point_block"][i]),
                         condition=ragged["condition"][i])
                   for i in range(d["point_gamma"].size))
    vectors = {name: _split(d[f"collision_{name}"], d[f"collision_{name}_at"])
               for name in _COLLISION_RAGGED}
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
    continued = {int(b): list(d[f"continued_{b}"]) if f"continued_{b}" in d else None
                 for b in d["continued_blocks"]}
    numbers = dict(zip(_PLASTIC_NUMBERS, (float(v) for v in d["plastic"])))
    plastic = PlasticEvent(**{**numbers, "steps": int(numbers["steps"])}, kind=str(d["plastic_kind"]))
    code, reason = (str(v) for v in d["status"])
    p = float(d["status_p"])
    status = Stop(StopCode(code), reason, None if np.isnan(p) else p)
    return ShearSegment(points, collisions, int(d["events"]), continued, int(d["widenings"]), status,
                        plastic, (d["next_q"], d["next_xi"], d["next_rows"], float(d["next_gamma"])))
