"""Certifying an interval between two samples: no collision can hide inside it.

A collision of two eigenvalues is a sign change of the pair's discriminant
    D = (lambda_i - lambda_j)^2,
smooth through the collision where the eigenvalues themselves are not. Per pair the test
function is y = |lambda_i - lambda_j|^2: D for two real eigenvalues, 4 (Im lambda_i)^2 = -D for
conjugate partners; y > 0 at both ends, and a collision inside needs y to reach 0. Besides these
two kinds, a complex eigenvalue and a real one are tested too: a complex pair can die and its
member be born again with another real partner within one interval (a fast eigenvalue passing
through a cluster does this: the paper's scene at F_x = 0.004), and the member's distance to the
new partner must then reach 0.

Fast detection (samples with slopes): y and dy/dt at both ends (t in [0, 1] across the interval;
dy = 2 Re(conj(lambda_i - lambda_j)(lambda_i' - lambda_j'))) define the cubic Hermite
interpolant H(t) = c0 + c1 t + c2 t^2 + c3 t^3. The pair is certified if

    min_[0,1] H  -  |c3| / 4   >=   rho min(y_a, y_b)  -  floor,

i.e. the cubic model stays above a fraction rho of the smaller end value even after taking a
quarter of its cubic term as uncertain (a model whose cubic term matters is trusted less).
floor = 4 thr^2 (thr the status threshold): below it nothing can be resolved. A uniformly moving
pair (y quadratic in t) is certified however far it moves; a pair approaching, narrowly missing or
passing through each other is not. The labels themselves are checked: an eigenvalue whose end
values disagree with its slopes by more than rho times its gap to the nearest other eigenvalue
(trapezoid defect |lambda_b - lambda_a - (lambda_a' + lambda_b') / 2|) was tracked across an
encounter the slopes do not explain, so the interval is not certified either.

Exhaustive detection (samples without slopes, as in version 0.1): the quadratic through the two
ends and a third sample (a "stencil" with the same status) and the motion of every real
eigenvalue against its gap (collisions.py keeps that variant).

Everything here is a pure function of arrays.
"""
from __future__ import annotations

import numpy as np

Array = np.ndarray


def hermite_coefficients(y0: Array, y1: Array, d0: Array, d1: Array) -> tuple[Array, ...]:
    """(c0, c1, c2, c3) of the cubic with H(0) = y0, H(1) = y1, H'(0) = d0, H'(1) = d1."""
    return y0, d0, 3.0 * (y1 - y0) - 2.0 * d0 - d1, 2.0 * (y0 - y1) + d0 + d1


def cubic_at(c: tuple[Array, ...], t) -> Array:
    c0, c1, c2, c3 = c
    return c0 + t * (c1 + t * (c2 + t * c3))


def cubic_min(c: tuple[Array, ...]) -> tuple[Array, Array]:
    """(min over [0, 1] of the cubic, where it is attained), elementwise."""
    c0, c1, c2, c3 = (np.asarray(a, dtype=float) for a in c)
    cands = [np.zeros_like(c0), np.ones_like(c0)]
    a, b, k = 3.0 * c3, 2.0 * c2, c1  # H' = a t^2 + b t + k
    with np.errstate(divide="ignore", invalid="ignore"):
        disc = np.sqrt(np.maximum(b * b - 4.0 * a * k, 0.0))
        quad = np.abs(a) > 1e-300
        for sign in (1.0, -1.0):
            root = np.where(quad, (-b + sign * disc) / (2.0 * a), -k / b)
            cands.append(np.where(np.isfinite(root), np.clip(root, 0.0, 1.0), 0.0))
    ts = np.stack(cands)
    vals = cubic_at(tuple(x[None] for x in (c0, c1, c2, c3)), ts)
    k = np.argmin(vals, axis=0)
    return np.take_along_axis(vals, k[None], 0)[0], np.take_along_axis(ts, k[None], 0)[0]


def cubic_roots_in_unit(c: tuple[float, ...]) -> list[float]:
    """Sign changes of a scalar cubic on [0, 1], located by bisection on a fine grid."""
    t = np.linspace(0.0, 1.0, 65)
    v = cubic_at(c, t)
    roots = []
    for k in np.flatnonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0):
        lo, hi = t[k], t[k + 1]
        for _ in range(50):
            mid = 0.5 * (lo + hi)
            if np.sign(cubic_at(c, mid)) == np.sign(cubic_at(c, lo)):
                lo = mid
            else:
                hi = mid
        roots.append(0.5 * (lo + hi))
    return roots


def pair_test_data(lam_a: Array, lam_b: Array, d_a: Array, d_b: Array, I: Array,
                   J: Array) -> tuple[Array, Array, Array, Array]:
    """(y_a, y_b, y'_a, y'_b) of y = |lambda_I - lambda_J|^2 for pairs (I, J); slopes d =
    d lambda / dt over the interval, y' = 2 Re(conj(lambda_I - lambda_J)(d_I - d_J)). For two
    real eigenvalues y is the discriminant D, for conjugate partners y = 4 Im^2 = -D, for a
    complex and a real eigenvalue the squared distance in the complex plane."""
    g_a, g_b = lam_a[I] - lam_a[J], lam_b[I] - lam_b[J]
    dg_a, dg_b = d_a[I] - d_a[J], d_b[I] - d_b[J]
    return (np.abs(g_a) ** 2, np.abs(g_b) ** 2, 2.0 * np.real(np.conj(g_a) * dg_a),
            2.0 * np.real(np.conj(g_b) * dg_b))


