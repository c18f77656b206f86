"""The modes of the damped linearization M q'' + eta M q' + J q = 0: a viscous drag -eta M q' on
every degree of freedom (the packing's damped relaxation applies it, at eta = damping omega_0).

With M^-1 J r = lambda r, q = r e^(s t) solves it where

    s^2 + eta s + lambda = 0,    s = (-eta +- sqrt(eta^2 - 4 lambda)) / 2,

so every eigenvalue lambda of M^-1 J gives two exponents s [1 / time] and the damped problem's
spectrum is known from the undamped one without another eigendecomposition. At eta = 0 they are
s = +-sqrt(-lambda): a complex pair lambda = a +- i b grows at |Im sqrt(lambda)|, the growth rate
of the undamped analysis. A mode is damped-unstable where Re s > 0. For lambda = a + i b with
a > 0 that holds exactly while eta < |b| / sqrt(a) (on the boundary s = i w: a = w^2 and
eta w = -b); a real lambda < 0 (a static instability) grows at any damping, a real lambda >= 0
never does. critical_damping is therefore the smallest drag that removes every oscillatory
instability, max |b| / sqrt(a) over the complex eigenvalues.
"""
from __future__ import annotations

import numpy as np


def damped_exponents(eigenvalues: np.ndarray, eta: float) -> np.ndarray:
    """(n, 2) complex: the two roots s of s^2 + eta s + lambda = 0 for each eigenvalue lambda of
    M^-1 J [1 / time^2], eta >= 0 [1 / time]; the root with the larger real part first."""
    lam = np.asarray(eigenvalues, dtype=complex)
    root = np.sqrt(eta * eta - 4.0 * lam)  # principal branch: Re root >= 0
    return np.stack([0.5 * (-eta + root), 0.5 * (-eta - root)], axis=-1)


def damped_growth_rates(eigenvalues: np.ndarray, eta: float) -> np.ndarray:
    """(n,): max Re s of each eigenvalue's two exponents [1 / time] (damped_exponents); positive
    for a damped-unstable mode. At eta = 0 it is computed as the undamped analysis computes its
    growth rates, |Im sqrt(lambda)| (= Re sqrt(-lambda)), so that the two agree bit for bit."""
    if eta == 0.0:
        return np.abs(np.sqrt(np.asarray(eigenvalues, dtype=complex)).imag)
    return damped_exponents(eigenvalues, eta)[..., 0].real


def critical_damping(eigenvalues: np.ndarray, rel_tol: float = 1e-9) -> float:
    """The drag eta [1 / time] above which no complex eigenvalue of M^-1 J gives a growing mode:
    max |Im lambda| / sqrt(Re lambda) over the complex ones (|Im| > rel_tol max|lambda|), 0
    without any; inf where a complex one has Re lambda <= 0 (it grows at any drag)."""
    lam = np.asarray(eigenvalues, dtype=complex)
    scale = float(np.abs(lam).max(initial=0.0))
    pairs = lam[np.abs(lam.imag) > rel_tol * scale]
    if not pairs.size:
        return 0.0
    if (pairs.real <= 0.0).any():
        return float("inf")
    return float(np.max(np.abs(pairs.imag) / np.sqrt(pairs.real)))
