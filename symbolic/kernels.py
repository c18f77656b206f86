"""Generated kernel modules: derive, print, cache on disk, import.

A module is generated for one set of effects and keyed by sha256 of (effects, generator
version), where the generator version is GENERATOR_VERSION plus a digest of the symbolic
package's own sources, so that a change of a law or of the printer regenerates every module.
Modules live in $DISKFRICTION_CACHE (default ~/.cache/diskfriction), written atomically; numba
keeps its compiled code beside them (cache=True), so a second process starts without compiling.
"""
from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
import tempfile
from pathlib import Path
from types import ModuleType

from diskfriction.scenes import Effects

GENERATOR_VERSION = 1
_SOURCES = ("laws.py", "contacts.py", "codegen.py", "assembly_src.py", "kernels.py")


def cache_dir() -> Path:
    """Where generated modules are kept: $DISKFRICTION_CACHE or ~/.cache/diskfriction."""
    root = os.environ.get("DISKFRICTION_CACHE") or Path.home() / ".cache" / "diskfriction"
    return Path(root) / "kernels"


def generator_version() -> str:
    """GENERATOR_VERSION and a digest of the generator's sources."""
    here = Path(__file__).parent
    digest = hashlib.sha256()
    for name in _SOURCES:
        digest.update((here / name).read_bytes())
    return f"{GENERATOR_VERSION}-{digest.hexdigest()[:12]}"


def effects_key(effects: Effects) -> str:
    """Only what changes the derivation: the law at each contact kind and rotation."""
    return f"pair={effects.pair_law};wall={effects.wall_law};rotation={effects.rotation}"


def module_hash(effects: Effects) -> str:
    text = f"{effects_key(effects)}|{generator_version()}"
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def generate_source(effects: Effects, digest: str) -> str:
    """Derive both contact kernels for these effects and print the module's source."""
    from diskfriction.symbolic import codegen, contacts

    pair = contacts.pair_contact(effects.pair_law, effects.rotation)
    wall = contacts.wall_contact(effects.wall_law, effects.rotation)
    header = (f'"""diskfriction generated kernels. Do not edit: regenerated from symbolic/.\n\n'
              f"hash: {digest}\neffects: {effects_key(effects)}\n"
              f'generator: {generator_version()}\n"""')
    assembly = (Path(__file__).parent / "assembly_src.py").read_text()
    return codegen.module_source(pair, wall, effects.rotation, header, assembly)


def write_atomic(path: Path, text: str) -> None:
    """Write text to a temporary file beside path, then rename it (readers never see half)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    with os.fdopen(fd, "w") as fh:
        fh.write(text)
    os.replace(tmp, path)


def module_path(effects: Effects) -> Path:
    return cache_dir() / f"kernels_{module_hash(effects)}.py"


def load_kernels(effects: Effects) -> ModuleType:
    """The generated module for these effects: reused from the cache, generated if missing."""
    digest = module_hash(effects)
    name = f"diskfriction_kernels_{digest}"
    if name in sys.modules:
        return sys.modules[name]
    path = module_path(effects)
    if not path.exists():
        write_atomic(path, generate_source(effects, digest))
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module
