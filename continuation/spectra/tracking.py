"""Spectra along a branch: classification (real | complex), counting, tracking.

Classification. An eigenvalue lambda of a real matrix counts as complex iff
    |Im lambda| > rel_tol * scale,     scale = max(max_k |lambda_k|, tiny),
and the number of complex pairs is the number of eigenvalues with Im lambda > rel_tol * scale
(LAPACK returns exact conjugate pairs for a real matrix). Default rel_tol = 1e-9, chosen
between two floors:
  * rounding: a real semisimple multiple eigenvalue (symmetry, decoupled blocks) may come
    back as a pair with |Im| ~ n eps cond ~ 1e-14 scale; 1e-9 leaves a factor ~1e5 margin;
  * consistency with collision location: near a collision the discriminant of the pair is
    D = (lambda_a - lambda_b)^2 ~ c (p - p*), so the count switches where 4 (rel_tol scale)^2
    = |c (p - p*)|, i.e. within 4e-18 scale^2 / |c| of p*, far inside the 1e-10 location
    tolerance. (A defective double eigenvalue itself is computed with an error ~ sqrt(eps)
    scale ~ 1.5e-8 scale, which also only matters within ~eps scale^2 / |c| of p*.)

Tracking. Eigenvalues of consecutive points are matched by the assignment that minimises
sum_i |lambda_i(prev) - lambda_perm(i)(new)| (scipy.optimize.linear_sum_assignment); when
every eigenvalue's nearest new eigenvalue is distinct, that nearest-neighbour map is already
optimal and the assignment solve is skipped. Column i of a branch's eigenvalue array is then
one continuous eigenvalue (up to the arbitrary choice at a collision).

Devices. Every dense spectrum of the core is taken by eigensystem(): LAPACK's dgeev on the CPU,
or cuSOLVER's geev on a GPU (gpu.py), on the device an eigensolver names
(eigensolvers.DenseSpectra(device)) or else inside `with spectra_on("gpu" | "cpu" | "auto"):`.
The default, "auto", sends an n x n matrix to the GPU from n = GPU_FROM on where CuPy and a
CUDA device are present, and keeps everything on the CPU elsewhere (CI, any machine without
one).
"""
from __future__ import annotations

import contextlib
from dataclasses import dataclass
from enum import StrEnum
from typing import Optional

import numpy as np
import scipy.linalg as sla
from scipy.optimize import linear_sum_assignment

from diskfriction.errors import OneLineError

from diskfriction.continuation.spectra import gpu as gpu_spectra
from diskfriction.continuation.linalg.solves import book, row_norms

Array = np.ndarray

DEFAULT_REL_TOL = 1e-9
_TINY = np.finfo(float).tiny


class Kind(StrEnum):
    """A collision's kind along the branch direction: two real eigenvalues meet and leave the
    real axis as a conjugate pair (birth), or the reverse (death). str-valued: a Kind is its
    name in every file and line (collisions.json's "kind")."""

    BIRTH = "birth"
    DEATH = "death"

    @property
    def sign(self) -> int:
        """The change of the complex-pair count across the collision: +1 or -1."""
        return 1 if self is Kind.BIRTH else -1

    def real_side(self, before, after):
        """Of an interval's ends (samples, points) before and after it, the one where the pair
        is real."""
        return before if self is Kind.BIRTH else after


def spectral_scale(eigvals: Array) -> float:
    """max(max_k |lambda_k|, tiny): the magnitude relative thresholds refer to."""
    return max(float(np.max(np.abs(eigvals), initial=0.0)), _TINY)


def imag_threshold(eigvals: Array, rel_tol: float = DEFAULT_REL_TOL) -> float:
    """rel_tol * spectral_scale(eigvals): |Im| above it counts as complex."""
    return rel_tol * spectral_scale(eigvals)


