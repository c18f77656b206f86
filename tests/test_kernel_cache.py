"""The generated-module cache: same effects reuse the module, another effect regenerates it."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from diskfriction.scenes import Effects
from diskfriction.symbolic import kernels


@pytest.fixture
def fresh_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("DISKFRICTION_CACHE", str(tmp_path))
    return tmp_path


def forget(effects: Effects) -> None:
    sys.modules.pop(f"diskfriction_kernels_{kernels.module_hash(effects)}", None)


def test_same_effects_reuse_the_generated_module(fresh_cache, monkeypatch):
    effects = Effects("mindlin-linear", True, False, False)
    forget(effects)
    module = kernels.load_kernels(effects)
    path = kernels.module_path(effects)
    assert path.parent == fresh_cache / "kernels" and path.exists()
    stamp = path.stat().st_mtime_ns
    forget(effects)

    def no_generation(*args):
        raise AssertionError("regenerated although cached")

    monkeypatch.setattr(kernels, "generate_source", no_generation)
    again = kernels.load_kernels(effects)
    assert again is not module and path.stat().st_mtime_ns == stamp
    assert kernels.module_hash(effects) in path.read_text().splitlines()[2]  # header names it


def test_changing_an_effect_or_the_generator_regenerates(fresh_cache, monkeypatch):
    base = Effects("mindlin-smooth", True, True, True)
    variants = [Effects("mindlin-linear", True, True, True), Effects("mindlin-smooth", False, True, True),
                Effects("mindlin-smooth", True, False, True), Effects("mindlin-smooth", True, True, False)]
    paths = {kernels.module_path(e) for e in [base, *variants]}
    assert len(paths) == 5
    forget(variants[0])
    kernels.load_kernels(variants[0])
    assert kernels.module_path(variants[0]).exists()
    assert not kernels.module_path(base).exists()
    monkeypatch.setattr(kernels, "GENERATOR_VERSION", kernels.GENERATOR_VERSION + 1)
    assert kernels.module_path(variants[0]) not in paths


def test_friction_switches_that_do_not_change_the_derivation_share_a_module():
    """With tangential law "none" the friction switches derive nothing: one module."""
    a = Effects("none", True, True, True)
    b = Effects("none", False, False, True)
    assert kernels.module_hash(a) == kernels.module_hash(b)


def test_compiled_code_is_cached_for_the_next_process(fresh_cache):
    """numba cache=True: after one process ran the kernels, their index files exist."""
    code = ("from scenes import Scene; from symbolic import System; s = System.from_scene(Scene(N=3));"
            "q, xi = s.rest_state(); s.forces_and_jacobian(q, xi, 0.0)")
    subprocess.run([sys.executable, "-c", code], check=True, env=dict(os.environ))
    assert list((fresh_cache / "kernels").rglob("*.nbi"))
