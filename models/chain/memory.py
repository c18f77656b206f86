"""What a sweep holds in memory, so that a scene too large for the machine is refused first.

A sweep's largest objects are the full eigendecompositions of the n x n stability matrix (n =
ndof = 3N, or 2N without rotation) that the fast collision detection takes at every sample: the
dense matrix and LAPACK's working copy (dgeev), its real left and right vectors, their complex
normalised copies (2 doubles per entry each) and the product dA R of the slopes, about
DENSE_MATRICES n x n arrays of doubles at once. The Newton, tangent and locator solves are
sparse (SuperLU, O(n)) from n = 240 on and dense below, where n^2 is small. Per stored point it keeps
q, the trial and committed histories, the tracked eigenvalues (complex) and the core's tangent,
about POINT_VECTORS vectors of n doubles, for at most `points` points (the paper's diagram has
about 700; a sweep stops after 20 000). Scan workers (scans.py) form their own dense matrices:
the dense part counts once per process.

The estimate is a lower bound, so the guard refuses only what cannot fit: the fast detection
keeps the full samples of a step whose intervals are not yet settled while it scans it, each
with 4 n^2 doubles of eigenvectors and n^2 of its matrix derivative dA/dtau (for the
certifier's coupling test, certify.decoupled), and with scan workers each of the three
processes holds such samples, so a full-spectrum sweep peaks higher: at N = 200 678 MB inline,
587 MB in each of two workers (docs/notes/core-scans.md, "Settled samples release their
vectors"); at N = 1000 up to 7.4 GB in one process (docs/notes/core-refinement.md, "Memory at
N = 1000"). A spectral window's samples hold n x k vectors, and at eps = 0 only the disks the
load reached carry vectors.
"""
from __future__ import annotations

DENSE_MATRICES = 12
POINT_VECTORS = 8
TYPICAL_POINTS = 2000
SPECTRUM_MATRICES = 6
"""A run's start spectrum (dynamics.start.spectrum: J, M^-1 J, LAPACK's copy, real and complex
eigenvectors) holds about this many n x n arrays of doubles at once."""


def sweep_bytes(ndof: int, points: int = TYPICAL_POINTS, processes: int = 1, dense: bool = True) -> float:
    """Estimated peak memory of a sweep [bytes] (float: N may be huge) whose spectra are taken
    in `processes` processes at once (the sweep's and its scan workers, scans.py: each forms
    its own dense matrices); the points are stored in the sweep's process alone. dense=False:
    a sweep that forms no n x n matrix, as far as a lower bound can tell (a spectral window,
    or eps = 0, where only the disks the load reached form a dense block)."""
    n = float(ndof)
    return 8.0 * (DENSE_MATRICES * n * n * processes * dense + POINT_VECTORS * n * points)


def spectrum_bytes(ndof: int, processes: int = 1) -> float:
    """Estimated peak memory of the dense eigendecomposition of M^-1 J at a run's start, in
    `processes` processes at once [bytes]."""
    n = float(ndof)
    return 8.0 * SPECTRUM_MATRICES * n * n * processes