def eigen_status(eigvals: Array, rel_tol: float = DEFAULT_REL_TOL) -> Array:
    """Per eigenvalue: +1 if Im > thr (upper member of a pair), -1 if Im < -thr, 0 real."""
    return status_at(eigvals, imag_threshold(eigvals, rel_tol))


def status_at(eigvals: Array, thr: float) -> Array:
    """eigen_status with a given threshold (a few eigenvalues of a spectrum whose scale is
    known from a neighbouring full one)."""
    im = np.imag(eigvals)
    return (im > thr).astype(np.int8) - (im < -thr).astype(np.int8)


def count_complex_pairs(eigvals: Array, rel_tol: float = DEFAULT_REL_TOL) -> int:
    """Number of complex-conjugate pairs: #{k: Im lambda_k > rel_tol * max(max|lambda|, tiny)}."""
    return int(np.count_nonzero(np.imag(eigvals) > imag_threshold(eigvals, rel_tol)))


def sort_spectrum(eigvals: Array) -> Array:
    """Eigenvalues ordered by (Re, Im): a reproducible order for the first point of a branch."""
    eigvals = np.asarray(eigvals, dtype=complex)
    return eigvals[np.lexsort((eigvals.imag, eigvals.real))]


def match_eigenvalues(reference: Array, eigvals: Array) -> Array:
    """Permutation perm such that eigvals[perm][i] continues reference[i].

    Minimises sum_i |reference_i - eigvals_perm(i)|; if the row-wise nearest neighbours
    already form a permutation, that is the optimum (each term at its lower bound).
    """
    cost = np.abs(reference[:, None] - eigvals[None, :])
    nearest = np.argmin(cost, axis=1)
    if np.unique(nearest).size == nearest.size:
        return nearest
    return linear_sum_assignment(cost)[1]


def track(reference: Array, eigvals: Array) -> Array:
    """eigvals reordered to continue reference (see match_eigenvalues)."""
    return eigvals[match_eigenvalues(reference, eigvals)]


def pair_discriminant(lam_i, lam_j, status_i, status_j):
    """Discriminant of a pair, consistent with the classification (works on arrays).

    For the 2x2 invariant subspace of the pair, D = (lambda_i - lambda_j)^2 = tr^2 - 4 det is
    real and smooth in p, positive for two real eigenvalues and negative for a conjugate pair;
    a collision is a sign change of D. Returned:
        both real (status 0, 0):          D = (Re lambda_i - Re lambda_j)^2 >= 0
        conjugate (status +1, -1):        D = -(Im lambda_i - Im lambda_j)^2 < 0
        anything else:                    nan (the two cannot collide with each other here).
    """
    st_i, st_j = np.asarray(status_i), np.asarray(status_j)
    real = (st_i == 0) & (st_j == 0)
    conj = (st_i * st_j) == -1
    d_re = np.real(lam_i) - np.real(lam_j)
    d_im = np.imag(lam_i) - np.imag(lam_j)
    return np.where(real, d_re**2, np.where(conj, -d_im**2, np.nan))


def conjugate_pairing(eigvals: Array, upper: Array, lower: Array,
                      other: Array | None = None) -> list[tuple[int, int]]:
    """Pair indices `upper` (Im > 0) with indices `lower` (Im < 0); returns [(u, l), ...].

    Minimises sum |lambda_u - conj(lambda_l)|, plus, when the same labels' eigenvalues `other`
    at the other end of an interval are given, |mean_other(u, l) - mean(u, l)|: the mean
    (lambda_u + lambda_l) / 2 of a colliding pair (half the trace of its block) is continuous
    through the collision, which resolves ties between multiple eigenvalues.
    """
    upper, lower = np.asarray(upper, dtype=int), np.asarray(lower, dtype=int)
    if upper.size == 0 or lower.size == 0:
        return []
    lu, ll = eigvals[upper][:, None], eigvals[lower][None, :]
    cost = np.abs(lu - np.conj(ll))
    if other is not None:
        cost = cost + np.abs((other[upper][:, None] + other[lower][None, :]) / 2 - (lu + ll) / 2)
    rows, cols = linear_sum_assignment(cost)
    return [(int(upper[r]), int(lower[c])) for r, c in zip(rows, cols)]


