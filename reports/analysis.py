"""Readings of cached results against the paper's claims (docs/model.md#targets).

Pure functions of the computations' result dicts (raw units in, paper units out where said);
no physics is computed here beyond counting and comparing.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from diskfriction.continuation.spectra.tracking import Kind, eigen_status

# The paper's numbers (docs/model.md#targets), paper units.
PAPER_COMPLEX_LOADS = (0.03, 0.04)
PAPER_REAL_LOAD = 0.062
PAPER_SECOND_PAIR_BY = 0.083
PAPER_IM = {0.083: 0.00024, 0.087: 0.00077, 0.090: 0.001}  # Im lambda of J / k_n
PAPER_V1 = {0.083: (0.0014, 0.00013), 0.087: (0.0022, 0.00015), 0.090: (0.0028, 0.00008)}
PAPER_V2 = 0.075  # 2R / tau
PAPER_OMEGA = 0.235  # 1 / tau
PAPER_WAVELENGTH = 2.0  # 2R
PAPER_V1_OVER_GROWTH = (4.3, 1.5)
PAPER_VCM = (-1.3e-5, 4.5e-4)  # intercept [2R / tau], slope [2R / tau per force]
PAPER_M_SATURATION = 1e-5  # M at F_x = 0.03, 0.04, (2R)^2
FACTOR = 2.0  # "within a factor 2" for the Im lambda claims


def max_imag(eigenvalues: np.ndarray) -> np.ndarray:
    """Largest Im lambda per row (0 where all real) [unit of the eigenvalues]; a float for one
    spectrum (1-D input)."""
    status = eigen_status_rows(eigenvalues)
    im = np.where(status == 1, np.atleast_2d(eigenvalues).imag, 0.0).max(axis=-1)
    return float(im[0]) if np.ndim(eigenvalues) == 1 else im


def eigen_status_rows(eigenvalues: np.ndarray) -> np.ndarray:
    """continuation.spectra.tracking.eigen_status of every row (+1 upper member of a pair, -1, 0 real),
    over the row's finite entries: a nan entry (a windowed branch's eigenvalue outside the
    window and its guard bands) is 0 and does not enter the threshold."""
    eigenvalues = np.atleast_2d(eigenvalues)
    status = np.zeros(eigenvalues.shape, dtype=np.int8)
    for row, values in zip(status, eigenvalues):
        known = np.isfinite(values)
        row[known] = eigen_status(values[known])
    return status


def births_of_pairs_at(branch: dict, F: float) -> list[float]:
    """For each complex pair present at the last branch point <= F (requested leg), the F_x
    at which it was born: following its tracked eigenvalue column back to where it was last
    real, then taking the located birth in that interval (the sampled point if none)."""
    rows = np.flatnonzero((branch["leg"] == 1) & (branch["F_x"] <= F + 1e-15))
    if not rows.size:
        return []
    status = eigen_status_rows(branch["eigenvalues"][rows])
    last = len(rows) - 1
    births = []
    for col in np.flatnonzero(status[last] == 1):
        k = last
        while k > 0 and status[k - 1, col] != 0:
            k -= 1
        lo = branch["F_x"][rows[k - 1]] if k > 0 else -np.inf
        hi = branch["F_x"][rows[k]]
        located = [p for p, kind in zip(branch["collision_F_x"], branch["collision_kind"])
                   if kind == Kind.BIRTH and lo <= p <= hi]
        births.append(float(located[-1]) if located else float(hi))
    return births


@dataclass(frozen=True)
class Claim:
    """One of the paper's Fig. 2 claims: what it says, our value, and whether it holds."""

    name: str
    paper: str
    ours: str
    holds: bool | None  # None: could not be evaluated


def _at(spectra: dict, F: float) -> int | None:
    idx = np.flatnonzero(np.isclose(spectra["loads"], F, rtol=0, atol=1e-12))
    return int(idx[0]) if idx.size and spectra["n_complex"][idx[0]] >= 0 else None


def fig2_claims(branch: dict | None, spectra: dict | None, eig_unit: float) -> list[Claim]:
    """The paper's Fig. 2 claims (docs/model.md#targets) read on one branch and its spectra at the loads:
    complex at 0.03 and 0.04, all real at 0.062, a pair at 0.083 born after the first window
    (after 0.04), Im lambda at 0.083/0.087/0.090 within a factor FACTOR of the paper's."""
    claims = []

    def spectrum_claim(F, want_complex):
        i = _at(spectra, F) if spectra else None
        if i is None:
            return Claim(f"{'complex' if want_complex else 'all real'} at {F:g}",
                         "complex" if want_complex else "all real", "n/a", None)
        n = int(spectra["n_complex"][i])
        im = max_imag(spectra["eigenvalues"][i]) / eig_unit
        ours = f"{n} pair{'s' if n != 1 else ''}" + (f", max Im {im:.2g}" if n else "")
        return Claim(f"{'complex' if want_complex else 'all real'} at {F:g}",
                     "complex" if want_complex else "all real", ours, (n > 0) == want_complex)

    for F in PAPER_COMPLEX_LOADS:
        claims.append(spectrum_claim(F, True))
    claims.append(spectrum_claim(PAPER_REAL_LOAD, False))
    if branch is None:
        claims.append(Claim("second pair born before 0.083", "yes", "n/a", None))
    else:
        births = [b for b in births_of_pairs_at(branch, PAPER_SECOND_PAIR_BY)
                  if b > max(PAPER_COMPLEX_LOADS)]
        ours = f"born at {min(births):.5f}" if births else "none"
        claims.append(Claim(f"second pair born before {PAPER_SECOND_PAIR_BY:g}", "yes", ours,
                            bool(births)))
    for F, value in PAPER_IM.items():
        i = _at(spectra, F) if spectra else None
        if i is None:
            claims.append(Claim(f"Im at {F:g} within x{FACTOR:g}", f"{value:g}", "n/a", None))
            continue
        im = max_imag(spectra["eigenvalues"][i]) / eig_unit
        ok = im > 0 and 1 / FACTOR <= im / value <= FACTOR
        claims.append(Claim(f"Im at {F:g} within x{FACTOR:g}", f"{value:g}",
                            f"{im:.2g} (x{im / value:.2f})" if im > 0 else "0 (all real)", ok))
    return claims


def mark(holds: bool | None) -> str:
    return {True: "yes", False: "**no**", None: "n/a"}[holds]


def movement(paper: float, base: dict | None, variant: dict | None) -> str:
    """Whether `variant` lies closer to `paper` than `base` does: "toward", "away", "no change"
    when the two differ by no more than their combined standard errors, "n/a" when either is
    missing. base, variant: Estimate dicts (value, error, n) in the paper's units."""
    if not base or not variant or base["value"] is None or variant["value"] is None:
        return "n/a"
    noise = np.hypot(*(e["error"] if e["error"] is not None else 0.0 for e in (base, variant)))
    if abs(variant["value"] - base["value"]) <= noise:
        return "no change"
    closer = abs(variant["value"] - paper) < abs(base["value"] - paper)
    return "toward" if closer else "away"
