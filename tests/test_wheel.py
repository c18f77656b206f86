"""The wheel a stranger installs (issue 9): built from a copy of the sources, installed into a
fresh virtual environment, and every subcommand run once from a directory outside the checkout.

Kept fast and offline: the wheel is built without build isolation (the test extras bring
setuptools and wheel), the fresh environment sees this environment's dependencies through a
.pth file (a directory listed there is not a site directory, so the editable install of this
checkout stays invisible), the wheel is installed with --no-deps --no-index, and the kernel
cache ($DISKFRICTION_CACHE or its default) is shared, so nothing is compiled again.
"""
from __future__ import annotations

import os
import shutil
import site
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from extras import needs_lammps

pytestmark = pytest.mark.slow  # whole runs of commands or examples: the slow tier (README, Tests)

ROOT = Path(__file__).resolve().parents[1]
NOT_SOURCES = shutil.ignore_patterns(".git", ".venv", "venv", "build", "dist", "*.egg-info",
                                     "__pycache__", ".pytest_cache", "out", ".cache",
                                     ".diskfriction-cache")
TINY = "[disks]\nN = 3\n[load]\nF_x = [0.0, 0.02]\n"
LINEAR = TINY + '[effects]\ntangential = "mindlin-linear"\nconventions = "lammps"\n'
"""A tiny scene LAMMPS can represent (export, crosscheck)."""


def run(*args, cwd: Path, env: dict | None = None) -> subprocess.CompletedProcess:
    result = subprocess.run([str(a) for a in args], cwd=cwd, capture_output=True, text=True,
                            timeout=600, env=env)
    assert result.returncode == 0, f"{args}: {result.stderr}"
    return result


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(wheel, python and diskfriction of the fresh environment, a working directory outside
    the checkout, the environment to run in)."""
    root = tmp_path_factory.mktemp("wheel")
    shutil.copytree(ROOT, root / "src", ignore=NOT_SOURCES)
    run(sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--no-index",
        "-q", "-w", root / "dist", root / "src", cwd=root)
    (wheel,) = (root / "dist").glob("diskfriction-*.whl")
    run(sys.executable, "-m", "venv", "--without-pip", root / "venv", cwd=root)
    python = root / "venv" / "bin" / "python"
    purelib = Path(run(python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])",
                       cwd=root).stdout.strip())
    (purelib / "dependencies.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    run(sys.executable, "-m", "pip", "--python", python, "install", "-q", "--no-deps",
        "--no-index", wheel, cwd=root)
    elsewhere = root / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "tiny.toml").write_text(TINY)
    (elsewhere / "linear.toml").write_text(LINEAR)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    return wheel, python, root / "venv" / "bin" / "diskfriction", elsewhere, env


def test_the_wheel_installs_only_the_diskfriction_package(installed):
    wheel = installed[0]
    names = zipfile.ZipFile(wheel).namelist()
    top = {name.split("/")[0] for name in names if ".dist-info/" not in name}
    assert top == {"diskfriction"}
    tops = [d for d in ROOT.iterdir() if (d / "__init__.py").exists() and d.name != "diskfriction"]
    folders = {p.parent.relative_to(ROOT).as_posix() for d in tops for p in d.rglob("__init__.py")}
    assert {"reports/sections", "reports/compute", "cli"} <= folders
    for folder in folders:  # found, not listed: a new folder cannot be left out
        assert f"diskfriction/{folder}/__init__.py" in names, folder
    for part in ("scenes/paper.toml", "symbolic/assembly_src.py", "dynamics/stepper_src.py",
                 "files.py", "__main__.py"):
        assert f"diskfriction/{part}" in names, part


def test_the_installed_package_is_the_wheel_not_the_checkout(installed):
    _, python, _, elsewhere, env = installed
    where = run(python, "-c", "import diskfriction.reports.sections as s; print(s.__file__)",
                cwd=elsewhere, env=env).stdout
    assert "/venv/" in where and str(ROOT) not in where


@pytest.mark.parametrize("args, says", [
    (["--version"], "diskfriction 0.1.0"),
    (["scene"], 'name = "paper"'),
    (["bifurcate", "tiny.toml", "--out", "b"], "wrote b/branch.npz"),
    (["simulate", "tiny.toml", "--fx", "0.01", "--t-end", "2", "--out", "s"], "wrote s/"),
    (["verify", "tiny.toml", "--t-end", "2", "--out", "v"], "wrote v/verify.json"),
    (["map", "tiny.toml", "--vary", "contacts.mu=5:10:2", "--workers", "1", "--out", "m"],
     "wrote m/map.csv"),
    (["report", "tiny.toml", "--only", "fig6", "--out", "r", "--cache", "r/cache"], "wrote r/report.md"),
    (["export", "lammps", "linear.toml", "--fx", "0.01", "--out", "e"], "wrote e/scene.data, e/in.scene"),
    pytest.param(["crosscheck", "lammps", "linear.toml", "--fx", "0.01", "--t-end", "1", "--out", "c"],
                 "wrote c/crosscheck.json", marks=needs_lammps),
], ids=lambda a: a[0] if isinstance(a, list) else None)
def test_every_subcommand_runs_from_the_wheel(installed, args, says):
    _, _, command, elsewhere, env = installed
    result = run(command, *args, cwd=elsewhere, env=env)
    assert says in result.stdout and "Traceback" not in result.stderr


def test_ci_runs_the_readme_test_command():
    """A clean clone's CI (.ci/run) runs exactly the README's test command, extras included."""
    readme = (ROOT / "README.md").read_text().splitlines()
    command = next(line for line in readme if "pytest" in line and line.startswith("python3 -m venv"))
    assert (ROOT / ".ci" / "run").read_text().rstrip().splitlines()[-1] == command


def test_python_dash_m_runs_the_installed_command(installed):
    _, python, _, elsewhere, env = installed
    assert run(python, "-m", "diskfriction", "--version", cwd=elsewhere, env=env).stdout.startswith(
        "diskfriction ")
