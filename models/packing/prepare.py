"""Frictionless preparation of a packing: N bidisperse disks at random in a periodic
square box, relaxed by FIRE (fire.py) at a packing fraction, or at the packing fraction where
the measured pressure is the target. Friction is switched on afterwards, not here.

Raw units (docs/model.md): the small radius R (0.5: the small diameter is the length unit),
k_n in force / length^(3/2), unit masses (FIRE only needs their ratios); pressure in force /
length (2D), energies in force * length.

The force comes from outside: pair_forces(positions, radii, L) -> (F (N, 2), energy, virial),
the frictionless normal force, always called with positions in [0, L).

Pressure protocol: the random configuration is relaxed at PHI_START, above jamming (relaxing
near phi_J is slow: at N = 256 one run at 0.84 took > 60000 FIRE steps, against ~3000 at 0.88);
phi goes up by PHI_STEP while the pressure is below the target, then down along the jammed
branch by a safeguarded secant on g(phi) = P^(2/3) - P_target^(2/3), linear in phi above
jamming for Hertz contacts (P ~ (phi - phi_J)^(3/2)), until |P / P_target - 1| <=
PRESSURE_RTOL (next_phi). Each step rescales the positions and the box affinely, from the last
configuration above the target (so that the secant walks along one contact network), and
relaxes again.
"""
from __future__ import annotations

import zipfile
from dataclasses import dataclass, fields
from typing import Callable, Optional

import numpy as np
from scipy.spatial import cKDTree

from diskfriction.errors import OneLineError
from diskfriction.files import save_npz
from diskfriction.models.packing.fire import Progress, fire

PairForces = Callable[[np.ndarray, np.ndarray, float], tuple[np.ndarray, float, float]]
"""pair_forces(positions, radii, L) -> (F (N, 2), energy, virial = sum_contacts r_ij . f_ij)."""

PHI_START = 0.88      # above jamming (near 0.84): relaxing there is fast, unlike near phi_J
PHI_STEP = 0.02       # steps of phi while the target is not bracketed
PHI_MAX = 0.95        # no jammed state below this: the preparation fails
PHI_MIN = 0.30        # decompressed this far and still above the target: fails
PRESSURE_RTOL = 1e-3  # |P / P_target - 1| at the end
MAX_RELAXATIONS = 60  # FIRE runs allowed in the pressure search
JAMMED = 1e-2         # P / P_target above which a state counts as jammed for the secant
MAX_STEPS = 500_000   # FIRE steps allowed in one relaxation
DT0_PER_CONTACT_TIME = 0.1  # dt0 / sqrt(m / (k_n R^(1/2))): see first_time_step


class PreparationError(OneLineError, ValueError):
    """The packing cannot be prepared as asked (no jammed state, FIRE did not converge)."""


class PackingFileError(OneLineError):
    """A packing file that cannot be read back: missing, damaged or not a packing."""


@dataclass(frozen=True, eq=False)
class Packing:
    """A relaxed frictionless packing and what it was made from.

    positions (N, 2) in [0, L), radii (N,), L the box side [length]; pressure = virial / (2 L^2)
    [force / length], energy [force * length] and max_force = max_i |F_i| [force] measured at
    the positions; phi = pi sum R_i^2 / L^2; rattlers (N,) bool (function rattlers). Made from:
    seed, R, k_n, size_ratio, fraction_small, target ("pressure" or "phi") at target_value,
    f_tol; steps: FIRE steps over all relaxations, relaxations: FIRE runs (pair_forces was
    called steps + 2 relaxations times)."""
    positions: np.ndarray
    radii: np.ndarray
    L: float
    pressure: float
    energy: float
    max_force: float
    phi: float
    rattlers: np.ndarray
    seed: int
    R: float
    k_n: float
    size_ratio: float
    fraction_small: float
    target: str
    target_value: float
    f_tol: float
    steps: int
    relaxations: int


def bidisperse_radii(N: int, R: float, size_ratio: float = 1.4, fraction_small: float = 0.5,
                     *, rng: np.random.Generator) -> np.ndarray:
    """Radii (N,) [length]: round(N fraction_small) of R, the rest R size_ratio, in an order
    drawn from rng (a permutation)."""
    small = int(round(N * fraction_small))
    return rng.permutation(np.r_[np.full(small, R), np.full(N - small, R * size_ratio)])


def packing_fraction(radii: np.ndarray, L: float) -> float:
    """phi = pi sum R_i^2 / L^2 (dimensionless)."""
    return float(np.pi * np.sum(radii ** 2) / L ** 2)


