"""Initial conditions for a run: an equilibrium (q, xi) at F_x plus a perturbation.

Small oscillations about an equilibrium obey M dq'' = -J dq with J = -dF/dq the total stiffness
(history following q, docs/model.md#stability), so the spectrum that governs the dynamics is that of M^-1 J,
whatever matrix a branch was diagonalised with. A complex pair lambda, conj(lambda) with
sqrt(lambda) = omega + i sigma (principal root, sigma = |Im sqrt(lambda)|) gives the solutions
dq = Re(V exp(s t)), s = +-(sigma - i omega): one grows at rate sigma, one decays.

Perturbations (raw units; the history always follows a displacement by the quasistatic rule,
Coulomb cap included, so a displaced state is one the chain can actually reach):
  none              the equilibrium itself, at rest.
  random-velocity   v = a g (x, y), v_theta = a g / R, g ~ N(0, 1) seeded: every mode excited.
  random-position   dq likewise, with v = 0.
  eigenvector       the growing solution of the chosen complex pair of M^-1 J (pair 0 = the
                    largest sigma): dq = Re V, v = Re(s V), s = sigma - i omega, V scaled so that
                    max_i (|V_x,i|^2 + |V_y,i|^2)^(1/2) = a, the largest displacement of a disk
                    centre over one period. Only that pair is excited, so M(t) grows at
                    2 sigma from the start, without a decaying partner.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from diskfriction.continuation.spectra.tracking import DEFAULT_REL_TOL, eigen_status
from diskfriction.symbolic import System

KINDS = ("none", "random-velocity", "random-position", "eigenvector")


@dataclass(frozen=True)
class Perturbation:
    """kind (KINDS), amplitude a [length, or length / time for random-velocity], seed of the
    random kinds, pair: index of the complex pair for "eigenvector" (0 = largest sigma)."""

    kind: str = "none"
    amplitude: float = 0.0
    seed: int = 0
    pair: int = 0

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"perturbation kind {self.kind!r} is not one of {', '.join(KINDS)}")
        if not (np.isfinite(self.amplitude) and self.amplitude >= 0):
            raise ValueError(f"amplitude must be a number >= 0 (got {self.amplitude})")
        if self.pair < 0:
            raise ValueError(f"pair must be >= 0 (got {self.pair})")


@dataclass(frozen=True)
class Spectrum:
    """Eigen-decomposition of M^-1 J at a state. eigenvalues (n,) [1 / time^2], vectors (n, n)
    columns; pairs: indices of the upper (Im > 0) members of the complex pairs, largest sigma
    first (classification of continuation.spectra.tracking, rel_tol DEFAULT_REL_TOL)."""

    eigenvalues: np.ndarray
    vectors: np.ndarray
    pairs: np.ndarray

    @property
    def omega_max(self) -> float:
        """sqrt of the largest |eigenvalue| [1 / time]: the fastest mode."""
        return float(np.sqrt(np.abs(self.eigenvalues).max()))

    def root(self, k: int) -> complex:
        """sqrt(lambda) = omega + i sigma of pair k (principal root, sigma > 0)."""
        return complex(np.sqrt(complex(self.eigenvalues[self.pairs[k]])))

    @property
    def leading_root(self) -> complex:
        """sqrt(lambda) of the pair with the largest sigma, 0 if M^-1 J is all real."""
        return self.root(0) if self.pairs.size else 0j

    @property
    def sigma(self) -> float:
        """Largest growth rate sigma = |Im sqrt(lambda)| over the complex pairs, 0 if none."""
        return abs(self.leading_root.imag)


def growth_rates(eigenvalues: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(upper, sigma): the indices of the upper members (Im > 0) of the complex pairs among
    `eigenvalues` of M^-1 J [1 / time^2] (continuation.spectra.tracking's classification, rel_tol
    DEFAULT_REL_TOL), and their growth rates sigma = |Im sqrt(lambda)| [1 / time]."""
    upper = np.flatnonzero(eigen_status(eigenvalues, DEFAULT_REL_TOL) == 1)
    return upper, np.abs(np.sqrt(eigenvalues[upper].astype(complex)).imag)


def spectrum(system: System, q: np.ndarray, xi: np.ndarray) -> Spectrum:
    """Eigenvalues and eigenvectors of M^-1 J(q, xi)."""
    J = system.jacobian(q, xi)
    lam, vec = np.linalg.eig(system.stability_matrix(J, "M^-1 J"))
    upper, sigma = growth_rates(lam)
    return Spectrum(lam, vec, upper[np.argsort(-sigma, kind="stable")])


def _position_scale(system: System, dq: np.ndarray) -> float:
    """max_i |dr_i| of a displacement (positions only)."""
    N = system.N
    return float(np.hypot(dq[:N], dq[N:2 * N]).max())


def perturb(system: System, q: np.ndarray, xi: np.ndarray, perturbation: Perturbation,
            spec: Spectrum | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, v, xi) of the perturbed start from the equilibrium (q, xi); see the module docstring."""
    p, N, n = perturbation, system.N, system.ndof
    dq, v = np.zeros(n), np.zeros(n)
    if p.kind in ("random-velocity", "random-position"):
        g = np.random.default_rng(p.seed).normal(size=n) * p.amplitude
        g[2 * N:] /= system.scene.R
        (v if p.kind == "random-velocity" else dq)[:] = g
    elif p.kind == "eigenvector":
        spec = spec or spectrum(system, q, xi)
        if p.pair >= spec.pairs.size:
            raise ValueError(f"pair {p.pair} asked for, but M^-1 J has {spec.pairs.size} "
                             f"complex pair(s) here")
        root = spec.root(p.pair)
        s = complex(abs(root.imag), -root.real)  # sigma - i omega: the growing root
        V = spec.vectors[:, spec.pairs[p.pair]]
        V = V * (p.amplitude / _position_scale(system, np.abs(V)))
        dq, v = V.real.copy(), (s * V).real.copy()
    if not dq.any():
        return q.copy(), v, xi.copy()
    q1 = q + dq
    return q1, v, system.history_step(q, q1, xi, cap=True)[0]
