"""Generated modules in the cache: written with a content hash, checked on every load, imported,
warmed up, and repaired when damaged.

The kernel modules (symbolic/kernels.py) and the dynamics steppers (dynamics/stepper.py) are
Python files generated into the cache directory, with numba's compiled code beside them in
__pycache__ (cache=True). Either can be damaged: a truncated, emptied or edited file, a
truncated or garbage .nbi/.nbc. `load_generated` repairs each without the user deleting
anything, with one warning line naming the path:

1. The first line of a generated file is ``# content sha256: <hex>``, the sha256 of the rest
   of the file. A file whose line does not match is regenerated (atomically).
2. The module is imported and its ``warm_up(progress)`` called: every compiled entry point once,
   with the argument types real use passes, so numba compiles it or loads its cache right here.
3. If that fails (numba raises UnpicklingError, EOFError, ... on a damaged cache file), the
   module's numba cache files are deleted and the module executed again as a fresh module
   object (the failed dispatchers stay with the old one) and warmed up again. It keeps its
   name: numba's cache records the module by name, and the next process imports it by that
   name. A second failure is a real error and propagates.
"""
from __future__ import annotations

import hashlib
import importlib.util
import sys
from pathlib import Path
from types import ModuleType
from typing import Callable, Optional

from diskfriction.files import save_text, warn

CONTENT_PREFIX = "# content sha256: "

Progress = Callable[[str, Optional[float]], None]
"""progress(stage, fraction or None): what a long step reports (the command line renders it)."""


def with_content_hash(body: str) -> str:
    """The file text: the content-hash line, then `body`."""
    return f"{CONTENT_PREFIX}{hashlib.sha256(body.encode()).hexdigest()}\n{body}"


def damage(path: Path) -> Optional[str]:
    """None if `path` holds an intact generated module, else what is wrong with it."""
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return "missing"
    except (OSError, UnicodeDecodeError) as error:
        return f"unreadable ({error})"
    first, _, body = text.partition("\n")
    if not first.startswith(CONTENT_PREFIX):
        return "no content hash (emptied, truncated or not generated here)"
    if first[len(CONTENT_PREFIX):] != hashlib.sha256(body.encode()).hexdigest():
        return "content hash does not match (truncated or edited)"
    return None


def _import(name: str, path: Path, then: Callable[[ModuleType], object] = lambda m: None
            ) -> ModuleType:
    """Execute `path` as the module `name`, registered in sys.modules, then then(module); on
    any failure nothing stays registered."""
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
        then(module)
    except BaseException:
        del sys.modules[name]
        raise
    return module


def numba_cache_files(module: ModuleType) -> list[Path]:
    """numba's index and data files (.nbi, .nbc) of the module's compiled functions."""
    stem = Path(module.__file__).stem
    folders = {Path(f._cache.cache_path) for f in vars(module).values()
               if getattr(f, "_cache", None) is not None and hasattr(f._cache, "cache_path")}
    folders.add(Path(module.__file__).parent / "__pycache__")
    return sorted(p for folder in folders for pattern in (f"{stem}.*.nbi", f"{stem}.*.nbc")
                  for p in folder.glob(pattern))


def load_generated(path: Path, name: str, source: Callable[[], str],
                   progress: Optional[Progress] = None) -> ModuleType:
    """The module `name` from the generated file `path`: written from source() (the body; the
    content-hash line is added here) when missing or damaged, imported, warmed up, and
    repaired once if numba's cache of it is damaged (module docstring).
    progress("generating", None) before source() runs; before the warm-up progress("compiling",
    None) on a cold numba cache, progress("loading compiled code", None) otherwise."""
    if name in sys.modules:
        return sys.modules[name]
    problem = damage(path)
    if problem is not None:
        if problem != "missing":
            warn(f"generated module {path} is damaged: {problem}; regenerating it")
        if progress is not None:
            progress("generating", None)
        save_text(path, with_content_hash(source()))
    module = _import(name, path)
    stage = "loading compiled code" if numba_cache_files(module) else "compiling"
    tick = (lambda fraction: progress(stage, fraction)) if progress else None
    if progress is not None:
        progress(stage, None)
    try:
        module.warm_up(tick)
    except Exception as error:  # a damaged numba cache: UnpicklingError, EOFError, ValueError...
        del sys.modules[name]
        _repair_numba_cache(module, path, error)
        # a fresh module object: fresh dispatchers, not the failed ones
        module = _import(name, path, lambda fresh: fresh.warm_up(tick))
    return module


def _repair_numba_cache(module: ModuleType, path: Path, error: Exception) -> None:
    """Delete the module's numba cache files, with one warning line."""
    files = numba_cache_files(module)
    what = (str(error).splitlines() or [""])[0]
    warn(f"numba cache of {path} is damaged ({type(error).__name__}: {what}); deleting its "
         f"{len(files)} files and compiling again")
    for p in files:
        p.unlink(missing_ok=True)
