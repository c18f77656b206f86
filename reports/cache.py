"""On-disk results of report computations, keyed by what they depend on.

key = sha256 of the canonical JSON of
  computation   its registered name;
  scene         Scene.physics_fields(): every field that enters physics (all but `name` and
                `source`, so renaming or moving a scene file reuses its results);
  params        the computation's parameters (JSON values);
  code          a digest of the source files the computation depends on (its own module and
                the packages it declares, e.g. continuation/, symbolic/, scenes/).
A result is a dict whose values are numpy arrays or JSON values; it is stored as one .npz file
(the arrays, plus the JSON part under META) written atomically, and read back with
allow_pickle=False: nothing in the cache is ever evaluated as code.
"""
from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np

from diskfriction.files import CACHE_VARIABLE, cache_root, write_atomic
from diskfriction.scenes import Scene

META = "__meta__"


def default_cache_dir(out: Path) -> Path:
    """report/ in the cache directory (files.cache_root) if $DISKFRICTION_CACHE is set, else
    OUT/.cache."""
    return cache_root() / "report" if os.environ.get(CACHE_VARIABLE) else Path(out) / ".cache"


def cache_key(computation: str, scene: Scene, params: dict, code: str) -> str:
    text = json.dumps({"computation": computation, "scene": scene.physics_fields(),
                       "params": params, "code": code}, sort_keys=True, allow_nan=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _split(result: dict) -> tuple[dict, dict]:
    arrays = {k: v for k, v in result.items() if isinstance(v, np.ndarray)}
    meta = {k: v for k, v in result.items() if k not in arrays}
    if META in result:
        raise ValueError(f"a result may not use the key {META!r}")
    return arrays, meta


class ResultCache:
    """Results stored as DIR/<computation>/<key>.npz."""

    def __init__(self, directory: Path) -> None:
        self.directory = Path(directory)

    def path(self, computation: str, key: str) -> Path:
        return self.directory / computation / f"{key}.npz"

    def load(self, computation: str, key: str) -> dict | None:
        """The stored result, or None if absent or unreadable (then it is recomputed)."""
        path = self.path(computation, key)
        if not path.exists():
            return None
        try:
            with np.load(path, allow_pickle=False) as data:
                result = {k: data[k] for k in data.files if k != META}
                result.update(json.loads(str(data[META])))
        except (OSError, ValueError, KeyError):
            return None
        return result

    def store(self, computation: str, key: str, result: dict) -> None:
        arrays, meta = _split(result)
        text = json.dumps(meta, allow_nan=True)

        def write(tmp: Path) -> None:
            with open(tmp, "wb") as fh:
                np.savez_compressed(fh, **arrays, **{META: np.array(text)})

        write_atomic(self.path(computation, key), write)