@dataclass(frozen=True)
class Eigensystem:
    """Eigenvalues of a stability matrix A with, optionally, right vectors (columns of `right`,
    A r_i = lambda_i r_i) and left vectors (rows of `left`, l_i^H A = lambda_i l_i^H) scaled so
    that l_i^H r_i = 1; `excluded` marks modes kept out of collision detection (exactly
    decoupled modes or the zero modes of a gauge, structure.py, whose eigenvalues can never
    become complex; or, when only a spectral window is tracked, the eigenvalues beyond its
    guard band: window.py); `guard` marks
    the eigenvalues in a window's guard band, the only ones that may enter or leave the
    tracked set between two samples; `columns`, when only some eigenvalues have vectors (a
    partial sample, samples.partial_sample_at; a reduced eigensystem's, structure.embedded),
    the column of `right` and row of `left` of each eigenvalue (-1: none), else None
    (eigenvalue i has column i); `disc`, when only the eigenvalues nearest a shift were computed
    (a spectral window), (sigma, radius): every eigenvalue with |lambda - sigma| < radius is
    among `values`, and radius is the largest |lambda_i - sigma| of them; None: all computed;
    `band`, with a window, the certified band (lo, hi) of Re lambda (SpectralWindow.certified: no
    collision beyond it is located), None: every eigenvalue is certified."""

    values: Array
    right: Optional[Array] = None
    left: Optional[Array] = None
    excluded: Optional[Array] = None
    guard: Optional[Array] = None
    columns: Optional[Array] = None
    disc: Optional[tuple[float, float]] = None
    band: Optional[tuple[float, float]] = None

    def vectors(self, i: int) -> tuple[Array, Array]:
        """(right vector, left vector) of eigenvalue i."""
        c = i if self.columns is None else int(self.columns[i])
        if c < 0:
            raise ValueError(f"eigenvalue {i} has no vectors")
        return self.right[:, c], self.left[c]

    def permuted(self, perm: Array) -> "Eigensystem":
        """The same eigensystem with labels new[i] = old[perm[i]]. The vectors are shared, not
        copied: `columns` says which of them each label has (a relabelling costs O(n), not
        two n x n copies)."""
        pick = lambda a: None if a is None else a[perm]  # noqa: E731
        columns = None if self.right is None else (perm if self.columns is None else self.columns[perm])
        return Eigensystem(self.values[perm], self.right, self.left, pick(self.excluded), pick(self.guard),
                           columns, self.disc, self.band)


class SpectraDevice(StrEnum):
    """Where eigensystem() takes dense spectra: "cpu" (LAPACK), "gpu" (cuSOLVER, every size;
    gpu.py) or "auto" (the GPU from n = GPU_FROM on where one is usable, else the CPU)."""

    CPU = "cpu"
    GPU = "gpu"
    AUTO = "auto"


GPU_FROM = 1000
"""Matrix size from which "auto" takes dense spectra on a GPU (benchmarks/dense_spectrum.py
--spectra cpu,gpu; docs/notes/core-spectra.md, "Dense spectra on a GPU": one spectrum 4.6 times
faster on an H100 at n = 1002, while at n = 600 two CPU scan workers match the GPU's inline
sweep)."""

_DEVICE = [SpectraDevice.AUTO]


class NoGpu(OneLineError, RuntimeError):
    """spectra_on("gpu") where no GPU spectra can run (gpu_spectra.unavailable says why)."""

    exit_code = 2


