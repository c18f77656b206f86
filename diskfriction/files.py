"""Files, digests and the cache directory: the bottom layer every part of diskfriction may import.

- Every file is written atomically (`write_atomic`): to a temporary file beside its path, then
  renamed over it, so a reader or an interrupted run never sees half a file. Files are 0644
  (mkstemp's 0600 widened): results and generated modules are ordinary readable files.
- JSON is strict (`json_text`, `save_json`): a value that is not finite is written as null,
  never as the NaN or Infinity that JSON does not have.
- `source_digest` is the one code version: sha256 over the names and contents of the .py files
  of the given modules or packages. Cache keys and resumable runs carry it, so an edit of those
  sources makes them stale.
- `cache_root` is where generated kernels, numba's compiled code and the report's results live:
  $DISKFRICTION_CACHE, else ~/.cache/diskfriction. When that directory cannot be written, a
  private temporary directory replaces it for this process and its children (one warning line).

Nothing here imports numpy or anything else of diskfriction at module level.
"""
from __future__ import annotations

import atexit
import hashlib
import importlib.util
import json
import math
import os
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Callable, Iterable

FILE_MODE = 0o644
CACHE_VARIABLE = "DISKFRICTION_CACHE"


def write_atomic(path: Path, write: Callable[[Path], None]) -> None:
    """Call write(tmp) for a temporary file beside `path` (mode 0644), then rename it to `path`.
    Creates the parent directories; the temporary file never outlives a failure."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        os.chmod(tmp, FILE_MODE)
        write(Path(tmp))
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def save_text(path: Path, text: str) -> None:
    """`text` written atomically (UTF-8)."""
    write_atomic(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def json_values(data):
    """`data` in JSON's values: a float that is not finite (nan, inf) becomes None (null), a
    numpy scalar or array its Python number or list, a tuple a list, recursively through
    dicts and lists."""
    if isinstance(data, dict):
        return {key: json_values(value) for key, value in data.items()}
    if isinstance(data, (list, tuple)):
        return [json_values(value) for value in data]
    if hasattr(data, "tolist") and type(data).__module__ == "numpy":  # scalars and arrays
        return json_values(data.tolist())
    if isinstance(data, float) and not math.isfinite(data):
        return None
    return data


def json_text(data, indent: int | None = 1) -> str:
    """`data` as strict JSON text (json_values: no NaN or Infinity, which JSON does not have;
    a value json cannot write raises TypeError)."""
    return json.dumps(json_values(data), indent=indent, allow_nan=False)


def save_json(path: Path, data) -> None:
    """`data` as indented strict JSON (json_text), written atomically."""
    save_text(path, json_text(data) + "\n")


def save_npz(path: Path, **arrays) -> None:
    """numpy arrays as an .npz, written atomically (read back with allow_pickle=False). Not
    compressed: zlib shrank a run's floats by 23 % (trajectory.npz of --t-end 40000, 880 -> 680
    MB) and took 42 s of the run's 50, against about 2 s to write them as they are
    (docs/notes/chain-dynamics.md, "Cost")."""
    import numpy as np

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)

    write_atomic(path, write)


def _source_files(module: str) -> list[tuple[str, Path]]:
    """(name relative to the module, path) of the .py files of a module, or of every module of
    a package (recursively)."""
    spec = importlib.util.find_spec(module)
    if spec is None or spec.origin is None:
        raise ValueError(f"cannot find the sources of {module!r}")
    origin = Path(spec.origin)
    if not spec.submodule_search_locations:
        return [(origin.name, origin)]
    root = origin.parent
    return [(str(p.relative_to(root)), p) for p in sorted(root.rglob("*.py"))
            if "__pycache__" not in p.parts]


def source_digest(modules: Iterable[str]) -> str:
    """sha256 (hex) over the names and contents of the source files of `modules` (dotted names
    of modules or packages, e.g. "diskfriction.continuation"), in sorted order."""
    digest = hashlib.sha256()
    for module in sorted(set(modules)):
        for name, path in _source_files(module):
            digest.update(f"{module}:{name}\0".encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


def writable(directory: Path) -> str | None:
    """None if files can be created in `directory` (made if missing), else why not."""
    try:
        directory.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=directory, prefix=".probe.")
        os.close(fd)
        os.remove(probe)
    except OSError as error:
        return error.strerror or str(error)
    return None


def warn(line: str) -> None:
    """One warning line on stderr."""
    print(f"diskfriction warning: {line}", file=sys.stderr, flush=True)


def cache_root() -> Path:
    """$DISKFRICTION_CACHE, else ~/.cache/diskfriction, created if missing.

    If it cannot be written (read-only, a path under a file, ...), a private temporary
    directory takes its place: one warning line, $DISKFRICTION_CACHE set to it so that worker
    processes started later share it, and it is removed when this process exits."""
    root = Path(os.environ.get(CACHE_VARIABLE) or Path.home() / ".cache" / "diskfriction")
    problem = writable(root)
    if problem is None:
        return root
    private = Path(tempfile.mkdtemp(prefix="diskfriction-cache-"))
    atexit.register(shutil.rmtree, private, ignore_errors=True)
    os.environ[CACHE_VARIABLE] = str(private)
    warn(f"cache directory {root} is not writable ({problem}); using a private temporary "
         f"cache {private} for this run")
    return private
