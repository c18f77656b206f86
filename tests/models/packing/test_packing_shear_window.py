"""A shear tracking a spectral window: the full spectrum's collisions in it, a window that
crowds widened (along the run or at its first point) with the same collisions, a commit that
leaves the matrix the same keeping its spectrum, and the condition numbers' columns."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from invariants import unaccounted_pair_changes
from sheared_packing import SCENE

from diskfriction.models.packing.shear import ShearParams, shear


WINDOW = (0.0, 50.0)


@pytest.fixture(scope="module")
def windowed(packing):
    return shear(SCENE, packing, ShearParams(workers=0), window=WINDOW)


def test_a_spectral_window_finds_the_full_spectrums_collisions_in_it(branch, windowed):
    """Shear tracking only Re lambda in [0, 50] (sparse shift-invert, its k sized at the start):
    the same collisions as the dense spectra's with their double eigenvalue in the window, each
    at the same strain within 1e-9; every change of the window's complex pairs is one of them."""
    window = WINDOW
    inside = sorted(c.p for c in branch.collisions if window[0] <= c.eigenvalue <= window[1])
    assert windowed.status.reached and len(inside) >= 4
    assert len(windowed.collisions) == len(inside)
    assert np.abs(np.array(sorted(c.p for c in windowed.collisions)) - inside).max() <= 1e-9
    kinds = [(c.p, c.kind) for c in windowed.collisions]
    assert unaccounted_pair_changes(windowed.gamma, windowed.n_complex, kinds) == []
    assert windowed.window == window and windowed.eigenvalues.shape[1] < 3 * SCENE.N


@pytest.mark.slow
def test_a_window_that_crowds_is_widened_and_finds_the_same_collisions(packing, monkeypatch):
    """A window [0, 40] sized with k = the eigenvalues within reach + 1 crowds as the shear
    softens the packing: the run is not lost (256 disks lost 205 s so), the window is sized
    anew, wider, at the last certified state and the shear goes on; the collisions equal a
    generous window's within 1e-9, and each strain is recorded once. The crowding comes before
    the collisions here: the steps after the restart differ, and the history makes the branch
    depend on its steps (measured 1.2e-10; the chain's 5.9e-10, tests/continuation/detection/test_detection.py)."""
    from diskfriction.models.packing import shear as shearing

    window = (0.0, 40.0)
    generous = shear(SCENE, packing, ShearParams(workers=0), window=window)
    monkeypatch.setattr(shearing, "WINDOW_MARGIN", 1.0)  # the shear's window's margins
    monkeypatch.setattr(shearing, "WINDOW_EXTRA", 1)
    tight = shear(SCENE, packing, ShearParams(workers=0), window=window)
    assert generous.widenings == 0 and tight.widenings >= 1
    assert tight.status.reached and np.all(np.diff(tight.gamma) > 0)
    assert len(tight.collisions) == len(generous.collisions) >= 4
    assert np.abs(np.array([c.p for c in tight.collisions])
                  - [c.p for c in generous.collisions]).max() <= 1e-9
    kinds = [(c.p, c.kind) for c in tight.collisions]
    assert unaccounted_pair_changes(tight.gamma, tight.n_complex, kinds) == []


def test_a_window_that_crowds_at_its_first_point_is_widened_there(packing, windowed, monkeypatch):
    """A window sized with k = the eigenvalues within its reach crowds at once, at the first
    point of the run (as 256 disks' window did at the start of a segment after a plastic event
    at gamma = 0.0102, a pair with |Im| = 12.7 in its band, where the exception lost 334 s of
    shear): it is sized anew, wider, there and the shear goes on; the same collisions as a
    generous window within 1e-12."""
    from diskfriction.continuation.spectra import window as spectral_window

    sized, decompose = spectral_window.sized, spectral_window.window_eigensystem
    points, crowded_at = [], []

    def watched(A, window, vectors, deflated=None):
        try:
            return decompose(A, window, vectors, deflated)
        except spectral_window.WindowCrowded:
            crowded_at.append(len(points))
            raise

    def too_tight(w, problem, u, p):  # at the start; widened with the window's own margins
        return w if w.k else replace(w, k=sized(w, problem.stability_structure(u, p).shifted(), 1.0, 1).k - 1)

    monkeypatch.setattr(spectral_window.SpectralWindow, "prepared", too_tight)
    monkeypatch.setattr(spectral_window, "window_eigensystem", watched)
    tight = shear(SCENE, packing, ShearParams(workers=0), points.append, window=WINDOW)
    assert crowded_at[0] == 0 and tight.widenings >= 1 and tight.status.reached
    assert len(tight.collisions) == len(windowed.collisions) >= 4
    assert np.abs(np.array([c.p for c in tight.collisions])
                  - [c.p for c in windowed.collisions]).max() <= 1e-12


@pytest.mark.slow
def test_a_commit_that_leaves_the_matrix_the_same_keeps_the_spectrum(packing, windowed, monkeypatch):
    """Commits where loose disks gave way or histories were capped change the state but not
    A_red: the re-solve from the committed q (PackingEquilibria.resolve_start) takes no update,
    and the end sample's spectrum is kept at the new point (arclength._moved) instead of a
    second decomposition of the same matrix. With that second decomposition forced, the branch
    is the same point for point and the collisions within 1e-12 in strain."""
    from diskfriction.continuation.stepping import arclength

    kept, updates, same_matrix = [], {}, arclength.same_matrix
    real_newton = arclength.factored_fixed_p

    def counting_newton(*args, **kwargs):
        result, near = real_newton(*args, **kwargs)
        updates["last"] = result.iterations
        return result, near

    def counting_same(A, B):
        same = same_matrix(A, B)
        if same:
            kept.append(updates["last"])
        return same

    monkeypatch.setattr(arclength, "factored_fixed_p", counting_newton)
    monkeypatch.setattr(arclength, "same_matrix", counting_same)
    counted = shear(SCENE, packing, ShearParams(workers=0), window=WINDOW)
    assert len(kept) >= 5 and set(kept) == {0}
    monkeypatch.setattr(arclength, "same_matrix", lambda A, B: False)
    again = shear(SCENE, packing, ShearParams(workers=0), window=WINDOW)
    for run in (counted, again):
        assert np.array_equal(run.gamma, windowed.gamma) and np.array_equal(run.q, windowed.q)
    assert len(again.collisions) == len(windowed.collisions) >= 4
    assert np.abs(np.array([c.p for c in again.collisions])
                  - [c.p for c in windowed.collisions]).max() <= 1e-12


def test_the_condition_numbers_follow_the_eigenvalues_columns(branch, windowed):
    """branch.condition has the eigenvalues' shape: nan exactly at the translations' and loose
    disks' zeros (no vectors), at least 1 elsewhere (|l| |r| >= |l^H r|); with a window, nan
    exactly where the window's columns are."""
    zero = branch.eigenvalues == 0
    assert branch.condition.shape == branch.eigenvalues.shape
    assert np.isnan(branch.condition[zero]).all() and (branch.condition[~zero] >= 1 - 1e-12).all()
    assert np.array_equal(np.isnan(windowed.condition), np.isnan(windowed.eigenvalues))
