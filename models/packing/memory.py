"""What a packing command holds in memory, so that a scene too large for the machine is refused
with one line before any work (models/packing/commands.check_packing), as models/chain/memory.py does for a chain's
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
  WINDOW_POINT_DOUBLES n. The points: POINTS_PER_STRAIN per unit strain (32 and 64 disks to
  gamma = 0.01: 196 to 442 points, 256 disks to 0.05 with a window: 1554).
"""
from __future__ import annotations

PREPARE_BYTES_PER_DISK = 210.0
DENSE_MATRICES = 12
POINT_DOUBLES = 9
WINDOW_POINT_DOUBLES = 6
POINTS_PER_STRAIN = 2e4


def prepare_bytes(N: int) -> float:
    """Estimated peak memory of the preparation of N disks [bytes] (float: N may be huge)."""
    return PREPARE_BYTES_PER_DISK * float(N)


def points_bytes(N: int, gamma: float, window: bool) -> float:
    """Estimated memory of the points a shear of N disks to `gamma` keeps [bytes]."""
    per_point = WINDOW_POINT_DOUBLES if window else POINT_DOUBLES
    return 8.0 * per_point * 3.0 * N * shear_points(gamma)


def shear_points(gamma: float) -> float:
    """The accepted points of a shear to `gamma`, at least one (POINTS_PER_STRAIN)."""
    return 1.0 + POINTS_PER_STRAIN * gamma


def dense_bytes(N: int, processes: int = 1) -> float:
    """Estimated peak memory of the dense spectra of a shear of N disks taken in `processes`
    processes at once [bytes]."""
    n = 3.0 * N
    return 8.0 * DENSE_MATRICES * n * n * processes