def box_side(radii: np.ndarray, phi: float) -> float:
    """L = sqrt(pi sum R_i^2 / phi) [length], the box side at packing fraction phi."""
    return float(np.sqrt(np.pi * np.sum(radii ** 2) / phi))


def wrap(positions: np.ndarray, L: float) -> np.ndarray:
    """positions mod L, in [0, L) (a -1e-17 would round to L: it becomes 0) [length]."""
    wrapped = np.mod(positions, L)
    return np.where(wrapped >= L, 0.0, wrapped)


def separations(positions: np.ndarray, L: float, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """r_ij = r_i - r_j - L round((r_i - r_j) / L), the minimum image (len(i), 2) [length]."""
    r_ij = positions[i] - positions[j]
    return r_ij - L * np.round(r_ij / L)


def contacts(positions: np.ndarray, radii: np.ndarray, L: float) -> tuple[np.ndarray, np.ndarray]:
    """(i, j), i < j, lexicographic: the pairs with overlap delta = R_i + R_j - |r_ij| > 0 in
    the periodic box of side L (candidates from a periodic k-d tree, O(N log N))."""
    pairs = cKDTree(wrap(positions, L), boxsize=L).query_pairs(2 * float(np.max(radii)),
                                                             output_type="ndarray")
    i, j = pairs.min(axis=1), pairs.max(axis=1)
    r_ij = separations(positions, L, i, j)
    touching = np.sum(r_ij * r_ij, axis=1) < (radii[i] + radii[j]) ** 2
    order = np.lexsort((j[touching], i[touching]))
    return i[touching][order], j[touching][order]


def mean_overlap(positions: np.ndarray, radii: np.ndarray, L: float) -> float:
    """The mean over contacts of delta_ij / (R_i + R_j) (dimensionless), 0 without contacts."""
    i, j = contacts(positions, radii, L)
    if len(i) == 0:
        return 0.0
    distance = np.sqrt(np.sum(separations(positions, L, i, j) ** 2, axis=1))
    return float(np.mean(1 - distance / (radii[i] + radii[j])))


def rattlers(i: np.ndarray, j: np.ndarray, N: int) -> np.ndarray:
    """(N,) bool: the disks with fewer than d + 1 = 3 contacts, found iteratively: a rattler's
    contacts are taken from its neighbours' counts, which may make them rattlers too, until
    none is added. (i, j): the contacts, each pair once."""
    rattler = np.zeros(N, dtype=bool)
    while True:
        kept = ~rattler[i] & ~rattler[j]
        z = np.bincount(i[kept], minlength=N) + np.bincount(j[kept], minlength=N)
        new = (z < 3) & ~rattler
        if not new.any():
            return rattler
        rattler |= new


def first_time_step(k_n: float, R: float) -> float:
    """FIRE's dt0 = 0.1 sqrt(m / (k_n R^(1/2))) with m = 1 [time]. Two disks at overlap delta
    oscillate at omega^2 = 3 k_n delta^(1/2) / m: at the random start's worst overlaps (delta ~ 2R)
    omega dt0 ~ 0.2, stable; FIRE then grows dt up to 10 dt0 as the overlaps shrink. (0.05 took
    about twice the steps at N = 32, 64, 0.2 no fewer.)"""
    return DT0_PER_CONTACT_TIME / np.sqrt(k_n * np.sqrt(R))


@dataclass(frozen=True, eq=False)
class Relaxed:
    """One FIRE relaxation in the box of side L at packing fraction phi: positions in [0, L),
    pressure = virial / (2 L^2), energy, max_force = max_i |F_i| at them, the FIRE steps it
    took; phi_J = phi (1 - <delta_ij / (R_i + R_j)>_contacts)^2, where an affine decompression
    would open the mean contact: an estimate of jamming (phi without contacts)."""
    positions: np.ndarray
    L: float
    phi: float
    pressure: float
    energy: float
    max_force: float
    steps: int
    phi_J: float


def relax(fractions: np.ndarray, radii: np.ndarray, L: float, pair_forces: PairForces,
          f_tol: float, dt0: float, progress: Optional[Progress]) -> Relaxed:
    """FIRE from positions = fractions L (fractions: (N, 2) in [0, 1)) in the box of side L
    until max_i |F_i| <= f_tol [force]; pair_forces sees the positions wrapped into [0, L).
    The pressure is the 2D virial P = sum_contacts r_ij . f_ij / (2 L^2) [force / length]."""
    result = fire(lambda x: pair_forces(wrap(x, L), radii, L)[:2], fractions * L, dt0, f_tol,
                  MAX_STEPS, progress)
    phi = packing_fraction(radii, L)
    if not result.converged:
        raise PreparationError(f"FIRE did not reach max |F| <= {f_tol:g} in {MAX_STEPS} steps at "
                               f"phi = {phi:.4f} (max |F| = {result.max_force:.3g})")
    positions = wrap(result.x, L)
    _, energy, virial = pair_forces(positions, radii, L)
    pressure = float(virial) / (2 * L * L)
    if progress is not None:
        progress(f"relaxed at phi = {phi:.5f}: P = {pressure:.4g}", None)
    return Relaxed(positions, L, phi, pressure, float(energy), result.max_force,
                   result.steps, phi * (1 - mean_overlap(positions, radii, L)) ** 2)


def next_phi(lo: Optional[Relaxed], hi: Optional[Relaxed], jammed: list[Relaxed],
             target: float) -> float:
    """The next packing fraction of the search, g = P^(2/3) - target^(2/3) < 0 at lo, >= 0 at
    hi. No hi yet: PHI_STEP up. Else, with P^(2/3) linear in phi above jamming: the secant of g
    through the last two jammed runs, or with one, phi_J + (phi - phi_J) (target / P)^(2/3);
    if that leaves the bracket (lo.phi or PHI_MIN, hi.phi): its midpoint, or PHI_STEP down."""
    if hi is None:
        return lo.phi + PHI_STEP
    b = jammed[-1]
    a = jammed[-2] if len(jammed) >= 2 and jammed[-2].pressure != b.pressure else None
    phi = b.phi_J + (b.phi - b.phi_J) * (target / b.pressure) ** (2 / 3) if a is None else \
        b.phi - (b.pressure ** (2 / 3) - target ** (2 / 3)) * (b.phi - a.phi) / \
        (b.pressure ** (2 / 3) - a.pressure ** (2 / 3))
    if (lo.phi if lo else PHI_MIN) < phi < hi.phi:
        return phi
    return (lo.phi + hi.phi) / 2 if lo else hi.phi - PHI_STEP


def pressure_search(relax_at: Callable[[float, np.ndarray], Relaxed], fractions: np.ndarray,
                    target: float) -> list[Relaxed]:
    """The relaxations that bring the pressure to target (module docstring, next_phi), the last
    one within PRESSURE_RTOL. relax_at(phi, fractions) relaxes at packing fraction phi from
    positions fractions L: those of the last run above the target once there is one, else of
    the last run. Jammed: P >= JAMMED target."""
    runs, lo, hi, jammed = [], None, None, []
    phi = PHI_START
    while len(runs) < MAX_RELAXATIONS:
        start = hi or lo
        run = relax_at(phi, start.positions / start.L if start else fractions)
        runs.append(run)
        if abs(run.pressure / target - 1) <= PRESSURE_RTOL:
            return runs
        lo, hi = (run, hi) if run.pressure < target else (lo, run)
        if run.pressure >= JAMMED * target:
            jammed.append(run)
        phi = next_phi(lo, hi, jammed, target)
        if phi > PHI_MAX:
            raise PreparationError(f"no jammed state below phi = {PHI_MAX}: the pressure "
                                   f"is {run.pressure:.3g} < {target:g} at phi = {lo.phi:.3f}")
        if phi < PHI_MIN:
            raise PreparationError(f"the pressure is still {run.pressure:.3g} > {target:g} "
                                   f"at phi = {hi.phi:.3f}")
    raise PreparationError(f"the pressure did not reach {target:g} within {PRESSURE_RTOL:g} in "
                           f"{MAX_RELAXATIONS} relaxations (last P = {runs[-1].pressure:.6g})")


def prepare(N: int, seed: int, R: float, k_n: float, size_ratio: float = 1.4,
            fraction_small: float = 0.5, *, pressure: Optional[float] = None,
            phi: Optional[float] = None, pair_forces: PairForces, f_tol: float,
            progress: Optional[Progress] = None) -> Packing:
    """A frictionless packing of N disks (radii: bidisperse_radii) at a target pressure [force /
    length] or packing fraction phi (exactly one), relaxed by FIRE until max_i |F_i| <= f_tol
    [force]. The start: positions uniform at random (fractions of the box side, drawn from
    np.random.default_rng(seed) after the radii: uncorrelated, as a dilute gas), put in the box
    of side L = box_side(radii, phi) and relaxed once, or with a pressure at PHI_START and
    searched (module docstring). R [length], k_n [force / length^(3/2)] set FIRE's first time
    step (first_time_step); pair_forces gives the force (module docstring).
    f_tol is absolute, not scaled: a contact carries about P <2R> [force], so P is known to about
    f_tol / (P <2R>) relative; keep that well below PRESSURE_RTOL (1e-8 at P = 1e-2: 1e-6)."""
    if (pressure is None) == (phi is None):
        raise PreparationError("prepare needs exactly one of pressure and phi")
    rules = {"N >= 1": N >= 1, "seed >= 0": seed >= 0, "R > 0": R > 0, "k_n > 0": k_n > 0,
             "size_ratio > 0": size_ratio > 0, "0 <= fraction_small <= 1": 0 <= fraction_small <= 1,
             "f_tol > 0": f_tol > 0, "pressure > 0": pressure is None or pressure > 0,
             "0 < phi < 1": phi is None or 0 < phi < 1}
    broken = [rule for rule, holds in rules.items() if not holds]
    if broken:
        raise PreparationError(
            f"prepare needs {', '.join(broken)} (got N = {N}, seed = {seed}, R = {R}, k_n = {k_n}, "
            f"size_ratio = {size_ratio}, fraction_small = {fraction_small}, f_tol = {f_tol}, "
            f"pressure = {pressure}, phi = {phi})")
    rng = np.random.default_rng(seed)
    radii = bidisperse_radii(N, R, size_ratio, fraction_small, rng=rng)
    fractions = rng.random((N, 2))
    dt0 = first_time_step(k_n, R)

    def relax_at(phi_now: float, start: np.ndarray) -> Relaxed:
        return relax(start, radii, box_side(radii, phi_now), pair_forces, f_tol, dt0, progress)

    runs = [relax_at(phi, fractions)] if phi is not None else \
        pressure_search(relax_at, fractions, pressure)
    last = runs[-1]
    rattling = rattlers(*contacts(last.positions, radii, last.L), N)
    return Packing(last.positions, radii, last.L, last.pressure, last.energy, last.max_force,
                   last.phi, rattling,
                   int(seed), float(R), float(k_n), float(size_ratio), float(fraction_small),
                   "pressure" if phi is None else "phi", float(pressure or phi), float(f_tol),
                   sum(run.steps for run in runs), len(runs))


FORMAT = "diskfriction packing 1"
FIELDS = {f.name: {"float": float, "int": int, "str": str}.get(f.type) for f in fields(Packing)}
"""Packing's fields and the Python type of the scalars among them (None: an array)."""


def save_packing(path, packing: Packing, record: Optional[dict] = None) -> None:
    """The packing as an uncompressed .npz, written atomically (files.save_npz): every field
    under its name (scalars as 0-d arrays), format = FORMAT, and the arrays of `record` (what
    the packing was made for: reports/packing_outputs.scene_arrays), a Packing field among
    them taking the packing's value."""
    save_npz(path, **{**(record or {}), "format": np.array(FORMAT),
                      **{name: np.asarray(getattr(packing, name)) for name in FIELDS}})


def load_packing(path) -> Packing:
    """The packing save_packing wrote to path: the same arrays bit for bit, the same scalars.
    A missing, damaged or foreign file raises PackingFileError naming path and the problem."""
    try:
        with np.load(path, allow_pickle=False) as data:
            if "format" not in data.files or str(data["format"]) != FORMAT:
                raise PackingFileError(f"{path}: not a packing file (no format '{FORMAT}')")
            missing = [name for name in FIELDS if name not in data.files]
            if missing:
                raise PackingFileError(f"{path}: packing file without {', '.join(missing)}")
            values = {name: data[name] if kind is None else kind(data[name][()])
                      for name, kind in FIELDS.items()}
    except (OSError, ValueError, TypeError, EOFError, zipfile.BadZipFile) as error:
        raise PackingFileError(f"{path}: cannot read a packing ({error})".replace("\n", " "))
    N = len(values["radii"])
    if values["positions"].shape != (N, 2) or values["rattlers"].shape != (N,):
        raise PackingFileError(f"{path}: packing file with positions {values['positions'].shape}, "
                               f"rattlers {values['rattlers'].shape} for {N} radii")
    return Packing(**values)
