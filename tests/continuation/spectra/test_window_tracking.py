"""A spectral window's stored columns: each one eigenvalue, continued across entries and exits
(docs/continuation.md, A spectral window), checked against the full spectrum of the same
sweep and on the rule's parts."""
from dataclasses import replace

import numpy as np
import pytest

from diskfriction.continuation.spectra import window as spectral_window
from diskfriction.continuation.detection.collisions import certified_tracked
from diskfriction.continuation.detection.detectors import fast
from diskfriction.continuation.detection.labels import continuation_perm
from diskfriction.continuation.detection.samples import Sample
from diskfriction.continuation.spectra.window import SpectralWindow, window_columns
from diskfriction.continuation.detection.verdicts import beyond_band
from diskfriction.models.chain.sweep import SweepParams, sweep
from diskfriction.scenes import Scene
from diskfriction.symbolic import System

SCENES = {"paper": Scene(), "N20-eps1e-4": Scene(N=20, eps=1e-4)}
MATCH = 1e-8
"""Windowed (shift-invert) and full (dense) eigenvalues agree to this fraction of max|lambda|."""

def full_sweep(chain_sweep, name: str, F_from: float = 0.0, F_to: float = 0.12):
    """The full sweep of J (conftest.chain_sweep: once per session)."""
    return chain_sweep(SCENES[name], "J", F_from, F_to)[0]


def windowed_sweep(name: str, lo: float, hi: float, F_from: float = 0.0, F_to: float = 0.12):
    k_n = SCENES[name].k_n
    return sweep(System.from_scene(SCENES[name]), F_from, F_to, "J", SweepParams(window=(lo * k_n, hi * k_n)))


def tracks(value: complex, row: np.ndarray, tol: float) -> set:
    """The full spectrum's columns holding `value` (a conjugate pair's members alike: which
    label takes the upper one at a birth is a convention)."""
    distance = np.abs(value.real - row.real) + np.abs(np.abs(value.imag) - np.abs(row.imag))
    return set(np.flatnonzero(distance <= tol).tolist())


def joined(a: set, b: set, pairs: list) -> bool:
    """Whether a column of `a` reaches one of `b` through the colliding pairs."""
    seen, todo = set(a), list(a)
    while todo:
        i = todo.pop()
        for j in [q for p, q in pairs if p == i] + [p for p, q in pairs if q == i]:
            if j not in seen:
                seen.add(j)
                todo.append(j)
    return bool(seen & b)


def jumps(window, full, rows: np.ndarray) -> list:
    """(column, F_x, F_x', lambda, lambda') for each windowed column and consecutive points of
    `rows` where it lies inside the window whose values are not one eigenvalue of the full
    sweep, nor two that meet at a collision the full detection located between them (there
    the eigenvalues are not smooth and which continues which is not defined)."""
    lo, hi = window.window
    W, Fu, F = window.eigenvalues[rows], full.eigenvalues[rows], window.F_x[rows]
    tol = MATCH * np.abs(Fu).max()
    found = []
    for c in range(W.shape[1]):
        inside = np.flatnonzero((W[:, c].real >= lo) & (W[:, c].real <= hi))
        for r0, r1 in zip(inside, inside[1:]):
            a, b = tracks(W[r0, c], Fu[r0], tol), tracks(W[r1, c], Fu[r1], tol)
            between = [tuple(x.pair) for x in full.collisions if F[r0] <= x.p <= F[r1] or F[r1] <= x.p <= F[r0]]
            if not (a and b and (a & b or joined(a, b, between))):
                found.append((c, F[r0], F[r1], W[r0, c], W[r1, c]))
    return found


@pytest.mark.parametrize("name, lo, hi", [("paper", 0.05, 0.08), ("paper", 0.055, 0.06),
                                          ("N20-eps1e-4", 0.05, 0.08), ("paper", 0.0, 0.02)])
@pytest.mark.slow
def test_windowed_columns_follow_the_full_spectrum(name, lo, hi, chain_sweep):
    """Where a column lies inside the window, from one point to the next it holds one
    eigenvalue of the full sweep (same F_x), or passes through a collision located between
    them; it holds values in the window and its guard bands only; and every eigenvalue of the
    full spectrum in the window is in some column. Before columns were continued across
    entries and exits, at the paper's F_x = 0.0537 -> 0.0557 (window 0.05:0.08) one
    eigenvalue left the k nearest the centre and another joined, and the assignment shifted a
    chain of labels: 0.0695 -> 0.0599, 0.0584 -> 0.0554 inside the window."""
    full, window = full_sweep(chain_sweep, name), windowed_sweep(name, lo, hi)
    assert np.max(np.abs(window.F_x - full.F_x)) <= 1e-12  # the same points
    assert jumps(window, full, np.arange(len(window))) == []
    W, band = window.eigenvalues, SpectralWindow(*window.window)
    assert np.all(band.tracked(W[~np.isnan(W)]))
    tol = MATCH * np.abs(full.eigenvalues).max()
    for r in range(len(full)):
        inside = full.eigenvalues[r][(full.eigenvalues[r].real > band.lo + tol) & (full.eigenvalues[r].real < band.hi - tol)]
        assert all(np.nanmin(np.abs(W[r] - v)) <= tol for v in inside)


