"""Packaging: every top-level folder with an __init__.py is installed as diskfriction.<folder>.

The design card keeps scenes/, symbolic/, continuation/, dynamics/, reports/ and cli/ at the
repository's top level; a package-dir mapping installs them under the diskfriction namespace,
so no generic top-level name (reports, symbolic, ...) reaches site-packages. The folders are
found, not listed: a new one cannot be left out of the wheel. Everything else is in
pyproject.toml.
"""
from pathlib import Path

from setuptools import find_packages, setup

ROOT = Path(__file__).parent
NOT_INSTALLED = ["diskfriction", "diskfriction.*", "tests", "tests.*", "benchmarks",
                 "benchmarks.*", "examples", "examples.*", "build", "build.*"]
FOLDERS = find_packages(where=str(ROOT), exclude=NOT_INSTALLED)

setup(
    packages=["diskfriction", *(f"diskfriction.{name}" for name in FOLDERS)],
    package_dir={"diskfriction": "diskfriction",
                 **{f"diskfriction.{name}": name for name in FOLDERS if "." not in name}},
    package_data={"diskfriction.scenes": ["*.toml"]},
)
