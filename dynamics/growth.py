"""The exponential phase of M(t) and its rate, to compare with the spectrum.

A complex pair of M^-1 J with sqrt(lambda) = omega + i sigma makes the displacement grow as
exp(sigma t) times an oscillation of period T = 2 pi / omega, so M ~ |dq|^2 grows at 2 sigma.

Fit. M is cut into consecutive blocks of one period T; each block contributes its maximum
E_k (at time t_k), the envelope, which removes the oscillation (and its zeros, which would spoil
a fit of log M itself). sigma_measured = slope / 2 of the least-squares line through
(t_k, log E_k) over the window below.

Window (the phase where M grows exponentially, and only that):
  start  the first block with E_k >= START_GROWTH * E_0, E_0 the first block's envelope: by then
         the growing solution dominates the start (M is measured from r_i(0), so for a start
         displaced along the mode M ~ (A e^(sigma t) + A)^2 and the slope is low by a factor
         1 - e^(-sigma t); at a growth of 1e3 in M that is 3% at the window's start, decaying);
  end    the last block before the linear regime ends: before the largest displacement of a
         disk centre, max_i |r_i(t) - r_i(0)|, reaches LINEAR_FRACTION times the smallest
         overlap of the equilibrium's active contacts (a contact that opens or changes its
         stiffness appreciably ends linearity), and before the first Coulomb breach at the
         substrate; and below END_FRACTION * max M over the run.
At least MIN_BLOCKS blocks, else no rate is measured (sigma = nan, with the reason).
Without a complex pair T is 2 pi / sqrt(median positive eigenvalue of M^-1 J).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

START_GROWTH = 1e3
LINEAR_FRACTION = 0.1
END_FRACTION = 1e-2
MIN_BLOCKS = 8


@dataclass(frozen=True)
class GrowthFit:
    """sigma [1 / time] (nan if no window) and its standard error; the window [t_start, t_end]
    and the number of blocks in it; period T of the blocks; reason: "ok" or why not."""

    sigma: float
    stderr: float
    t_start: float
    t_end: float
    blocks: int
    period: float
    reason: str

    def as_dict(self) -> dict:
        def num(v):
            return float(v) if np.isfinite(v) else None
        return {"sigma": num(self.sigma), "stderr": num(self.stderr), "t_start": num(self.t_start),
                "t_end": num(self.t_end), "blocks": self.blocks, "period": num(self.period),
                "reason": self.reason}


def oscillation_period(eigenvalues: np.ndarray, omega_pair: float) -> float:
    """2 pi / omega of the growing pair, or of the median positive eigenvalue if none [time]."""
    if omega_pair > 0:
        return 2 * np.pi / omega_pair
    lam = np.real(eigenvalues)
    positive = lam[lam > 1e-9 * np.abs(lam).max()]
    return 2 * np.pi / np.sqrt(np.median(positive)) if positive.size else np.inf


def block_envelope(t: np.ndarray, M: np.ndarray, period: float) -> tuple[np.ndarray, np.ndarray]:
    """(t_k, E_k): time and value of the maximum of M in each block [k T, (k+1) T)."""
    block = np.floor((t - t[0]) / period).astype(np.int64)
    starts = np.flatnonzero(np.r_[True, block[1:] != block[:-1]])
    ends = np.r_[starts[1:], t.size]
    arg = np.array([s + np.argmax(M[s:e]) for s, e in zip(starts, ends)])
    return t[arg], M[arg]


def linear_end(traj) -> float:
    """Time the linear regime ends (module docstring): displacement bound or first breach."""
    active = traj.overlaps0[traj.overlaps0 > 0]
    bound = LINEAR_FRACTION * active.min() if active.size else np.inf
    disp = np.hypot(traj.x - traj.x[0], traj.y - traj.y[0]).max(axis=1)
    over = np.flatnonzero(disp >= bound)
    t_end = traj.t[over[0]] if over.size else np.inf
    breach = traj.breach_t[np.isfinite(traj.breach_t)]
    return min(t_end, breach.min()) if breach.size else t_end


def fit_growth(traj) -> GrowthFit:
    """Fit the exponential phase of traj.M (module docstring)."""
    period = oscillation_period(traj.eigenvalues, traj.omega_predicted)
    nan = float("nan")
    if not np.isfinite(period) or traj.t[-1] < MIN_BLOCKS * period:
        return GrowthFit(nan, nan, nan, nan, 0, period, "run shorter than the fit needs")
    M = traj.M
    tk, Ek = block_envelope(traj.t, M, period)
    grown = np.flatnonzero(Ek >= START_GROWTH * Ek[0])
    if Ek[0] <= 0 or not grown.size:
        return GrowthFit(nan, nan, nan, nan, 0, period, "M never grew by START_GROWTH")
    t_stop = min(linear_end(traj), tk[np.flatnonzero(Ek >= END_FRACTION * M.max())[0]])
    window = np.arange(grown[0], tk.size)
    window = window[tk[window] + period <= t_stop]  # whole blocks inside the linear regime
    if window.size < MIN_BLOCKS:
        return GrowthFit(nan, nan, nan, nan, int(window.size), period,
                         f"fewer than {MIN_BLOCKS} periods between the start of growth and the "
                         f"end of the linear regime (smaller amplitude or longer run)")
    (slope, _), cov = np.polyfit(tk[window], np.log(Ek[window]), 1, cov=True)
    return GrowthFit(slope / 2, float(np.sqrt(cov[0, 0])) / 2, float(tk[window[0]]),
                     float(tk[window[-1]]), int(window.size), period, "ok")
