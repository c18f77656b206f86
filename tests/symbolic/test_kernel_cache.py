"""The generated-module cache: same effects reuse the module, another effect regenerates it, and
a damaged module, numba cache file or cache directory is repaired with one warning line."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from diskfriction import files
from diskfriction.scenes import Effects, Scene
from diskfriction.symbolic import generated, kernels

pytestmark = pytest.mark.slow  # whole runs of commands or examples: the slow tier (README, Tests)


def forget(effects: Effects) -> None:
    sys.modules.pop(f"diskfriction_kernels_{kernels.module_hash(effects)}", None)


# ---- one process generates and compiles: a cache seeded by it ---------------------------------

USE = """
from diskfriction.scenes import Scene
from diskfriction.symbolic import System
from diskfriction.dynamics.stepper import load_stepper
s = System.from_scene(Scene(N=2, mu=0.0))
load_stepper(s.kernels)
q, xi = s.rest_state()
print(abs(s.forces(q, xi, 0.0)).max())
"""
"""Loads the kernels and the stepper of a small frictionless scene and prints max|F| at rest."""


def use(cache: Path, code: str = USE) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, env={**os.environ, "DISKFRICTION_CACHE": str(cache)})


@pytest.fixture(scope="module")
def seeded(tmp_path_factory):
    """A cache holding the generated and compiled modules of USE, made by one process (each
    test that loads from it or damages it works on a copy)."""
    cache = tmp_path_factory.mktemp("seed")
    run = use(cache)
    assert run.returncode == 0 and run.stderr == "", run.stderr
    return cache


USED = Scene(N=2, mu=0.0).resolved_effects
"""The effects of USE's scene, whose kernel module `seeded` holds."""


def seeded_copy(seeded: Path, tmp_path: Path) -> Path:
    cache = tmp_path / "cache"
    shutil.copytree(seeded, cache)
    return cache


def test_same_effects_reuse_the_generated_module(seeded, tmp_path, monkeypatch):
    """The module USE's process generated (in a copy of `seeded`: a cache of its own would
    generate and compile the same kernels again, 5-9 s) is found by its effects: loading them
    twice in this process generates nothing and leaves the file as it was."""
    cache = seeded_copy(seeded, tmp_path)
    monkeypatch.setenv("DISKFRICTION_CACHE", str(cache))
    path = kernels.module_path(USED)
    assert path.parent == cache / "kernels" and path.exists()
    assert path.stat().st_mode & 0o777 == 0o644
    stamp = path.stat().st_mtime_ns

    def no_generation(*args):
        raise AssertionError("regenerated although cached")

    monkeypatch.setattr(kernels, "generate_source", no_generation)
    forget(USED)
    module = kernels.load_kernels(USED)
    forget(USED)
    again = kernels.load_kernels(USED)
    assert again is not module and path.stat().st_mtime_ns == stamp
    assert kernels.module_hash(USED) in path.read_text().splitlines()[3]  # header names it


def test_changing_an_effect_or_the_generator_regenerates(seeded, tmp_path, monkeypatch):
    monkeypatch.setenv("DISKFRICTION_CACHE", str(seeded_copy(seeded, tmp_path)))
    base = Effects("mindlin-smooth", True, True, True)
    variants = [Effects("mindlin-linear", True, True, True), Effects("mindlin-smooth", False, True, True),
                Effects("mindlin-smooth", True, False, True), Effects("mindlin-smooth", True, True, False)]
    paths = {kernels.module_path(e) for e in [base, *variants]}
    assert len(paths) == 5
    # a cache in which the kernels of USED were generated holds their module, and no other
    assert kernels.module_path(USED).exists() and USED.pair_law == "none"
    assert not any(path.exists() for path in paths)
    monkeypatch.setattr(kernels, "GENERATOR_VERSION", kernels.GENERATOR_VERSION + 1)
    assert kernels.module_path(variants[0]) not in paths


def test_friction_switches_that_do_not_change_the_derivation_share_a_module():
    """With tangential law "none" the friction switches derive nothing: one module."""
    a = Effects("none", True, True, True)
    b = Effects("none", False, False, True)
    assert kernels.module_hash(a) == kernels.module_hash(b)


def test_conventions_regenerate_only_where_they_change_something():
    """The conventions act on contacts with friction: without any, one module; with friction,
    "lammps" is a module of its own and the default "model" keeps the plain key."""
    for law, pair, wall in (("mindlin-smooth", True, True), ("mindlin-linear", False, True)):
        model, lammps = (Effects(law, pair, wall, True, c) for c in ("model", "lammps"))
        assert kernels.module_hash(model) != kernels.module_hash(lammps)
        assert "conventions" not in kernels.effects_key(model)
    frictionless = [Effects("none", False, False, True, c) for c in ("model", "lammps")]
    assert kernels.module_hash(frictionless[0]) == kernels.module_hash(frictionless[1])


