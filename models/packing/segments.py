"""A finished segment of a shear run (models/packing/shear.py) as a file a rerun resumes from.

A segment is the branch between two plastic events: it starts from a relaxed state (the
prepared packing, or the state past a fold: models/packing/plastic.py) and is a function of that
state, the scene and the run's options alone (its window is sized at its start, its scans and
its labels are its own). So a run resumed after its finished segments, from the state where
the next one starts, gives the same branch as a run that was never interrupted, value for
value (tests/models/packing/test_packing_plastic.py). A segment is a Branch of one segment piece
(shear.shear_segment) whose plastic event, passed at its end, holds that state; its file is
the branch's complete arrays (continuation/records.complete_arrays: ragged columns and the
collisions' vectors flat with offsets), the plastic event's numbers and state, and a key, read
back with allow_pickle=False (nothing in it is evaluated as code).
"""
from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from diskfriction.continuation.branch import Branch
from diskfriction.continuation.records import branch_of, complete_arrays
from diskfriction.files import save_npz
from diskfriction.models.packing.plastic import PlasticEvent
from diskfriction.models.packing.sampled import SpectrumSample

_PLASTIC_NUMBERS = ("gamma", "stress_before", "stress_after", "displacement", "steps")


def save_segment(path: Path, segment: Branch, key: str) -> None:
    """A finished segment (its plastic event passed, with the state after it) as an .npz,
    written atomically, tagged with `key` (what the caller's results depend on: load_segment
    refuses another)."""
    event, = segment.plastic
    q, xi, rows, gamma = event.after
    save_npz(path, **complete_arrays(segment), **_sample_arrays(segment), key=np.array(key),
             plastic=np.array([getattr(event, name) for name in _PLASTIC_NUMBERS], dtype=float),
             plastic_kind=np.array(event.kind), next_q=q, next_xi=xi, next_rows=rows,
             next_gamma=np.array(gamma))


def _sample_arrays(segment: Branch) -> dict[str, np.ndarray]:
    """A segment's samples (its labelled "sample", models/packing/sampled.py) as arrays: their
    pair counts, residuals, and their eigenvalues flat with offsets (their strains are
    complete_arrays' sample_gamma); {} without."""
    if "sample" not in segment.labelled:
        return {}
    samples = segment.sample
    offsets = np.cumsum([0] + [x.eigenvalues.size for x in samples])
    values = [x.eigenvalues for x in samples]
    return {"sample_n_complex": np.array([x.n_complex for x in samples], dtype=int),
            "sample_residual": np.array([x.residual for x in samples], dtype=float),
            "sample_offsets": offsets,
            "sample_values": np.concatenate(values) if values else np.zeros(0, complex)}


def _samples_of(d: dict[str, np.ndarray]) -> dict[str, tuple]:
    """{"sample": the samples} that _sample_arrays wrote, or {}."""
    if "sample_n_complex" not in d:
        return {}
    o = d["sample_offsets"]
    return {"sample": tuple(SpectrumSample(float(g), d["sample_values"][o[i]:o[i + 1]], int(n), float(r))
                            for i, (g, n, r) in enumerate(zip(d["sample_gamma"], d["sample_n_complex"],
                                                               d["sample_residual"])))}


class SegmentFileError(ValueError):
    """A segment file that cannot be read, or was written for other inputs or code."""


def load_segment(path: Path, key: str) -> Branch:
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
        numbers = dict(zip(_PLASTIC_NUMBERS, (float(v) for v in d["plastic"])))
        after = (d["next_q"], d["next_xi"], d["next_rows"], float(d["next_gamma"]))
        event = PlasticEvent(**{**numbers, "steps": int(numbers["steps"])},
                             kind=str(d["plastic_kind"]), after=after)
        return branch_of(d, {"plastic": (event,), **_samples_of(d)})
    except (KeyError, IndexError, ValueError, TypeError) as error:
        raise SegmentFileError(f"{path}: incomplete ({error})") from None