def test_a_window_holding_all_but_two_eigenvalues_locates_the_full_sweeps_collisions(chain_sweep):
    """Window 0:0.02 of the paper's scene tracks k = n - 2 = 28 of its 30 eigenvalues, where
    ARPACK's Krylov space may be no smaller than n (it was cut to n - 1, a traceback): the
    collisions it locates are the full sweep's with Re lambda in the window, to 1e-10 in F_x."""
    full, window = full_sweep(chain_sweep, "paper"), windowed_sweep("paper", 0.0, 0.02)
    lo, hi = window.window
    expected = [(c.kind, c.p) for c in full.collisions if lo <= c.eigenvalue <= hi]
    found = [(c.kind, c.p) for c in window.collisions]
    assert len(expected) == 6 and [k for k, _ in found] == [k for k, _ in expected]
    assert np.max(np.abs(np.subtract([p for _, p in found], [p for _, p in expected]))) <= 1e-10


@pytest.mark.slow
def test_windowed_columns_continue_across_the_legs(chain_sweep):
    """Loading to 0.06 and unloading to 0.03: the unloading leg starts with its labels in order
    of value; its columns continue the loading leg's (each moves to the nearest value at the
    first unloading point), and inside the unloading leg they follow the full spectrum."""
    full, window = full_sweep(chain_sweep, "paper", 0.06, 0.03), windowed_sweep("paper", 0.05, 0.08, 0.06, 0.03)
    W = window.eigenvalues
    last = np.flatnonzero(window.leg == 0)[-1]
    both = np.flatnonzero(~np.isnan(W[last]) & ~np.isnan(W[last + 1]))
    assert both.size >= 8
    nearest = np.nanargmin(np.abs(W[last + 1][None, :] - W[last][both][:, None]), axis=1)
    assert nearest.tolist() == both.tolist()
    assert jumps(window, full, np.flatnonzero(window.leg == 1)) == []


def test_full_columns_and_collision_pairs_continue_across_the_legs(chain_sweep):
    """The full spectrum of the same sweep: each column at the first unloading point is the
    nearest to its value at the last loading point (the unloading leg's labels, sorted by
    value at its start, used to jump by up to 14 raw there), and each collision's pair names
    the two columns that meet: at the point nearest it they are each other's nearest."""
    full = full_sweep(chain_sweep, "paper", 0.06, 0.03)
    E, last = full.eigenvalues, np.flatnonzero(full.leg == 0)[-1]
    nearest = np.argmin(np.abs(E[last + 1][None, :] - E[last][:, None]), axis=1)
    assert nearest.tolist() == list(range(E.shape[1]))
    assert len(full.collisions) >= 2
    for c in full.collisions:
        row = E[np.argmin(np.abs(full.F_x - c.p))]
        distance = np.abs(row[:, None] - row[None, :].conj()) + np.diag(np.full(row.size, np.inf))
        i, j = c.pair
        assert np.argmin(distance[i]) == j and np.argmin(distance[j]) == i


def test_a_column_continues_only_where_its_label_is_certified():
    """window_columns: label 1 leaves the band at point 1 and comes back at point 2, certified
    throughout: one column with a gap; at point 3 it is not certified: a new column, and the
    old one ends; label 0 (shown throughout) keeps its column."""
    values = np.array([[1.0, 2.0], [1.1, 9.0], [1.2, 2.2], [1.3, 2.3]], dtype=complex)
    continued = np.array([[False, False], [True, True], [True, True], [True, False]])
    shown = np.array([[True, True], [True, False], [True, True], [True, True]])
    columns = window_columns(values, continued, shown)
    nan = np.nan
    expected = np.array([[1.0, 2.0, nan], [1.1, nan, nan], [1.2, 2.2, nan], [1.3, nan, 2.3]])
    assert np.array_equal(columns, expected, equal_nan=True)


def _window_sample(values: list, excluded: list, p: float) -> Sample:
    values = np.array(values, dtype=complex)
    n = values.size
    return Sample(0.0, np.array([p]), values, np.zeros(n, np.int8), 1e-12, np.array(excluded),
                  tangent=np.array([1.0]), dlam=np.zeros(n, complex), guard=np.zeros(n, bool),
                  gaps=np.ones(n), disc=(0.0, float(np.abs(values).max())))


