"""An independent reference for the packings: frictionless Hertz disks in a periodic square box,
every pair checked (O(N^2) plain numpy, minimum image). The tests pass it to
packings.prepare as `pair_forces`; the generated kernels are checked against it.

Raw units (docs/model.md): lengths with the small diameter 1, k_n in force / length^(3/2).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

K_N = 2000.0


@lru_cache(maxsize=8)
def all_pairs(N: int) -> tuple[np.ndarray, np.ndarray]:
    """(i, j), every pair i < j of N disks."""
    return np.triu_indices(N, 1)


def hertz_pair_forces(positions: np.ndarray, radii: np.ndarray, L: float, k_n: float = K_N):
    """(F (N, 2), energy, virial) of Hertz contacts in the periodic box of side L.

    r_ij = r_i - r_j - L round((r_i - r_j) / L) (minimum image), delta = R_i + R_j - |r_ij|;
    where delta > 0: f_ij = k_n delta^(3/2) r_ij / |r_ij| (the force on i from j, on j -f_ij),
    energy = sum (2/5) k_n delta^(5/2), virial = sum r_ij . f_ij = sum k_n delta^(3/2) |r_ij|,
    each contact once [force, energy = force * length, virial = force * length]."""
    i, j = all_pairs(len(radii))
    r_ij = positions[i] - positions[j]
    r_ij -= L * np.round(r_ij / L)
    distance = np.sqrt(np.sum(r_ij * r_ij, axis=1))
    delta = radii[i] + radii[j] - distance
    touching = delta > 0
    i, j, r_ij, distance, delta = (a[touching] for a in (i, j, r_ij, distance, delta))
    f = k_n * delta ** 1.5
    f_ij = (f / distance)[:, None] * r_ij
    N = len(radii)
    F = np.stack([np.bincount(i, f_ij[:, a], N) - np.bincount(j, f_ij[:, a], N)
                  for a in range(2)], axis=1)
    return F, float(np.sum(0.4 * k_n * delta ** 2.5)), float(np.sum(f * distance))
