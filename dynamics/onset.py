"""Onset of sliding of each disk, from the recorded positions.

What moves the chain. Past the instability the chain leaves its equilibrium by rolling as much
as by slipping: a disk rolling on the substrate does not charge its substrate history (docs/model.md#contacts),
so a disk can travel far with its substrate contact never capped, while its pair contacts slip
or open. Substrate slip alone therefore misses the motion the paper calls sliding; the first
Coulomb breach at the substrate (recorded separately, per step, by the stepper) is a different
event, usually later for most disks.

Definition. Let X_i(t) = <x_i>_T(t) - x_i(0) be the forward displacement of disk i averaged over
a trailing window of one period T of the oscillation (the growing pair's 2 pi / omega), which
removes the oscillation about the equilibrium and keeps the drift. Disk i has slid if its run
ends with X_i >= END_FACTOR * threshold; its onset of sliding is then the start of the final
excursion: the last time X_i crossed `threshold` upward, after which it never fell back below
it. onset_x is x_i at that time.

The threshold defaults to 1e-3 (raw length, 1e-3 disk diameters), the order of the substrate
overlap delta_w = 1.36e-3 of the paper's scene: a displacement of the size of the contact
itself, far above the oscillation amplitudes of the linear phase and below the saturated
amplitudes of runs that do not slide (M ~ 1e-5, rms displacement ~ 3e-3, whose window mean
returns to zero). Lower thresholds resolve the backward-running front earlier in its rise;
the onset times shift together, not the front's order.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

END_FACTOR = 10.0


@dataclass(frozen=True)
class OnsetParams:
    """threshold [length]: the averaged forward displacement that marks sliding (module doc)."""

    threshold: float = 1e-3

    def __post_init__(self):
        if not self.threshold > 0:
            raise ValueError(f"onset threshold must be > 0 (got {self.threshold})")


def trailing_mean(t: np.ndarray, a: np.ndarray, window: float) -> np.ndarray:
    """Mean of a (f, ...) over the frames in (t - window, t] (the first frames average what
    exists), by cumulative sums; exact for any frame spacing."""
    c = np.concatenate([np.zeros((1,) + a.shape[1:]), np.cumsum(a, axis=0)])
    start = np.searchsorted(t, t - window, side="right")
    count = (np.arange(t.size) + 1 - start).reshape((-1,) + (1,) * (a.ndim - 1))
    return (c[1:] - c[start]) / count


def sliding_onset(t: np.ndarray, x: np.ndarray, period: float, params: OnsetParams
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(onset_t, onset_x) per disk from frames t (f,) and x (f, N); nan where no sliding."""
    X = trailing_mean(t, x, period) - x[0]
    N = x.shape[1]
    onset_t, onset_x = np.full(N, np.nan), np.full(N, np.nan)
    for i in range(N):
        if X[-1, i] < END_FACTOR * params.threshold:
            continue
        below = np.flatnonzero(X[:, i] < params.threshold)
        k = below[-1] + 1 if below.size else 0
        onset_t[i], onset_x[i] = t[k], x[k, i]
    return onset_t, onset_x
