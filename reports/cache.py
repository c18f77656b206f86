"""On-disk results of report computations, keyed by what they depend on.

key = sha256 of the canonical JSON of
  computation   its registered name;
  scene         every field of the Scene dataclass that enters physics (all but `name` and
                `source`, so renaming or moving a scene file reuses its results);
  params        the computation's parameters (JSON values);
  code          a digest of the source files the computation depends on (its own module and
                the packages it declares, e.g. continuation/, symbolic/, scenes/).
A result is a dict whose values are numpy arrays or JSON values; it is stored as one .npz file
(the arrays, plus the JSON part under META) written atomically, and read back with
allow_pickle=False: nothing in the cache is ever evaluated as code.
"""
from __future__ import annotations

import dataclasses
import hashlib
import importlib.util
import json
import os
from pathlib import Path
from typing import Iterable

import numpy as np

from diskfriction.reports.files import write_atomic
from diskfriction.scenes import Scene

META = "__meta__"
NOT_PHYSICS = ("name", "source")


def default_cache_dir(out: Path) -> Path:
    """$DISKFRICTION_CACHE/report if that variable is set, else OUT/.cache."""
    root = os.environ.get("DISKFRICTION_CACHE")
    return Path(root) / "report" if root else Path(out) / ".cache"


def scene_fields(scene: Scene) -> dict:
    """The scene's dataclass fields that enter physics, as JSON values."""
    fields = dataclasses.asdict(scene)
    for key in NOT_PHYSICS:
        fields.pop(key)
    return fields


def _module_files(module: str) -> list[Path]:
    """The .py files of a module, or of every module of a package (recursively)."""
    spec = importlib.util.find_spec(module)
    if spec is None or spec.origin is None:
        raise ValueError(f"cannot find the sources of {module!r}")
    origin = Path(spec.origin)
    if spec.submodule_search_locations:  # a package: all its sources
        return sorted(p for p in origin.parent.rglob("*.py") if "__pycache__" not in p.parts)
    return [origin]


def code_version(modules: Iterable[str]) -> str:
    """sha256 over the names and contents of the source files of `modules`."""
    digest = hashlib.sha256()
    for module in sorted(set(modules)):
        for path in _module_files(module):
            digest.update(f"{module}:{path.name}\0".encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


def cache_key(computation: str, scene: Scene, params: dict, code: str) -> str:
    text = json.dumps({"computation": computation, "scene": scene_fields(scene),
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
