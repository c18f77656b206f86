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
Two real eigenvalues that pass through each other (modes that do not interact) never pass
that test: their y touches 0. Their signed gap g = lambda_i - lambda_j does not touch 0, it
crosses it: where its cubic model is transversal (slope >= rho times the secant's), the split
goes to its root, and an interval with the pair resolved at an end (|g| <= 2 thr) is certified
(_crossing).
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

import math

import numba
import numpy as np

Array = np.ndarray


def hermite_coefficients(y0: Array, y1: Array, d0: Array, d1: Array) -> tuple[Array, ...]:
    """(c0, c1, c2, c3) of the cubic with H(0) = y0, H(1) = y1, H'(0) = d0, H'(1) = d1."""
    return y0, d0, 3.0 * (y1 - y0) - 2.0 * d0 - d1, 2.0 * (y0 - y1) + d0 + d1


def cubic_at(c: tuple[Array, ...], t) -> Array:
    c0, c1, c2, c3 = c
    return c0 + t * (c1 + t * (c2 + t * c3))


@numba.njit(cache=True, error_model="numpy")
def _cubic_min(c0: float, c1: float, c2: float, c3: float) -> tuple[float, float]:
    """(min over [0, 1] of H = c0 + c1 t + c2 t^2 + c3 t^3, where it is attained): candidates
    t = 0, 1 and the two roots of H' = 3 c3 t^2 + 2 c2 t + c1 clipped to [0, 1] (a non-finite
    root counts as t = 0); the first of equal minima."""
    a, b, k = 3.0 * c3, 2.0 * c2, c1
    disc = math.sqrt(max(b * b - 4.0 * a * k, 0.0))
    best_v, best_t = c0, 0.0
    for sign in (0.0, 1.0, -1.0):  # 0: the end t = 1; +-1: the roots of H'
        t = 1.0
        if sign != 0.0:
            root = (-b + sign * disc) / (2.0 * a) if abs(a) > 1e-300 else -k / b
            t = min(max(root, 0.0), 1.0) if math.isfinite(root) else 0.0
        v = c0 + t * (c1 + t * (c2 + t * c3))
        if v < best_v:
            best_v, best_t = v, t
    return best_v, best_t


def stays_above(y0: Array, y1: Array, d0: Array, d1: Array, level: float, doubt: float) -> Array:
    """Whether each cubic Hermite model (ends y0, y1, slopes d0, d1 on [0, 1]) stays above
    `level` all along: its minimum, less doubt |c3| (the weight the certificates give the cubic
    term), is above it."""
    return _stays_above(*hermite_coefficients(*(np.asarray(v, dtype=float) for v in (y0, y1, d0, d1))),
                        level, doubt)


@numba.njit(cache=True, error_model="numpy")
def _stays_above(c0: Array, c1: Array, c2: Array, c3: Array, level: float, doubt: float) -> Array:
    out = np.empty(c0.size, np.bool_)
    for k in range(c0.size):
        out[k] = _cubic_min(c0[k], c1[k], c2[k], c3[k])[0] - doubt * abs(c3[k]) > level
    return out


@numba.njit(cache=True, error_model="numpy")
def _pair_margin(la: complex, lb: complex, da: complex, db: complex, rho: float, floor: float,
                 doubt: float) -> tuple[bool, float, float]:
    """One pair's certification from its difference g = lambda_i - lambda_j and slope dg at the
    two ends: (uncertified?, min(y_a, y_b), t of the model minimum), with y = |g|^2,
    y' = 2 Re(conj(g) dg) and the test of uncertified_pair (module docstring)."""
    y_a, y_b = abs(la) ** 2, abs(lb) ** 2
    dy_a = 2.0 * (la.real * da.real + la.imag * da.imag)
    dy_b = 2.0 * (lb.real * db.real + lb.imag * db.imag)
    c2, c3 = 3.0 * (y_b - y_a) - 2.0 * dy_a - dy_b, 2.0 * (y_a - y_b) + dy_a + dy_b
    low, t_min = _cubic_min(y_a, dy_a, c2, c3)
    y_min = min(y_a, y_b)
    return low - doubt * abs(c3) < rho * y_min - floor, y_min, t_min


@numba.njit(cache=True, error_model="numpy")
def _crossing(g_a: float, g_b: float, dg_a: float, dg_b: float, rho: float,
              resolution: float) -> tuple[bool, float]:
    """Two real eigenvalues passing through each other (modes that do not interact): their
    signed gap g = lambda_i - lambda_j (not its square) has a cubic Hermite model G on [0, 1]
    from g, g' at both ends. If G is transversal (|G'| >= rho |g_b - g_a| throughout: one
    simple root at most, no turning back) and the end nearer the crossing is resolved (|g| <=
    resolution there), no collision can hide inside: (True, nan). If G is transversal and
    changes sign inside, (False, the root of G): a sample there resolves the crossing. Else
    (False, nan)."""
    c0, c1 = g_a, dg_a
    c2, c3 = 3.0 * (g_b - g_a) - 2.0 * dg_a - dg_b, 2.0 * (g_a - g_b) + dg_a + dg_b
    least = min(c1, c1 + 2.0 * c2 + 3.0 * c3)  # G' at the ends and at its extremum inside
    most = max(c1, c1 + 2.0 * c2 + 3.0 * c3)
    if abs(c3) > 1e-300:
        t = -c2 / (3.0 * c3)
        if 0.0 < t < 1.0:
            inside = c1 + t * (2.0 * c2 + 3.0 * c3 * t)
            least, most = min(least, inside), max(most, inside)
    if least * most <= 0.0 or min(abs(least), abs(most)) < rho * abs(g_b - g_a):
        return False, math.nan
    if min(abs(g_a), abs(g_b)) <= resolution:
        return True, math.nan
    if g_a * g_b >= 0.0:
        return False, math.nan
    lo, hi = 0.0, 1.0  # G is monotone: bisect its sign change
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if (c0 + mid * (c1 + mid * (c2 + mid * c3))) * g_a > 0.0:
            lo = mid
        else:
            hi = mid
    return False, 0.5 * (lo + hi)


FAR_SLACK = 1.001
"""Factor on the reaches (reaches): a pair it skips passes the pair test with a margin far above
the test's rounding."""


@numba.njit(cache=True, error_model="numpy")
def reaches(lam_a: Array, lam_b: Array, d_a: Array, d_b: Array, labels: Array, rho: float,
            doubt: float) -> Array:
    """Each label's reach r over the interval: two labels i, j with |Re lambda_i - Re lambda_j|
    >= r_i + r_j at its start pass the pair test of uncertified_pairs. With delta_i =
    |lambda_i(b) - lambda_i(a)|, s_i = max(|d_a|, |d_b|) (per unit of the interval) and D =
    |lambda_i(a) - lambda_j(a)|, the pair's gap g has |g_a| = D, ||g_b| - D| <= delta =
    delta_i + delta_j and |dg| <= s = s_i + s_j, so y_min >= (D - delta)^2, |dy_a| + |dy_b| <=
    2 s (2D + delta) and |y_a - y_b| <= delta (2D + delta). The Hermite basis gives min H >=
    y_min - (4/27)(|dy_a| + |dy_b|), and |c3| <= 2|y_a - y_b| + |dy_a| + |dy_b|, so the test
    holds where (1 - rho) u^2 >= (2u + 3 delta) K, u = D - delta, K = 2 (4/27 + doubt) s +
    2 doubt delta (floor >= 0 only helps), i.e. for u >= 2K / (1 - rho) + sqrt(3 delta K /
    (1 - rho)); since sqrt(delta K) <= (delta + K) / 2, that holds wherever D >= (1 + gamma)
    delta + (2 / (1 - rho) + gamma) K, gamma = sqrt(3 / (1 - rho)) / 2: a sum of one term per
    label, r_i = FAR_SLACK ((1 + gamma) delta_i + (2 / (1 - rho) + gamma) K_i), K_i =
    2 (4/27 + doubt) s_i + 2 doubt delta_i (nan where a label's values are not finite)."""
    gamma = 0.5 * math.sqrt(3.0 / (1.0 - rho))
    out = np.empty(labels.size)
    for a in range(labels.size):
        i = labels[a]
        moved = abs(lam_b[i] - lam_a[i])
        k = 2.0 * (4.0 / 27.0 + doubt) * max(abs(d_a[i]), abs(d_b[i])) + 2.0 * doubt * moved
        out[a] = FAR_SLACK * ((1.0 + gamma) * moved + (2.0 / (1.0 - rho) + gamma) * k)
    return out


@numba.njit(cache=True, error_model="numpy")
def _real_pair(lam_a: Array, lam_b: Array, d_a: Array, d_b: Array, i: int, j: int, rho: float,
               floor: float, doubt: float, resolution: float) -> tuple[bool, float, float, bool]:
    """The test of two real labels (uncertified_pairs): (uncertified?, min(y_a, y_b), where to
    split: the model minimum or a crossing's root, crossing?)."""
    bad, y, t = _pair_margin(lam_a[i] - lam_a[j], lam_b[i] - lam_b[j], d_a[i] - d_a[j],
                             d_b[i] - d_b[j], rho, floor, doubt)
    if not bad:
        return False, y, t, False
    passed, root = _crossing((lam_a[i] - lam_a[j]).real, (lam_b[i] - lam_b[j]).real,
                             (d_a[i] - d_a[j]).real, (d_b[i] - d_b[j]).real, rho, resolution)
    if passed:
        return False, y, t, False
    return True, y, (t if math.isnan(root) else root), not math.isnan(root)


@numba.njit(cache=True, error_model="numpy")
def _uncertified_real_pairs(lam_a: Array, lam_b: Array, d_a: Array, d_b: Array, real: Array,
                            rho: float, floor: float, doubt: float):
    """The uncertified pairs of two real labels (_real_pair), as arrays (i, j, min(y_a, y_b),
    where to split, crossing?) in pair order (a double loop over the positions in `real`). Pairs
    whose real parts lie their reaches apart (reaches) pass and are not looked at: a sweep over
    the labels by Re lambda, each looking ahead while the gap is below its reach plus the
    largest one, O(n log n + the pairs looked at) time and memory for the uncertified ones;
    where a value is not finite, every pair is looked at in order."""
    n = real.size
    resolution = math.sqrt(floor)
    x = lam_a[real].real
    r = reaches(lam_a, lam_b, d_a, d_b, real, rho, doubt)
    finite = bool(np.all(np.isfinite(x)) and np.all(np.isfinite(r)))
    order = np.argsort(x) if finite else np.arange(n)
    top = r.max() if finite and n > 0 else np.inf
    K = []
    Y = []
    T = []
    C = []
    for p in range(n):
        a = order[p]
        for q in range(p + 1, n):
            b = order[q]
            if finite:
                gap = x[b] - x[a]
                if gap >= r[a] + top:
                    break
                if gap >= r[a] + r[b]:
                    continue
            lo, hi = min(a, b), max(a, b)
            bad, y, t, crossing = _real_pair(lam_a, lam_b, d_a, d_b, real[lo], real[hi], rho, floor,
                                             doubt, resolution)
            if bad:
                K.append(lo * n + hi)
                Y.append(y)
                T.append(t)
                C.append(crossing)
    keys, first = _key_order(K)
    return (real[keys // max(n, 1)], real[keys % max(n, 1)], np.array(Y, np.float64)[first],
            np.array(T, np.float64)[first], np.array(C, np.bool_)[first])


@numba.njit(cache=True)
def _key_order(K):
    """The pair keys K (a list of int64) in ascending order, and the order that sorts them."""
    keys = np.array(K, np.int64)
    first = np.argsort(keys)
    return keys[first], first


@numba.njit(cache=True, error_model="numpy")
def uncertified_pairs(lam_a: Array, lam_b: Array, d_a: Array, d_b: Array, real: Array,
                      upper: Array, partner: Array, rho: float, floor: float,
                      doubt: float) -> tuple[Array, Array, Array, Array, Array]:
    """Every pair that could collide over the interval (t in [0, 1]) and is not certified;
    lam_*: complex eigenvalues at the ends in tracked order, d_*: their slopes d lambda / dt.
    Pairs: two real eigenvalues (labels `real`), an upper complex one with a real one (`upper`
    x `real`), and each upper one with its conjugate partner (`upper[k]`, `partner[k]`;
    partner is empty when there is no lower one); in that order.

    A pair is uncertified if its cubic Hermite model H of y = |lambda_i - lambda_j|^2 (y and
    y' = 2 Re(conj(lambda_i - lambda_j)(lambda_i' - lambda_j')) at both ends) has
        min_[0,1] H - doubt |c3| < rho min(y_a, y_b) - floor,
    and, for two real ones, _crossing does not certify them either. Returns arrays (i, j,
    min(y_a, y_b), where to split: the model minimum or a crossing's root, crossing?) in pair
    order. Two real ones, or an upper one and a real one, whose real parts lie their reaches
    apart pass the test and are not looked at (_uncertified_real_pairs,
    _uncertified_mixed_pairs); the conjugate pairs are O(pairs) time. Arrays only of the
    uncertified pairs."""
    I, J, Y, T, C = _uncertified_real_pairs(lam_a, lam_b, d_a, d_b, real, rho, floor, doubt)
    MI, MJ, MY, MT = _uncertified_mixed_pairs(lam_a, lam_b, d_a, d_b, upper, real, rho, floor, doubt)
    UI = []
    UJ = []
    UY = []
    UT = []
    for k in range(partner.size):  # each upper one with its partner
        i, j = upper[k], partner[k]
        bad, y, t = _pair_margin(lam_a[i] - lam_a[j], lam_b[i] - lam_b[j], d_a[i] - d_a[j],
                                 d_b[i] - d_b[j], rho, floor, doubt)
        if bad:
            UI.append(i)
            UJ.append(j)
            UY.append(y)
            UT.append(t)
    m = MI.size + len(UI)
    return (np.concatenate((I, MI, np.array(UI, np.int64))), np.concatenate((J, MJ, np.array(UJ, np.int64))),
            np.concatenate((Y, MY, np.array(UY, np.float64))), np.concatenate((T, MT, np.array(UT, np.float64))),
            np.concatenate((C, np.zeros(m, np.bool_))))


@numba.njit(cache=True, error_model="numpy")
def _uncertified_mixed_pairs(lam_a: Array, lam_b: Array, d_a: Array, d_b: Array, upper: Array,
                             real: Array, rho: float, floor: float, doubt: float):
    """The uncertified pairs of an upper complex label with a real one (_pair_margin), as arrays
    (i, j, min(y_a, y_b), where to split) in pair order (upper by upper, each with the real
    labels in their order). A pair whose real parts lie their reaches apart (reaches, whose
    bound holds for complex labels too: |lambda_i - lambda_j| >= |Re lambda_i - Re lambda_j|)
    passes and is not looked at: the real labels sorted by Re lambda, each upper one looks only
    within its reach plus the largest real one of its real part; where a value is not finite,
    every pair is looked at."""
    n_real, n_upper = real.size, upper.size
    x = lam_a[real].real
    r_real = reaches(lam_a, lam_b, d_a, d_b, real, rho, doubt)
    r_upper = reaches(lam_a, lam_b, d_a, d_b, upper, rho, doubt)
    # a finite reach needs finite values at both ends
    finite = bool(np.all(np.isfinite(r_real))) and bool(np.all(np.isfinite(r_upper)))
    order = np.argsort(x) if finite else np.arange(n_real)
    xs = x[order]
    top = r_real.max() if finite and n_real > 0 else np.inf
    K = []
    Y = []
    T = []
    for u in range(n_upper):
        i = upper[u]
        lo, hi = 0, n_real
        if finite:
            lo = np.searchsorted(xs, lam_a[i].real - r_upper[u] - top)
            hi = np.searchsorted(xs, lam_a[i].real + r_upper[u] + top, side="right")
        for q in range(lo, hi):
            p = order[q]
            if finite and abs(x[p] - lam_a[i].real) >= r_upper[u] + r_real[p]:
                continue
            j = real[p]
            bad, y, t = _pair_margin(lam_a[i] - lam_a[j], lam_b[i] - lam_b[j], d_a[i] - d_a[j],
                                     d_b[i] - d_b[j], rho, floor, doubt)
            if bad:
                K.append(u * n_real + p)
                Y.append(y)
                T.append(t)
    keys, first = _key_order(K)
    return (upper[keys // max(n_real, 1)], real[keys % max(n_real, 1)], np.array(Y, np.float64)[first],
            np.array(T, np.float64)[first])


def worst_uncertified_pair(lam_a: Array, lam_b: Array, d_a: Array, d_b: Array, real: Array,
                           upper: Array, partner: Array, rho: float, floor: float,
                           doubt: float = 0.25, spared=None) -> tuple[float, Array, bool]:
    """Of the uncertified_pairs (same arguments), the pairs not spared (a function of the
    arrays (i, j) giving a mask of pairs to leave out, or None): (where to split, at the pair
    with the smallest min(y_a, y_b) (the first such), or nan if none is left; the mask of
    labels in any of them; whether that split is at a crossing's root)."""
    I, J, Y, T, C = uncertified_pairs(lam_a, lam_b, d_a, d_b, real, upper, partner, rho, floor,
                                      doubt)
    if spared is not None and I.size:
        keep = ~spared(I, J)
        I, J, Y, T, C = I[keep], J[keep], Y[keep], T[keep], C[keep]
    trouble = np.zeros(lam_a.size, bool)
    if not I.size:
        return math.nan, trouble, False
    trouble[I] = trouble[J] = True
    k = int(np.argmin(Y))
    return float(T[k]), trouble, bool(C[k])


def decoupled(g: Array, dg: Array, coupling: Array, thr: float) -> Array:
    """Mask of pairs that do not interact near a sample, by their 2 x 2 model there: in the
    eigenbasis at the sample, A(tau) ~ diag(lambda_i, lambda_j) + tau M (M = L dA/dtau R), the
    pair's discriminant is D(tau) = (g + tau g')^2 + 4 tau^2 m_ij m_ji (g = lambda_i -
    lambda_j, g' its slope, `coupling` = m_ij m_ji). If D dips below 0, the imaginary part of
    the pair born there reaches at most |g| sqrt|c| / sqrt(g'^2 - 4|c|) (c the coupling); the
    pair is decoupled if that bound is within the status threshold thr (an excursion no sample
    could see as complex) and g'^2 > 4|c|. Modes of different symmetry (Fourier modes of a
    homogeneous state) have c at rounding level and pass through each other."""
    c = np.abs(coupling)
    slope2 = np.abs(dg) ** 2
    return (slope2 > 4.0 * c) & (np.abs(g) ** 2 * c <= thr * thr * (slope2 - 4.0 * c))


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


@numba.njit(cache=True, error_model="numpy")
def nearest_gaps(lam: Array) -> Array:
    """|lambda_i - lambda_j| minimised over j != i (inf for a single eigenvalue). In order of
    real part, each eigenvalue looks at its neighbours only while their real parts differ by
    less than its best distance so far (the nearest one is among them): about n log n for a
    spectrum, where all pairs cost n^2."""
    n = lam.size
    gaps = np.full(n, np.inf)
    order = np.argsort(lam.real)
    re = lam.real[order]
    for a in range(n):
        i = order[a]
        for step in (1, -1):
            b = a + step
            while 0 <= b < n and abs(re[b] - re[a]) < gaps[i]:
                gaps[i] = min(gaps[i], abs(lam[i] - lam[order[b]]))
                b += step
    return gaps


def inconsistent_labels(lam_a: Array, lam_b: Array, d_a: Array, d_b: Array, gaps_a: Array,
                        gaps_b: Array, rho: float, floor: float) -> Array:
    """Mask of eigenvalues whose trapezoid defect |lambda_b - lambda_a - (d_a + d_b) / 2|
    exceeds rho times their smallest gap to another eigenvalue (gaps_* at either end,
    nearest_gaps) plus floor. A label with a nan is never flagged (the caller masks it out)."""
    defect = np.abs(lam_b - lam_a - 0.5 * (d_a + d_b))
    return defect > rho * np.minimum(gaps_a, gaps_b) + floor


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