@contextlib.contextmanager
def spectra_on(device: str):
    """Dense spectra on `device` (a SpectraDevice or its name) inside the block. NoGpu for
    "gpu" where CuPy or a CUDA device is missing; ValueError for an unknown name."""
    device = SpectraDevice(device)
    if device is SpectraDevice.GPU and (why := gpu_spectra.unavailable()) is not None:
        raise NoGpu(why)
    before, _DEVICE[0] = _DEVICE[0], device
    try:
        yield
    finally:
        _DEVICE[0] = before


def on_gpu(n: int, device: Optional[SpectraDevice] = None) -> bool:
    """Whether eigensystem() takes an n x n spectrum on the GPU on `device` (None: the current
    one, spectra_on's)."""
    device = _DEVICE[0] if device is None else SpectraDevice(device)
    if device is SpectraDevice.AUTO:
        return n >= GPU_FROM and gpu_spectra.unavailable() is None
    return device is SpectraDevice.GPU


def eigensystem(A: Array, vectors: bool, device: Optional[SpectraDevice] = None) -> Eigensystem:
    """All eigenvalues of the dense matrix A (LAPACK dgeev, or cuSOLVER's geev where on_gpu on
    `device`, None: spectra_on's: gpu.py; LAPACK where the GPU's right vectors are singular or
    its memory is too small), with left and right vectors normalised to l_i^H r_i = 1 if
    `vectors`; booked as a full spectrum (solves.book)."""
    book("spectra")
    if on_gpu(A.shape[0], device) and (arrays := gpu_spectra.eigensystem_arrays(A, vectors)) is not None:
        return Eigensystem(*arrays)
    if not vectors:
        return Eigensystem(np.linalg.eigvals(A).astype(complex))
    lam, vl, vr = sla.eig(A, left=True, right=True, check_finite=False)
    left = vl.conj().T
    scale = np.einsum("ij,ji->i", left, vr)
    return Eigensystem(lam.astype(complex), vr, left / scale[:, None])


def condition_numbers(system: Eigensystem) -> Array:
    """kappa_i = |l_i| |r_i| / |l_i^H r_i| of every eigenvalue (|l_i| |r_i| with the vectors'
    normalisation l_i^H r_i = 1): the eigenvalue's sensitivity to a perturbation of the matrix,
    |d lambda_i| <= kappa_i |dA| (Wilkinson); 1 for a normal matrix, and growing like
    |p - p_c|^(-1/2) towards a collision, where the pair's left and right vectors become
    orthogonal. nan for an eigenvalue without vectors (Eigensystem.columns -1) or a system
    without them."""
    kappa = np.full(system.values.size, np.nan)
    if system.right is None:
        return kappa
    columns = np.arange(system.values.size) if system.columns is None else system.columns
    have = columns >= 0
    c = columns[have]
    kappa[have] = (row_norms(system.right.T) * row_norms(system.left))[c]
    return kappa


SLOPE_COLUMNS = 256
"""Vectors per block in eigenvalue_slopes: dA r for all n vectors at once is an n x n temporary
(144 MB at n = 3000); by blocks the same values, bit for bit."""


def eigenvalue_slopes(system: Eigensystem, dA: Array) -> Array:
    """d lambda_i = l_i^H dA r_i for a perturbation dA of the matrix (first-order perturbation
    of simple eigenvalues; infinite at a collision, where the pair's discriminant stays smooth).
    dA dense or sparse. An eigenvalue without vectors (Eigensystem.columns -1: a free disk's
    mode, kept out of collision detection, models/chain/equilibria.py) gets 0: its slope only
    predicts where it goes for tracking, and a free disk's block changes only through pair
    overlaps of rounding size."""
    right, left = system.right, system.left
    slopes = np.concatenate([np.einsum("ij,ji->i", left[c:c + SLOPE_COLUMNS], dA @ right[:, c:c + SLOPE_COLUMNS])
                             for c in range(0, right.shape[1], SLOPE_COLUMNS)])
    if system.columns is None:
        return slopes
    return np.where(system.columns >= 0, slopes[system.columns], 0.0)
