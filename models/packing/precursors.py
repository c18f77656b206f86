"""The plastic events of a shear against their precursors
(docs/packings.md#plastic-events-and-their-precursors):
one row per plastic event and drag eta, what the event was and the last onset of damped
instability before it (models/packing/damped.py; with contact dashpots of the rate eta,
contact_onsets.py: the state's first mode to grow), so that "was this event preceded by a damped
oscillatory instability, how long before, and is the unstable mode the event's displacement?"
is read off a table.

An event's displacement field u is the disks' translations from the last equilibrium before it
(the fold) to the relaxed state after it, the mean translation removed (the network's drift
carries no information). Its size is |u| [length] and its participation ratio

    PR = (sum_i |u_i|^2)^2 / (N sum_i |u_i|^4)     (1 / N for one disk moving, 1 for all alike).

A mode's overlap with u: the mode r is the onset's marginal mode (models/packing/damped.py
DampedHopf.mode: the right eigenvector of the physical M^-1 J at the onset; with dashpots the
null vector of the quadratic pencil there, contact_onsets.mode_translations); its translations,
the mean removed, span with Re r and Im r the plane of displacements the oscillation passes
through, and the overlap is |P u| / |u| (P the projection on that plane), in [0, 1]. A field
drawn at random in the 2 N translations would overlap about sqrt(2 / (2 N)) (random_overlap).
"""
from __future__ import annotations

from typing import Callable, Optional, Sequence

import numpy as np

from diskfriction.continuation.branch import Branch
from diskfriction.continuation.spectra.tracking import DEFAULT_REL_TOL
from diskfriction.models.packing.damped import DampedHopf, damped_hopfs, fastest_damped
from diskfriction.models.packing.network import Network
from diskfriction.models.packing.strain_statistics import strain_statistics

EVENT_COLUMNS = ("event", "gamma", "kind", "fold_lambda", "sigma_xy_before", "drop", "relative_drop",
                 "displacement", "participation", "drag", "eta", "unstable_at_event",
                 "growth_at_event", "onset_gamma", "strain_gap", "onset_frequency", "overlap",
                 "random_overlap", "chance_preceded", "chance_gap")
"""The precursor table's columns, in order (event_rows; None where not known)."""


def translations(q: np.ndarray, N: int) -> np.ndarray:
    """(N, 2): the disks' (x, y) from q = (x_1..x_N, y_1..y_N, theta_1..theta_N)."""
    return np.stack([q[:N], q[N:2 * N]], axis=1)


def displacement_field(q_before: np.ndarray, q_after: np.ndarray, N: int) -> np.ndarray:
    """(N, 2): the translations from q_before to q_after, their mean removed [length]."""
    u = translations(q_after - q_before, N)
    return u - u.mean(axis=0)


def participation_ratio(u: np.ndarray) -> float:
    """(sum |u_i|^2)^2 / (N sum |u_i|^4) of an (N, 2) field: 1 / N for one disk, 1 for all alike."""
    squared = np.sum(u * u, axis=1)
    return float(squared.sum() ** 2 / (u.shape[0] * np.sum(squared ** 2)))


def plane_overlap(u: np.ndarray, mode: np.ndarray) -> float:
    """|P u| / |u|: P the projection on the plane spanned by the translations of Re mode and Im
    mode ((N, 2) complex, their mean removed)."""
    mode = mode - mode.mean(axis=0)
    basis = np.linalg.qr(np.stack([mode.real.ravel(), mode.imag.ravel()], axis=1))[0]
    return float(np.linalg.norm(basis.T @ u.ravel()) / np.linalg.norm(u))


def random_overlap(N: int) -> float:
    """sqrt(2 / (2 N)): the typical overlap of a field drawn at random in 2 N translations with
    a plane."""
    return float(np.sqrt(1.0 / N))


CHANCE_POINTS = 1000
"""The strains, evenly spread over an event's segment, at which chance() asks what an event
there would have been preceded by."""


def chance(onsets: np.ndarray, start: float, end: float, points: int = CHANCE_POINTS
           ) -> tuple[float, Optional[float]]:
    """What "preceded" would be by chance, for an event at a strain drawn evenly from the segment
    [start, end] with the onsets at `onsets` in it: the fraction of the segment's strain that has
    an onset before it, and the median strain gap from the last onset over that strain (None
    without one). An event is preceded more often, or closer, than chance where its onsets
    cluster before it."""
    strains = start + (np.arange(points) + 0.5) * (end - start) / points
    last = np.searchsorted(np.sort(onsets), strains, side="right")
    after = last > 0
    if not after.any():
        return 0.0, None
    gaps = strains[after] - np.sort(onsets)[last[after] - 1]
    return float(after.mean()), float(np.median(gaps))