def uncertified_pairs(y_a: Array, y_b: Array, dy_a: Array, dy_b: Array, rho: float,
                      floor: float, doubt: float = 0.25) -> tuple[Array, Array]:
    """(mask of pairs the cubic model does not certify, t of each pair's model minimum);
    doubt: the fraction of the cubic term taken as the model's uncertainty."""
    c = hermite_coefficients(y_a, y_b, dy_a, dy_b)
    low, t_min = cubic_min(c)
    bad = low - doubt * np.abs(c[3]) < rho * np.minimum(y_a, y_b) - floor
    return bad, t_min


GRID = np.linspace(0.0, 1.0, 33)


def event_pair_clearance(m: tuple, D: tuple, lam_a: Array, lam_b: Array, d_a: Array, d_b: Array,
                         rho: float, floor: float) -> tuple[Array, Array]:
    """For an event pair (its members change status inside the interval) and other eigenvalues
    k: w_k(t) = |m(t) - lambda_k(t)|^2 - |D(t)| / 4 on a grid of t, with m the pair's mean and D
    its discriminant (both smooth through the collision; cubic Hermite coefficients m, D) and
    lambda_k by its own cubic. The members stay within sqrt|D| / 2 of m, so w_k > 0 keeps them
    away from lambda_k. Returns (mask of k not certified, t of each w_k's minimum)."""
    t = GRID[:, None]
    mean = cubic_at(m, t)
    half = np.abs(cubic_at(D, t)) / 4.0
    re = cubic_at(hermite_coefficients(lam_a.real, lam_b.real, d_a.real, d_b.real), t)
    im = cubic_at(hermite_coefficients(lam_a.imag, lam_b.imag, d_a.imag, d_b.imag), t)
    w = (mean - re) ** 2 + im**2 - half
    low = w.min(axis=0)
    return low < rho * np.minimum(w[0], w[-1]) - floor, GRID[np.argmin(w, axis=0)]


def event_pairs_apart(models: list, rho: float, floor: float) -> tuple[bool, float]:
    """For several event pairs in one interval, models [(m, D), ...] (cubic coefficients of each
    pair's mean and discriminant): each two pairs' members stay apart if
    w(t) = (m_1 - m_2)^2 - (sqrt|D_1| + sqrt|D_2|)^2 / 4 > 0 (their members lie within
    sqrt|D| / 2 of their means, on the real axis or symmetric about it). Returns (all pairs
    certified on the grid, t of the worst minimum)."""
    t = GRID
    means = [cubic_at(m, t) for m, _ in models]
    radii = [0.5 * np.sqrt(np.abs(cubic_at(D, t))) for _, D in models]
    worst, t_worst = np.inf, 0.5
    for a in range(len(models)):
        for b in range(a + 1, len(models)):
            w = (means[a] - means[b]) ** 2 - (radii[a] + radii[b]) ** 2
            margin = w.min() - (rho * min(w[0], w[-1]) - floor)
            if margin < worst:
                worst, t_worst = margin, float(t[np.argmin(w)])
    return worst >= 0.0, t_worst


def inconsistent_labels(lam_a: Array, lam_b: Array, d_a: Array, d_b: Array, rho: float,
                        floor: float) -> Array:
    """Mask of eigenvalues whose trapezoid defect |lambda_b - lambda_a - (d_a + d_b) / 2|
    exceeds rho times their smallest gap to another eigenvalue (at either end) plus floor."""
    defect = np.abs(lam_b - lam_a - 0.5 * (d_a + d_b))

    def gaps(lam):
        d = np.abs(lam[:, None] - lam[None, :])
        np.fill_diagonal(d, np.inf)
        return d.min(axis=1) if lam.size > 1 else np.full(lam.size, np.inf)

    return defect > rho * np.minimum(gaps(lam_a), gaps(lam_b)) + floor


def curvature_too_large(y_a: Array, y_b: Array, y_c: Array, t_c: float, rho: float, floor: float) -> bool:
    """Exhaustive detection: True if for some k the quadratic q through (0, y_a), (1, y_b),
    (t_c, y_c) (t_c outside [0, 1]) bends by more than the certification margin:

        q(t) = y_a + (y_b - y_a) t + kappa t (t - 1),
        kappa = (y_c - y_a - (y_b - y_a) t_c) / (t_c (t_c - 1)),
        flag  if  |kappa| / 4 > (1 - rho) min(y_a, y_b) + floor.

    |kappa| / 4 is the largest deviation of q from the chord on [0, 1]; if it is within the
    margin, q >= rho min(y_a, y_b) - floor on the whole interval.
    """
    kappa = (y_c - y_a - (y_b - y_a) * t_c) / (t_c * (t_c - 1.0))
    return bool(np.any(0.25 * np.abs(kappa) > (1.0 - rho) * np.minimum(y_a, y_b) + floor))


def outruns_gaps(ev_a: Array, ev_b: Array, real: Array, rho: float, floor: float) -> bool:
    """Exhaustive detection: True if some eigenvalue real at both ends moves by more than rho
    times its gap,

        |lambda_i(b) - lambda_i(a)| > rho min(gap_i(a), gap_i(b)) + floor,
        gap_i = min over the other real eigenvalues j of |lambda_i - lambda_j|.

    Two real eigenvalues must meet to collide; if none moves by more than a fraction of the
    distance to its nearest neighbour, none reaches another inside the interval. The test needs
    no correct labels: a tracking that swaps two eigenvalues passing each other shows a
    displacement of about their gap, which fails it.
    """
    if real.size < 2:
        return False
    ra, rb = ev_a.real[real], ev_b.real[real]

    def gaps(r):
        d = np.abs(r[:, None] - r[None, :])
        np.fill_diagonal(d, np.inf)
        return d.min(axis=1)

    return bool(np.any(np.abs(rb - ra) > rho * np.minimum(gaps(ra), gaps(rb)) + floor))
