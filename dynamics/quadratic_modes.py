"""The modes of a linearization with a general damping, M q'' + C q' + K q = 0: q = r e^(s t)
where

    det(s^2 M + s C + K) = 0,

2n exponents s [1 / time] for n degrees of freedom. Where C = eta M (a drag on every degree of
freedom) they are dynamics/damped_modes.py's, known from the eigenvalues of M^-1 K alone; a
damping that acts on relative contact velocities only (models/packing/contact_damping.py) has a C
that does not commute with M^-1 K, and the exponents are those of the quadratic eigenproblem.

It is solved by a first-order linearization in (q, q' / w), with w = sqrt(||M^-1 K||_inf) a
frequency scale [1 / time] that makes the four blocks of the same size:

    M diagonal:   A = [[0, I], [-M^-1 K / w^2, -M^-1 C / w]],   A x = sigma x,
    M a matrix:   [[0, I], [-K / w^2, -C / w]] x = sigma [[I, 0], [0, M]] x,

s = w sigma, by scipy.linalg.eig (LAPACK's QZ for the generalized form, balanced QR for A).
Dividing by a positive diagonal M rounds each entry once (no solve), so the standard form loses
nothing to the generalized one and costs half as much.

Rigid-body modes (K T = 0 and C T = 0: a packing's translations) are Jordan blocks of size 2 at
s = 0, which rounding splits into s ~ +-w sqrt(eps) ~ 1e-8 w, real or imaginary: no tolerance
on eps tells them apart from a slow mode. largest_growth therefore drops them by count, the
2 r exponents nearest 0 for r rigid modes.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp


def _dense(matrix) -> np.ndarray:
    """A dense float array of a dense or scipy.sparse matrix."""
    return matrix.toarray() if sp.issparse(matrix) else np.asarray(matrix, dtype=float)


def quadratic_exponents(mass, C, K) -> np.ndarray:
    """(2n,) complex: every s with det(s^2 M + s C + K) = 0 [1 / time], in decreasing real part
    (then imaginary part). mass: diag(M) (n,) > 0, or M (n, n) [mass]; C (n, n) [mass / time] and
    K (n, n) [mass / time^2], dense or scipy.sparse (module docstring)."""
    C, K = _dense(C), _dense(K)
    n = K.shape[0]
    mass = mass.toarray() if sp.issparse(mass) else np.asarray(mass, dtype=float)
    diagonal = mass.ndim == 1
    scaled_K = K / mass[:, None] if diagonal else np.linalg.solve(mass, K)
    w = float(np.sqrt(np.abs(scaled_K).sum(axis=1).max(initial=0.0))) or 1.0
    if diagonal:
        A = np.block([[np.zeros((n, n)), np.eye(n)],
                      [-scaled_K / w**2, -C / (mass[:, None] * w)]])
        sigma = sla.eigvals(A, overwrite_a=True, check_finite=False)
    else:
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-K / w**2, -C / w]])
        B = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), mass]])
        sigma = sla.eigvals(A, B, overwrite_a=True, check_finite=False)
    s = w * sigma
    return s[np.lexsort((-s.imag, -s.real))]


def largest_growth(exponents: np.ndarray, rigid: int = 0) -> float:
    """max Re s [1 / time] over `exponents` less the 2 `rigid` nearest 0 (one Jordan pair per
    rigid-body mode: module docstring); positive where a mode grows."""
    s = np.asarray(exponents)
    kept = np.argsort(np.abs(s), kind="stable")[2 * rigid:]
    return float(s[kept].real.max())