def test_compiled_code_is_cached_for_the_next_process(seeded):
    """numba cache=True: after one process ran the kernels (USE, in the fresh cache `seeded`),
    their index files exist, the kernel module's and the stepper's. (The seeded cache serves:
    a process of its own in a fresh cache would compile the same kernels again, ~7 s.)"""
    assert list((seeded / "kernels").rglob("kernels_*.nbi"))
    assert list((seeded / "kernels").rglob("stepper_*.nbi"))


# ---- damage and repair ----------------------------------------------------------------------

BODY = "x = 1\n" * 50


@pytest.mark.parametrize("damage, says", [
    (lambda text: text[: len(text) // 2], "does not match"),  # truncated
    (lambda text: "", "no content hash"),  # emptied
    (lambda text: text.replace("x = 1", "x = 2", 1), "does not match"),  # edited
    (lambda text: text.split("\n", 1)[1], "no content hash"),  # header line lost
])
def test_a_damaged_module_is_told_by_its_content_hash(tmp_path, damage, says):
    path = tmp_path / "module.py"
    path.write_text(generated.with_content_hash(BODY))
    assert generated.damage(path) is None
    path.write_text(damage(path.read_text()))
    assert says in generated.damage(path)
    assert generated.damage(tmp_path / "absent.py") == "missing"


def damaged_copy(seeded: Path, tmp_path: Path, pattern: str, damage) -> tuple[Path, Path]:
    cache = seeded_copy(seeded, tmp_path)
    (path,) = (cache / "kernels").glob(pattern)
    damage(path)
    return cache, path


def assert_repaired(cache: Path, path: Path, says: str) -> None:
    """One warning line naming the path, a correct result, and a next run without warning."""
    first = use(cache)
    assert first.returncode == 0, first.stderr
    assert first.stderr.count("\n") == 1 and str(path) in first.stderr and says in first.stderr
    assert "Traceback" not in first.stderr and float(first.stdout) < 1e-12
    again = use(cache)
    assert again.returncode == 0 and again.stderr == "", again.stderr


def test_a_truncated_kernel_module_is_regenerated(seeded, tmp_path):
    cache, path = damaged_copy(seeded, tmp_path, "kernels_*.py",
                               lambda p: p.write_bytes(p.read_bytes()[:2000]))
    assert_repaired(cache, path, "regenerating")
    assert generated.damage(path) is None


def test_an_emptied_stepper_module_is_regenerated(seeded, tmp_path):
    cache, path = damaged_copy(seeded, tmp_path, "stepper_*.py", lambda p: p.write_text(""))
    assert_repaired(cache, path, "regenerating")


def test_a_garbage_numba_cache_file_is_deleted_and_compiled_again(seeded, tmp_path):
    """The stepper's (the kernels' are repaired the same way, and compile twice as long)."""
    def garbage(module: Path) -> None:
        (data,) = (module.parent / "__pycache__").glob(f"{module.stem}.advance-*.nbc")
        data.write_bytes(b"\x80\x04 not a pickle" * 10)

    cache, path = damaged_copy(seeded, tmp_path, "stepper_*.py", garbage)
    assert_repaired(cache, path, "numba cache")


def test_an_unwritable_cache_directory_falls_back_to_a_private_one(tmp_path):
    """A path under a regular file can never be written (also not by root)."""
    (tmp_path / "file").write_text("")
    run = use(tmp_path / "file" / "cache", USE.replace("load_stepper(s.kernels)", ""))
    assert run.returncode == 0 and float(run.stdout) < 1e-12
    assert run.stderr.count("\n") == 1 and "not writable" in run.stderr
    private = Path(run.stderr.split("private temporary cache ")[1].split()[0])
    assert not private.exists()  # removed when the process ended


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into a read-only directory anyway")
def test_a_read_only_cache_directory_falls_back_to_a_private_one(tmp_path, monkeypatch):
    monkeypatch.setenv("DISKFRICTION_CACHE", str(tmp_path))
    tmp_path.chmod(0o555)
    try:
        root = files.cache_root()
    finally:
        tmp_path.chmod(0o755)
    assert root != tmp_path and root.is_dir()
    assert os.environ["DISKFRICTION_CACHE"] == str(root)  # workers started later share it
