"""Rough wall time of a disk sweep 0 .. 0.12, for the estimate long commands print first.

Calibrated on the sweeps of N = 10 .. 3000 on the project's 2-core machine (2026-11-24, 81ecb24
and 8ecca05; docs/notes/chain-performance.md, "Against N"; docs/notes/maps-cost.md, "The
estimate printed first"): with full spectra (eps > 0) the paper's diagram took 0.22 s at N = 10
and time grew as N^2.1; at eps = 0 only the disks the load reached take spectra, 2.8 s at
N = 100 growing as N^0.8. A sweep's step is span / 60 whatever the span, so the span does not
enter. Good to a factor of about 2 on those sweeps: enough to tell seconds from days. Full
spectra have been faster since (N = 400 in 74-83 s on 2026-11-29, b7fb09a, where the rule says
510 s): at large N the estimate errs high.
"""
from __future__ import annotations

DENSE_SECONDS_N10 = 0.22
DENSE_EXPONENT = 2.1
SPARSE_SECONDS_N100 = 2.8
SPARSE_EXPONENT = 0.8


def sweep_seconds(N: int, dense: bool) -> float:
    """Estimated wall time of a sweep with collision detection on N disks [s]; dense: full
    spectra at every point (eps > 0, no window), else only the reached disks' (eps = 0)."""
    if dense:
        return DENSE_SECONDS_N10 * (N / 10) ** DENSE_EXPONENT
    return max(DENSE_SECONDS_N10, SPARSE_SECONDS_N100 * (N / 100) ** SPARSE_EXPONENT)