def test_an_eigenvalue_leaving_the_disc_frees_its_label_and_shifts_no_other():
    """The k = 5 eigenvalues nearest 0: -1.0 (beyond the guard band) moves out of the disc and
    1.02 comes in. The tracked -0.3, 0, 0.3 and the excluded 0.9 keep their labels; the label
    of -1.0 takes 1.02 (a new eigenvalue). On the real line a plain assignment may as well
    shift the chain -1.0 -> -0.3 -> 0 -> 0.3 -> 0.9 -> 1.02 (the same total distance)."""
    a = _window_sample([-1.0, -0.3, 0.0, 0.3, 0.9], [True, False, False, False, True], 0.0)
    b = _window_sample([-0.3, 0.0, 0.3, 0.9, 1.02], [False, False, False, True, True], 0.01)
    assert continuation_perm(a, b).tolist() == [4, 0, 1, 2, 3]


def _located_collisions(monkeypatch, certified: float) -> tuple[list, list]:
    """The paper's scene, window 0.06:0.07 of Re lambda / k_n, scans inline, with CERTIFIED =
    `certified` of a guard band GUARD = 0.25 (with the default 0.15 no collision falls in the
    outer half of the guard band here): (every double eigenvalue the locator found, the sweep's
    collisions)."""
    found = []
    locate = fast.locate

    def counted(scan, idx, i, j, kind):
        collision = locate(scan, idx, i, j, kind)
        if collision is not None:
            found.append(collision.eigenvalue)
        return collision

    monkeypatch.setattr(fast, "locate", counted)
    monkeypatch.setattr(spectral_window, "CERTIFIED", certified)
    monkeypatch.setattr(spectral_window, "GUARD", 0.25)  # the guard band this case was found with
    k_n = SCENES["paper"].k_n
    window = sweep(System.from_scene(SCENES["paper"]), 0.0, 0.12, "J",
                   SweepParams(window=(0.06 * k_n, 0.07 * k_n), workers=0))
    return found, window.collisions


@pytest.mark.slow
def test_collisions_beyond_the_certified_band_are_not_located(monkeypatch):
    """With the whole guard band certified (CERTIFIED = 1) the paper's window
    0.06:0.07 locates a collision beyond the band's inner half, outside W, which is then not
    reported; with the outer half only watched it is not located, and the sweep reports the
    same collisions at the same F_x."""
    k_n = SCENES["paper"].k_n
    band = SpectralWindow(0.06 * k_n, 0.07 * k_n)
    everywhere, before = _located_collisions(monkeypatch, 1.0)
    certified, after = _located_collisions(monkeypatch, 0.5)
    lo, hi = band.lo - 0.5 * band.guard, band.hi + 0.5 * band.guard
    assert any(not lo <= lam <= hi for lam in everywhere)
    assert all(lo <= lam <= hi for lam in certified) and len(certified) < len(everywhere)
    assert len(after) == len(before) >= 2
    assert [(c.kind, c.p) for c in after] == [(c.kind, c.p) for c in before]


def test_labels_beyond_the_certified_band_on_one_side_are_not_certified():
    """beyond_band: labels beyond the band on the same side at both ends only (not one that
    crosses it, comes inside, or is unknown), and only while the cubic Hermite model of Re
    lambda stays beyond it (a label above at both ends whose slopes take it down through the
    band in between is not); certified_tracked: a label beyond it on both sides of an interval
    between samples where it is known is not certified over the step, even with a partial
    sample between that does not know it."""
    band = (0.0, 1.0)
    a = replace(_window_sample([-2.0, 0.5, 2.0, 3.0, 1.5], [False] * 5, 0.0), band=band)
    b = replace(_window_sample([-2.5, 0.6, 2.5, -3.0, 0.9], [False] * 5, 0.1), band=band)
    flat = np.zeros(5, complex)
    assert beyond_band(a, b, flat, flat, 0.25).tolist() == [True, False, True, False, False]
    assert not beyond_band(replace(a, band=None), replace(b, band=None), flat, flat, 0.25).any()
    down, up = flat.copy(), flat.copy()
    down[2], up[2] = -10.0, 10.0  # 2 - 10 t + 11.5 t^2 - t^3: down to -0.26 at t = 0.46
    assert beyond_band(a, b, down, up, 0.25).tolist() == [True, False, False, False, False]
    down[0], up[0] = -1.0, 1.0  # the label below: -2 - t - 0.5 t^2 + t^3, stays below
    assert beyond_band(a, b, down, up, 0.25).tolist() == [True, False, False, False, False]
    assert certified_tracked([a, b]).tolist() == [False, True, False, True, True]
    partial = replace(b, eigvals=np.array([np.nan, 0.6, np.nan, np.nan, 0.9]),
                      known=np.array([False, True, False, False, True]))
    c = replace(a, s=1.0)  # back where a was
    assert certified_tracked([b, partial, c]).tolist() == [False, True, False, True, True]