def fold_eigenvalue(eigenvalues: np.ndarray, rel_tol: float = DEFAULT_REL_TOL) -> Optional[float]:
    """The real eigenvalue of smallest |lambda| but the translations' exact zeros, over max|lambda|
    (a fold: a real eigenvalue through zero, so this is near 0 at the last state before it);
    None without spectra at the states."""
    lam = eigenvalues[np.isfinite(eigenvalues)]
    if not lam.size:
        return None
    scale = np.abs(lam).max()
    real = lam[(np.abs(lam.imag) <= rel_tol * scale) & (lam != 0)].real
    return float(real[np.argmin(np.abs(real))] / scale) if real.size else None


def event_rows(network: Network, mass: np.ndarray, branch: Branch, omega_0: float,
               hopfs: dict[float, Sequence[DampedHopf]],
               growth_at: Optional[Callable[[float, int], float]] = None) -> list[dict]:
    """One row per plastic event of a shear's branch and per drag of `hopfs` (drag in units of
    omega_0 -> its located onsets and ends, models/packing/damped.damped_hopfs at eta = drag
    omega_0, or contact_onsets.contact_hopfs with dashpots of that rate), EVENT_COLUMNS: the
    event (its index, strain, kind, fold_lambda: fold_eigenvalue at the last state before it,
    sigma_xy before and the drop [force / length], the displacement field's size [length] and
    participation ratio); at the drag, the largest damped growth rate at the last state before
    the event [1 / time] and whether it is positive (a mode grows there); the last onset in the
    event's segment before it: its strain, the strain gap to the event, the marginal frequency w
    [1 / time] and the overlap of its mode with the event's displacement (module docstring),
    None without one (the overlap None also where the onset was not refined and has no mode:
    DampedHopf.resolved). growth_at(drag, k): the growth rate at state k [1 / time], nan where
    not known; by default fastest_damped of the state's eigenvalues at the drag eta M (nan
    without spectra at the states: the growth and unstable_at_event None)."""
    N, rows = network.N, []
    spectra = branch.eigenvalues.shape[1] > 0
    if growth_at is None:
        def growth_at(drag: float, k: int) -> float:
            return fastest_damped(branch.eigenvalues[k], drag * omega_0) if spectra else np.nan
    for index, event in enumerate(branch.plastic):
        last = int(np.flatnonzero(branch.segment == index)[-1])
        u = displacement_field(branch.u[last], event.after[0], N)
        common = {"event": index, "gamma": event.gamma, "kind": event.kind,
                  "fold_lambda": fold_eigenvalue(branch.eigenvalues[last]) if spectra else None,
                  "sigma_xy_before": event.stress_before, "drop": event.stress_before - event.stress_after,
                  "relative_drop": (event.stress_before - event.stress_after) / event.stress_before,
                  "displacement": float(np.linalg.norm(u)), "participation": participation_ratio(u),
                  "random_overlap": random_overlap(N)}
        first = int(np.flatnonzero(branch.segment == index)[0])
        for drag, points in hopfs.items():
            growth = float(growth_at(drag, last))
            onsets = [h for h in points if h.kind == "onset" and first <= h.step < last]
            row = {**common, "drag": drag, "eta": drag * omega_0,
                   "unstable_at_event": None if np.isnan(growth) else bool(growth > 0),
                   "growth_at_event": growth if np.isfinite(growth) else None,
                   "onset_gamma": None, "strain_gap": None, "onset_frequency": None, "overlap": None}
            fraction, gap = chance(np.array([h.gamma for h in onsets]), float(branch.p[first]), event.gamma)
            row |= {"chance_preceded": fraction, "chance_gap": gap}
            if onsets:
                onset = onsets[-1]
                row |= {"onset_gamma": onset.gamma, "strain_gap": event.gamma - onset.gamma,
                        "onset_frequency": onset.frequency,
                        "overlap": None if onset.mode is None else plane_overlap(u, onset.mode)}
            rows.append({column: row[column] for column in EVENT_COLUMNS})
    return rows


def drag_study(network: Network, mass: np.ndarray, branch: Branch, omega_0: float,
               drags: Sequence[float], counted_from: float = 0.0):
    """(hopfs, rows, statistics) of a shear with spectra "full" of M^-1 J at the drags [omega_0]:
    per drag its damped Hopf points (damped_hopfs at eta = drag omega_0; those below
    counted_from left out, as the shear leaves out its collisions there), the precursor rows
    (event_rows) and the branch's StrainStatistics at those eta."""
    etas = tuple(drag * omega_0 for drag in drags)
    hopfs = {drag: tuple(h for h in damped_hopfs(network, mass, branch, eta) if h.gamma >= counted_from)
             for drag, eta in zip(drags, etas)}
    return (hopfs, event_rows(network, mass, branch, omega_0, hopfs),
            strain_statistics(branch, etas, counted_from=counted_from))
