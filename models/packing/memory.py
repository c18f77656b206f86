"""What a packing command holds in memory, so that a scene too large for the machine is refused
with one line before any work (models/packing/commands_checks.check_packing), as models/chain/memory.py does for a chain's
sweep. The counts are lower bounds: the guard refuses only what cannot fit.

- The preparation (prepare.py, fire.py, the frictionless kernel's cell list and contact rows):
  PREPARE_BYTES_PER_DISK. 1e6 disks held 210 to 255 MB above the interpreter's 220 MB (sampled
  every 10 s over 90 s), 1e5 disks 25 to 40 MB, 4096 disks 2 MB.
- The shear with every eigenvalue: at every sample the dense eigendecomposition of the n x n
  stability matrix (n = 3N) with its complex left and right eigenvectors, and the samples a
  collision scan keeps, in every process that takes spectra (the shear's and its scan
  workers', continuation/detection/scans.py): DENSE_MATRICES n x n doubles each. Measured in one process
  to gamma = 1e-5 and 1e-6: 512 disks held 531 MB and 768 disks 535 MB above 24 disks, 28 and
  12.6 such matrices.
- Every accepted point of the shear keeps q, its eigenvalues (complex) and their condition
  numbers, its contact rows (4 integers each, about one row per dof) and their histories:
  POINT_DOUBLES n doubles; a window's points keep only the window's eigenvalues,
  WINDOW_POINT_DOUBLES n (and so do the points of a shear without spectra, or with sampled
  ones). The points: POINTS_PER_STRAIN N^POINTS_EXPONENT per unit strain, a little below what
  the shears without spectra of 2026-12-02 took (seed 1, mu = 10, P = 0.1: 32, 64 and 256
  disks to gamma = 0.01 189, 360 and 725 points; 1024 disks to 0.002 658 points).
"""
from __future__ import annotations

PREPARE_BYTES_PER_DISK = 210.0
DENSE_MATRICES = 12
POINT_DOUBLES = 9
WINDOW_POINT_DOUBLES = 6
POINTS_PER_STRAIN, POINTS_EXPONENT = 1000.0, 0.8


def prepare_bytes(N: int) -> float:
    """Estimated peak memory of the preparation of N disks [bytes] (float: N may be huge)."""
    return PREPARE_BYTES_PER_DISK * float(N)


def points_bytes(N: int, gamma: float, spectra: str, window: bool) -> float:
    """Estimated memory of the points a shear of N disks to `gamma` keeps, with the spectra
    "full", "none" or "sample:DGAMMA" (the states alone, as a window's) [bytes]."""
    per_point = POINT_DOUBLES if spectra == "full" and not window else WINDOW_POINT_DOUBLES
    return 8.0 * per_point * 3.0 * N * shear_points(N, gamma)


def shear_needs(N: int, gamma: float, spectra: str, window: bool, processes: int) -> tuple[float, str]:
    """(bytes, what they hold) of a shear of N disks to `gamma` with `spectra` (resolved,
    PackingScene.resolved_spectra) and a window or not: its points (points_bytes) and, where it
    takes dense spectra (every one, full or sampled, without a window), the dense matrices
    of each of `processes` processes (full: the shear's and its scan workers'; sample: one)."""
    n, stored = 3 * N, points_bytes(N, gamma, spectra, window)
    if spectra == "none" or window:
        return stored, (f"a shear storing about {shear_points(N, gamma):.2g} points of {n} unknowns"
                        + (" with a window" if window else ""))
    processes = processes if spectra == "full" else 1
    where = f" in {processes} processes" if processes > 1 else ""
    return dense_bytes(N, processes) + stored, f"a shear with dense {n} x {n} spectra{where}"


def shear_points(N: int, gamma: float) -> float:
    """The accepted points of a shear of N disks to `gamma`, at least one: POINTS_PER_STRAIN
    N^POINTS_EXPONENT per unit strain (the contact events that cut the steps grow with N)."""
    return 1.0 + POINTS_PER_STRAIN * float(N) ** POINTS_EXPONENT * gamma


def dense_bytes(N: int, processes: int = 1) -> float:
    """Estimated peak memory of the dense spectra of a shear of N disks taken in `processes`
    processes at once [bytes]."""
    n = 3.0 * N
    return 8.0 * DENSE_MATRICES * n * n * processes
