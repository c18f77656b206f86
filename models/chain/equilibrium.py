"""The equilibrium at a load: the point of the branch from rest at exactly F_x, or why none is.

Every command that starts from an equilibrium (simulate, verify, ensembles, the report) gets it
here. Because the tangential history depends on the path, "the equilibrium at F_x" means the
one reached quasistatically from rest (F_x = 0, xi = 0) by loading: sweep.sweep from 0
to F_x, which ends exactly on F_x when the branch reaches it. When it does not, the branch has
ended short of F_x, and NoEquilibrium says where and why, in one line, from the branch itself:
the sweep's status, and the contacts of its last point that are open (delta <= 0) or at their
Coulomb limit (|xi| = t*, System.coulomb_limit, where the smoothed law has no tangential
stiffness left; when too many hold there the branch folds over), e.g.

    no equilibrium beyond F_x = 5.09975 (asked for 20): corrector failed (residual 1.6e-11);
    there the substrate contacts of disks 1..7, 9 are at their Coulomb limit (mu = 10), pair
    10-1 is open
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from diskfriction.continuation.stepping.arclength import ContinuationError
from diskfriction.continuation.detection.collisions import DetectionParams
from diskfriction.models.chain.equilibria import EquilibriumError
from diskfriction.continuation.branch import Branch
from diskfriction.models.chain.sweep import SweepParams, sweep
from diskfriction.errors import OneLineError
from diskfriction.symbolic import System

AT_LIMIT = 1e-9
"""A contact is at its Coulomb limit when |xi| >= (1 - AT_LIMIT) t*. The cap sets |xi| = t*
exactly, so only rounding separates a capped contact from t*; a sticking one stays far below
(max |xi| / t* = 0.092 on the whole paper branch)."""

REACHED = 1e-12
"""The sweep ends on its target; the last point must be within this relative distance of F_x."""


class NoEquilibrium(OneLineError):
    """The branch from rest ends before F_x; str() is the one line saying where and why.
    F_end: the last load reached [force] (0 if the branch could not start); F_x: the load asked."""

    def __init__(self, line: str, F_end: float, F_x: float) -> None:
        super().__init__(line)
        self.F_end, self.F_x = F_end, F_x


@dataclass(frozen=True)
class Equilibrium:
    """The state on the branch from rest at F_x [force]: positions q (docs/model.md#history layout), the
    committed history xi [length], residual max|F(q, xi; F_x)| [force]."""

    F_x: float
    q: np.ndarray
    xi: np.ndarray
    residual: float


def equilibrium_at(system: System, F_x: float) -> Equilibrium:
    """The equilibrium on the branch from rest at exactly F_x >= 0 (F_x = 0: the analytic rest
    state); raises NoEquilibrium when the branch ends before F_x, ValueError for F_x < 0."""
    if not np.isfinite(F_x) or F_x < 0:
        raise ValueError(f"F_x must be a finite number >= 0 (got {F_x})")
    if F_x == 0:
        q, xi = system.rest_state()
        return Equilibrium(0.0, q, xi, 0.0)
    try:
        no_spectra = DetectionParams(enabled=False, spectra=False)  # the equilibria alone
        branch = sweep(system, 0.0, F_x, None, SweepParams(detection=no_spectra))
    except (EquilibriumError, ContinuationError) as error:
        raise NoEquilibrium(f"no equilibrium beyond F_x = 0 (asked for {F_x:g}): the branch from "
                            f"rest cannot start: {error}", 0.0, F_x) from None
    check_reached(system, branch, F_x)
    return Equilibrium(float(branch.F_x[-1]), branch.q[-1], branch.xi[-1], float(branch.residual[-1]))


def check_reached(system: System, branch: Branch, F_x: float) -> None:
    """Raise NoEquilibrium (where the branch ended, why, and its contacts there) unless the
    branch's last point is F_x, reached (to REACHED * F_x)."""
    F_end = float(branch.F_x[-1])
    if branch.status.reached and abs(F_end - F_x) <= REACHED * F_x:
        return
    raise NoEquilibrium(f"no equilibrium beyond F_x = {F_end:.6g} (asked for {F_x:g}): "
                        f"{branch.status.sentence(len(branch))}; there "
                        f"{contact_states(system, branch.q[-1], branch.xi[-1])}", F_end, F_x)


def disk_list(disks: list[int]) -> str:
    """Increasing disk numbers, runs of three or more shortened: [1, 2, 3, 5, 6] -> "1..3, 5, 6"."""
    runs, start = [], None
    for k, d in enumerate(disks):
        start = d if start is None else start
        if k + 1 == len(disks) or disks[k + 1] != d + 1:
            runs.append(f"{start}..{d}" if d - start >= 2 else ", ".join(map(str, range(start, d + 1))))
            start = None
    return ", ".join(runs)


def _phrase(count: int, singular: str, plural: str, names: str, state: str) -> str:
    """"pair 9-10 is open" / "pairs 9-10, 10-1 are open"."""
    return f"{singular if count == 1 else plural} {names} {'is' if count == 1 else 'are'} {state}"


def contact_states(system: System, q: np.ndarray, xi: np.ndarray) -> str:
    """Which contacts are at their Coulomb limit or open at (q, xi), as words: pair k joins
    disks k and k+1 (pair N: disks N and 1), the substrate contact of disk i is named by i."""
    s, N = system.scene, system.N
    delta = system.overlaps(q)
    t_star = system.coulomb_limit(delta)
    at_limit = (delta > 0) & (t_star > 0) & (np.abs(xi) >= (1 - AT_LIMIT) * t_star)
    pairs = lambda where: [f"{k + 1}-{(k + 1) % N + 1}" for k in np.flatnonzero(where)]
    disks = lambda where: [int(k) + 1 for k in np.flatnonzero(where)]
    limit = f"at the Coulomb limit (mu = {s.mu:g})"
    walls, pair_limit = disks(at_limit[N:]), pairs(at_limit[:N])
    open_pairs, lifted = pairs(delta[:N] <= 0), disks(delta[N:] <= 0)
    parts = [_phrase(len(walls), "the substrate contact of disk", "the substrate contacts of disks",
                     disk_list(walls), limit) if walls else "",
             _phrase(len(pair_limit), "pair", "pairs", ", ".join(pair_limit), limit) if pair_limit else "",
             _phrase(len(open_pairs), "pair", "pairs", ", ".join(open_pairs), "open") if open_pairs else "",
             _phrase(len(lifted), "disk", "disks", disk_list(lifted), "off the substrate") if lifted else ""]
    return ", ".join(p for p in parts if p) or "no contact is open or at its Coulomb limit"
