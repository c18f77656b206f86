"""Generated kernel modules: derive, print, cache on disk, import.

A module is generated for one set of effects and keyed by sha256 of (effects, generator
version), where the generator version is GENERATOR_VERSION plus a digest of the generator's own
sources, so that a change of a law or of the printer regenerates every module. Modules live in
the cache directory's kernels/ (files.cache_root: $DISKFRICTION_CACHE, default
~/.cache/diskfriction), written atomically, checked against their content hash on every load and
repaired when damaged (symbolic/generated.py); numba keeps its compiled code beside them
(cache=True), so a second process starts without compiling.
"""
from __future__ import annotations

import hashlib
from pathlib import Path
from types import ModuleType
from typing import Optional

from diskfriction.files import cache_root, source_digest
from diskfriction.scenes import Effects
from diskfriction.symbolic.generated import Progress, load_generated
from diskfriction.symbolic.template import Dialect

GENERATOR_VERSION = 1
_SOURCES = tuple(f"diskfriction.symbolic.{name}" for name in
                 ("laws", "contacts", "codegen", "contact_src", "assembly_src", "packing_src",
                  "template", "kernels", "generated"))


def cache_dir() -> Path:
    """Where generated modules are kept: kernels/ in files.cache_root()."""
    return cache_root() / "kernels"


def generator_version() -> str:
    """GENERATOR_VERSION and a digest of the generator's sources."""
    return f"{GENERATOR_VERSION}-{source_digest(_SOURCES)[:12]}"


def effects_key(effects: Effects) -> str:
    """Only what changes the derivation: the law at each contact kind, rotation, the
    conventions where they change anything (Effects.contact_conventions), and the normal law
    where it is not the paper's Hertz."""
    key = f"pair={effects.pair_law};wall={effects.wall_law};rotation={effects.rotation}"
    conventions = effects.contact_conventions
    key = key if conventions == "model" else f"{key};conventions={conventions}"
    return key if effects.normal == "hertz" else f"{key};normal={effects.normal}"


def dialect(effects: Effects) -> Dialect:
    """The template dialect (symbolic/template.py) of the module for these effects."""
    return Dialect(effects.contact_conventions, effects.rotation)


def module_hash(effects: Effects) -> str:
    text = f"{effects_key(effects)}|{generator_version()}"
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _header(key: str, digest: str) -> str:
    return (f'"""diskfriction generated kernels. Do not edit: regenerated from symbolic/.\n\n'
            f"hash: {digest}\neffects: {key}\n"
            f'generator: {generator_version()}\n"""')


def _assembly(*names: str) -> list[str]:
    """The text of the assembly sources symbolic/<name>.py."""
    return [(Path(__file__).parent / f"{name}.py").read_text() for name in names]


def generate_source(effects: Effects, digest: str, progress: Optional[Progress] = None) -> str:
    """Derive both contact kernels of the chain for these effects and print the module's
    source; progress("generating", fraction) between the steps (fractions: their share of the
    time)."""
    from diskfriction.symbolic import codegen, contacts

    tick = (lambda fraction: progress("generating", fraction)) if progress else (lambda f: None)
    tick(0.0)
    pair = contacts.pair_contact(effects.pair_law, effects.rotation, effects.contact_conventions,
                                 effects.normal)
    tick(0.4)
    wall = contacts.wall_contact(effects.wall_law, effects.rotation, effects.normal)
    tick(0.45)
    source = codegen.module_source([pair, wall], dialect(effects),
                                   _header(effects_key(effects), digest),
                                   _assembly("contact_src", "assembly_src"))
    tick(1.0)
    return source


def module_path(effects: Effects) -> Path:
    return cache_dir() / f"kernels_{module_hash(effects)}.py"


def load_kernels(effects: Effects, progress: Optional[Progress] = None) -> ModuleType:
    """The generated module for these effects: reused from the cache (checked), generated if
    missing or damaged, compiled or loaded from numba's cache. progress(stage, None) as in
    generated.load_generated."""
    digest = module_hash(effects)
    return load_generated(module_path(effects), f"diskfriction_kernels_{digest}",
                          lambda: generate_source(effects, digest, progress), progress)


def packing_key(effects: Effects) -> str:
    """What changes a packing's derivation: the grain pairs' law and the normal law (a packing
    has no substrate; its disks rotate, conventions "model": docs/packings.md)."""
    return f"packing;pair={effects.pair_law};normal={effects.normal}"


def load_packing_kernels(effects: Effects, progress: Optional[Progress] = None) -> ModuleType:
    """The generated module of a packing (symbolic/packing_src.py over the grain-pair kernel),
    cached and checked as load_kernels."""
    from diskfriction.symbolic import codegen, contacts

    key = packing_key(effects)
    digest = hashlib.sha256(f"{key}|{generator_version()}".encode()).hexdigest()[:16]

    def source() -> str:
        grain = contacts.pair_contact(effects.pair_law, True, "model", effects.normal, "grain")
        return codegen.module_source([grain], Dialect("model", True), _header(key, digest),
                                     _assembly("contact_src", "packing_src"))

    return load_generated(cache_dir() / f"packing_{digest}.py", f"diskfriction_packing_{digest}",
                          source, progress)
