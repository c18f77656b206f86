"""A packing scene as LAMMPS input: its prepared packing sheared by damped molecular dynamics.

The quasistatic branch (models/packing/shear.py) follows the packing's equilibria in the strain
gamma. LAMMPS has no such solver; its nearest counterpart is a slow, damped shear: the same disks
(positions, radii, the box side L) in a periodic 2D box tilted at a constant rate,

    fix deform xy erate R remap v:   tilt xy = gamma L,  gamma = R t,

so that the image of a disk shifted by one box in y is shifted by gamma L in x, the
Lees-Edwards image of docs/packings.md. The disks start at rest in the flow (v_x = R (y - L/2),
v_y = 0, omega = 0), every tangential history zero, as the branch starts at gamma = 0.

Contacts. LAMMPS's `pair_style granular` writes the Hertz and Mindlin forces with the contact
radius a = sqrt(R_eff delta), R_eff = R_i R_j / (R_i + R_j) of the pair:

    F_n = k a delta,    F_t = -k_t' a xi,    |F_t| <= mu F_n (the history rescaled to the cap).

The packing's laws (docs/packings.md) have ONE k_n for every pair, F_n = k_n delta^(3/2) and the
linear Mindlin F_t = -k_t delta^(1/2) xi, so each pair of radii needs its own coefficients,

    hertz k = k_n / sqrt(R_eff),    mindlin k_t' = k_t / sqrt(R_eff),

written per pair of atom types (one type per radius: a bidisperse packing has two), every
damping coefficient 0 (`damping viscoelastic` with 0: the model has no damping). A scene
without friction (mu = 0 or the tangential law "none") gets `tangential linear_nohistory 0 0`.

The tangential law. LAMMPS has the linear Mindlin law with a sharp Coulomb cap only. A scene
with the smoothed law ("mindlin-smooth", docs/model.md, the packing's default) is written with
the linear one, and the deck's header and `export` say so (law_note): with the same history the
smoothed force is larger by the factor 1 + u - u^2 (u = |xi| / t*, at most 1.25 at u = 1/2) and
reaches mu F_n with zero slope, so the deck's contacts are tangentially softer while they stick
and slide at the same mu F_n. A scene with tangential = "mindlin-linear" is the like-for-like
comparison.

Dissipation. The branch has none; its damped relaxation (models/packing/plastic.py) drags every
disk with F_d = -eta M q', eta = damping omega_0 (PackingScene.omega_0), translation and
rotation. The deck drags the same way, but relative to the flow: F_x = -eta m_i (v_x - R
(y - L/2)), F_y = -eta m_i v_y (fix addforce with atom-style variables) and T = -eta I_i omega
(fix viscous/sphere, per type), so that a homogeneous shear at rate R feels no drag. (A drag to
rest in the lab frame, fix viscous, would push every layer back with a body force eta rho R y:
a stress gradient across the box that grows as R L^2.) The shear then differs from the branch by
rate effects that vanish with R (the disks lag behind the equilibria they follow, and a plastic
event relaxes over a time of order 1 / eta while the strain moves on by R / eta), by the sharp
cap where the scene's law is smoothed, and by LAMMPS's conventions: lever arm R_i - delta/2 in
the torques and the tangential velocity, the history rotated into the current tangent and
incremented at the end of a step (docs/physics.md, Conventions): O(delta / R) in the forces.

Integration: fix nve/sphere disc (I = m_i R_i^2 / 2; plain nve/sphere for c = 2/5), fix
enforce2d, dt = DT_FRACTION 2 / omega_max with omega_max = OMEGA_MAX_OVER_OMEGA_0 omega_0
(models/packing/cost.py). The masses are the scene's m_i = m R_i^2 / R^2.

Output: STRESS_FILE, one row every `every` steps (SAMPLES rows over the run), each the mean over
that interval of LAMMPS's pressure tensor without its kinetic part, sampled every SAMPLE_EVERY
steps, written in our sign and units: sigma_ab = -P_ab (virial part), LAMMPS's P_ab = (1 / A)
sum r_ij,a f_ij,b over the contacts, A = L^2 the box's area, which is Network.stress's
sigma_ab = -(1 / L^2) sum r_ij,a f_ij,b [force / length]. LAMMPS keeps one off-diagonal
component, P_xy = (1 / A) sum x_ij f_ij,y: sigma_xy. Every number is printed with 17 significant
digits. The run ends at the scene's gamma_range[1] (a deck variable).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

from diskfriction.errors import OneLineError
from diskfriction.files import save_text
from diskfriction.peers.lammps_deck import DATA_FILE, INPUT_FILE, INTEGRATORS, Contact, number
from diskfriction.scenes.packing import PackingScene

STRESS_FILE = "stress.txt"
STRESS_COLUMNS = ("step", "gamma", "sigma_xx", "sigma_yy", "sigma_xy")
"""The columns of STRESS_FILE: the step at the end of each interval, and the means over it of
gamma and of the contact stress [force / length] in Network.stress's sign."""
DT_FRACTION = 0.1
"""The deck's time step as a fraction of velocity Verlet's stability limit 2 / omega_max."""
SAMPLES = 1000
"""Rows of STRESS_FILE over a run (one per `every` steps)."""
SAMPLE_EVERY = 10
"""Steps between the samples of the stress that one row averages."""
SKIN_PER_R = 0.5
"""Neighbour skin [R, the small radius]: lists are rebuilt when a disk has moved a quarter of
the small radius."""
DEFAULT_RATE = 1e-5
"""The deck's strain rate R [1 / time] unless given."""
MAX_STEPS = 2**31 - 1
"""LAMMPS's `run N` takes N below 2^31."""


class Unrepresentable(OneLineError):
    """The scene has physics the deck cannot express; str() names the scene file and why."""

    exit_code = 2


def check_representable(scene: PackingScene) -> None:
    """Raise Unrepresentable where LAMMPS's granular package cannot reproduce `scene`'s contact
    laws or integrate its disks (the smoothed tangential law is written linear: law_note)."""
    why = None
    if scene.effects.normal != "hertz":
        why = (f'normal = "{scene.effects.normal}": the deck writes LAMMPS\'s hertz normal model '
               f'only (normal = "hertz")')
    elif scene.inertia not in INTEGRATORS:
        why = (f"disks.inertia = {scene.inertia:g}: LAMMPS integrates rotating disks with "
               f"I = c m R^2 for c = 1/2 (nve/sphere disc) or 2/5 (nve/sphere) only")
    if why:
        raise Unrepresentable(f"{scene.source}: LAMMPS cannot represent this scene: {why}")


def law_note(scene: PackingScene) -> Optional[str]:
    """What the deck changes in the scene's contact law, one sentence, or None."""
    if scene.resolved_effects.pair_law != "mindlin-smooth":
        return None
    return ('the scene\'s tangential law "mindlin-smooth" (smoothed Coulomb, docs/model.md) has no '
            'LAMMPS counterpart: the deck writes the linear Mindlin law with a sharp cap '
            '(tangential = "mindlin-linear"), whose force at the same history is smaller by the '
            'factor 1 / (1 + u - u^2) (u = |xi| / t*, down to 0.8 at u = 1/2): tangentially softer '
            'contacts while they stick, the same mu F_n when they slide')


def drag_rate(scene: PackingScene, damping: float) -> float:
    """eta = damping omega_0 [1 / time] (models/packing/plastic.drag_rate's rate for `damping`)."""
    return damping * scene.omega_0


def time_step(scene: PackingScene) -> float:
    """DT_FRACTION 2 / omega_max, omega_max = OMEGA_MAX_OVER_OMEGA_0 omega_0 [time]."""
    from diskfriction.models.packing.cost import OMEGA_MAX_OVER_OMEGA_0

    return DT_FRACTION * 2.0 / (OMEGA_MAX_OVER_OMEGA_0 * scene.omega_0)


def run_steps(strain: float, rate: float, dt: float) -> int:
    """The deck's steps over `strain`: ceil(strain / (rate dt)), as LAMMPS computes them."""
    return math.ceil(strain / (rate * dt))


@dataclass(frozen=True)
class ShearDeck:
    """The two files (their text) and the deck's defaults: rate R [1 / time], damping (eta in
    units of omega_0) and eta [1 / time], dt [time], gamma_end, steps; types: the radius of
    each atom type [length]; note: law_note's sentence or None."""

    data: str
    inputs: str
    rate: float
    damping: float
    eta: float
    dt: float
    gamma_end: float
    steps: int
    types: tuple[float, ...]
    note: Optional[str]

    def save(self, out: Path) -> list[Path]:
        """OUT/scene.data and OUT/in.scene, written atomically; their paths."""
        paths = [Path(out) / DATA_FILE, Path(out) / INPUT_FILE]
        for path, text in zip(paths, (self.data, self.inputs)):
            save_text(path, text)
        return paths


def radius_types(radii: np.ndarray) -> tuple[np.ndarray, tuple[float, ...]]:
    """(the atom type of each disk, 1-based, the smallest radius type 1; the radius of each type)."""
    sizes, types = np.unique(np.asarray(radii, dtype=float), return_inverse=True)
    return types + 1, tuple(float(r) for r in sizes)


def wrapped(positions: np.ndarray, L: float, gamma: float) -> tuple[np.ndarray, np.ndarray]:
    """Positions (N, 2) mapped into the box tilted by gamma (tilt gamma L), and the image flags
    (N, 2) of the Lees-Edwards shifts that took them there: x = x_w + ix L + iy gamma L,
    y = y_w + iy L."""
    x, y = np.asarray(positions, dtype=float).T
    iy = np.floor(y / L)
    y_w = y - iy * L
    x_s = x - iy * gamma * L
    ix = np.floor((x_s - gamma * y_w) / L)
    return np.column_stack([x_s - ix * L, y_w]), np.column_stack([ix, iy]).astype(int)


def data_file(scene: PackingScene, positions: np.ndarray, radii: np.ndarray, L: float,
              rate: float, gamma: float = 0.0) -> str:
    """The LAMMPS data file (atom_style sphere): the disks at `positions` (N, 2) in the square
    periodic box [0, L)^2 tilted by gamma (xy = gamma L), each disk's type its radius's
    (radius_types), moving with the flow v_x = rate (y - L/2) [length / time], v_y = omega = 0.
    Masses are set by the deck (the density column is a placeholder)."""
    N = radii.size
    types, _ = radius_types(radii)
    inside, image = wrapped(positions, L, gamma)
    z = float(radii.max())
    lines = [f"LAMMPS data file: diskfriction packing scene {scene.name!r}, {N} disks (raw units, "
             f"docs/packings.md)", "", f"{N} atoms", f"{int(types.max())} atom types", "",
             f"0 {number(L)} xlo xhi", f"0 {number(L)} ylo yhi", f"{number(-z)} {number(z)} zlo zhi",
             f"{number(gamma * L)} 0 0 xy xz yz", "", "Atoms # sphere", ""]
    for i in range(N):
        lines.append(f"{i + 1} {types[i]} {number(2 * radii[i])} 1 {number(inside[i, 0])} "
                     f"{number(inside[i, 1])} 0 {image[i, 0]} {image[i, 1]} 0")
    lines += ["", "Velocities", ""]
    for i in range(N):
        lines.append(f"{i + 1} {number(rate * (inside[i, 1] - L / 2))} 0 0 0 0 0")
    return "\n".join(lines) + "\n"


def input_deck(scene: PackingScene, sizes: tuple[float, ...], L: float, rate: float, eta: float,
               dt: float, gamma_end: float, version: str, note: Optional[str]) -> str:
    """The input deck (module docstring). Variables rate, eta, dt, gamma_end take these values
    unless given with `lmp -var NAME VALUE`; the run's steps follow from them."""
    c = scene.inertia
    integrator = INTEGRATORS[c]
    masses = [scene.m * (r / scene.R) ** 2 for r in sizes]
    pairs = [(a, b) for a in range(len(sizes)) for b in range(a, len(sizes))]
    law = ("no tangential force" if scene.resolved_effects.pair_law == "none" else
           "the linear Mindlin law with a sharp Coulomb cap"
           + (", NOT the scene's smoothed law" if note else ""))
    lines = [
        f"# LAMMPS input deck of the diskfriction packing scene {scene.name!r} ({scene.source}), "
        f"diskfriction {version}:",
        f"# its prepared packing (N = {scene.N}, pressure {scene.pressure:g}, "
        f"seed {scene.seed}) sheared by damped MD, gamma = rate t, to gamma_end.",
        f"# Contacts: Hertz and {law} (peers/packing_deck.py).",
    ]
    if note is not None:
        lines.append("# NOTE: " + note + ".")
    lines += [
        "# Units: the scene's raw units (docs/packings.md) in LAMMPS's units lj.",
        "# Conventions: LAMMPS's own (lever arm R_i - delta/2, end-of-step history increment): "
        "O(delta/R) from the branch's.",
        "# Output: stress.txt, columns step, gamma, sigma_xx, sigma_yy, sigma_xy: means over each "
        "row's interval,",
        "# sigma_ab = -P_ab (LAMMPS's pressure without its kinetic part) = -(1/L^2) sum r_ij,a "
        "f_ij,b [force / length],",
        "# diskfriction's Network.stress sign: compression negative, sigma_xy > 0 resists "
        "positive shear.",
        f"# Run: lmp -in {INPUT_FILE} [-var rate R] [-var eta ETA] [-var dt DT] "
        f"[-var gamma_end G] [-var samples K]",
        "",
        f"variable rate index {number(rate)}     # strain rate R [1 / time]: gamma = R t",
        f"variable eta index {number(eta)}     # drag rate eta = damping omega_0 [1 / time]",
        f"variable dt index {number(dt)}     # time step [time]",
        f"variable gamma_end index {number(gamma_end)}     # the strain the run ends at",
        f"variable samples index {SAMPLES}     # rows of stress.txt",
        "variable steps equal ceil((v_gamma_end-xy/ly)/(v_rate*v_dt))   # from the box's tilt as read",
        f"variable nrepeat equal ternary(v_steps>={SAMPLE_EVERY}*v_samples,floor(v_steps/({SAMPLE_EVERY}*v_samples)),1)",
        f"variable every equal {SAMPLE_EVERY}*v_nrepeat",
        "",
        "units lj",
        "dimension 2",
        "atom_style sphere",
        "boundary p p p",
        "comm_modify vel yes                 # granular contacts need the velocities of ghost disks",
        f"read_data {DATA_FILE}",
    ]
    for t, (r, m_t) in enumerate(zip(sizes, masses), start=1):
        lines.append(f"set type {t} mass {number(m_t)}   # radius {number(r)}: m_i = m R_i^2 / R^2")
    lines += ["", "# Per pair of radii: R_eff = R_i R_j / (R_i + R_j), hertz k = k_n / sqrt(R_eff), "
                  "mindlin k_t' = k_t / sqrt(R_eff),",
              "# so that F_n = k sqrt(R_eff delta) delta = k_n delta^(3/2) and F_t = -k_t' sqrt(R_eff "
              "delta) xi = -k_t delta^(1/2) xi;",
              f"# k_n = {number(scene.k_n)}, k_t = {number(scene.k_t)}, mu = {number(scene.mu)}; "
              "every damping coefficient 0.",
              "pair_style granular"]
    for a, b in pairs:
        R_eff = sizes[a] * sizes[b] / (sizes[a] + sizes[b])
        coefficients = Contact.of(scene, R_eff, scene.resolved_effects.pair_law != "none")
        lines.append(f"pair_coeff {a + 1} {b + 1} {coefficients.model()}   # R_eff = "
                     f"{number(coefficients.R_eff)}")
    spin = [eta * c * m_t * r**2 for r, m_t in zip(sizes, masses)]
    scale = " ".join(f"scale {t} {number(s / spin[0])}" for t, s in enumerate(spin[1:], start=2))
    lines += [
        "",
        f"neighbor {number(SKIN_PER_R * min(sizes))} bin",
        "neigh_modify delay 0 every 1 check yes",
        "timestep ${dt}",
        "",
        "# Shear: the box tilts at the strain rate; a disk crossing y = 0 or L has its v_x shifted "
        "by -+ rate L.",
        "fix shear all deform 1 xy erate ${rate} remap v flip no   # gamma = xy / L throughout",
        f"fix integrate all {integrator}   # velocity Verlet; I = c m_i R_i^2 with c = {c:g}",
        "# Drag relative to the flow v_x = rate (y - L/2): F = -eta m_i (v - v_flow), "
        "T = -eta I_i omega.",
        f"variable y_flow equal {number(L / 2)}",
        "variable drag_x atom -v_eta*mass*(vx-v_rate*(y-v_y_flow))",
        "variable drag_y atom -v_eta*mass*vy",
        "fix drag all addforce v_drag_x v_drag_y 0.0",
        f"fix spin_drag all viscous/sphere $(v_eta*{number(spin[0] / eta)}) {scale}".rstrip()
        + "   # eta I_i, I_i = c m_i R_i^2",
        "fix plane all enforce2d",
        "",
        "compute contact_stress all pressure NULL virial",
        "variable gamma equal xy/ly",
        "variable sigma_xx equal -c_contact_stress[1]",
        "variable sigma_yy equal -c_contact_stress[2]",
        "variable sigma_xy equal -c_contact_stress[4]",
        f"fix stress all ave/time {SAMPLE_EVERY} ${{nrepeat}} ${{every}} v_gamma v_sigma_xx "
        f"v_sigma_yy v_sigma_xy file {STRESS_FILE} format \" %.17g\"",
        "thermo_style custom step time v_gamma v_sigma_xy ke",
        "thermo_modify norm no",
        "thermo $(v_every*ceil(v_samples/20))",
        "run ${steps}",
    ]
    return "\n".join(lines) + "\n"


def check_run(scene: PackingScene, rate: float, gamma_end: Optional[float] = None) -> None:
    """Raise TooManySteps (one line, exit 2) where the run to gamma_end (default: the scene's
    gamma_range[1]) at `rate` takes more time steps than LAMMPS's `run` takes (MAX_STEPS)."""
    gamma_end = scene.gamma_range[1] if gamma_end is None else gamma_end
    dt = time_step(scene)
    steps = run_steps(gamma_end, rate, dt)
    if steps > MAX_STEPS:
        raise TooManySteps(f"--rate: the run to gamma = {gamma_end:g} takes {steps:.3g} time steps "
                           f"of dt = {dt:.4g} ({DT_FRACTION:g} of the stability limit), more than "
                           f"the {MAX_STEPS} LAMMPS runs at once; the slowest rate it takes is "
                           f"{gamma_end / (MAX_STEPS * dt):.3g} (got {rate!r})")


class TooManySteps(OneLineError):
    """A rate too slow for one LAMMPS run; str() names --rate and its value."""

    exit_code = 2


def shear_deck(scene: PackingScene, packing, rate: float, damping: Optional[float] = None,
               gamma_end: Optional[float] = None, gamma: float = 0.0) -> ShearDeck:
    """The data file and input deck shearing `packing` (models/packing/prepare.Packing: its
    positions (N, 2), radii (N,) and box side L) at `rate` [1 / time] with the drag damping
    omega_0 (default: the scene's damping) to gamma_end (default: the scene's gamma_range[1]),
    starting from the box tilted by `gamma` (the positions as they are there). Raises
    Unrepresentable (check_representable)."""
    import diskfriction

    check_representable(scene)
    damping = scene.damping if damping is None else damping
    gamma_end = scene.gamma_range[1] if gamma_end is None else gamma_end
    eta, dt = drag_rate(scene, damping), time_step(scene)
    positions, radii, L = packing.positions, packing.radii, packing.L
    _, sizes = radius_types(radii)
    note = law_note(scene)
    return ShearDeck(data_file(scene, positions, radii, L, rate, gamma),
                     input_deck(scene, sizes, L, rate, eta, dt, gamma_end, diskfriction.__version__,
                                note),
                     rate, damping, eta, dt, gamma_end,
                     run_steps(gamma_end - gamma, rate, dt), sizes, note)


def summary(deck: ShearDeck, paths: list[Path]) -> list[str]:
    """What `export lammps` prints for a packing: the run, the drag, what the deck changes in
    the scene's law, the output, the files and how to run them."""
    run = (f"deck: the prepared packing sheared at rate {deck.rate:g} to "
           f"gamma = {deck.gamma_end:g}: {deck.steps} steps of dt = {deck.dt:.6g} (t = "
           f"{deck.gamma_end / deck.rate:.6g}); drag {deck.damping:g} omega_0 = {deck.eta:.6g} "
           f"relative to the flow")
    lines = [run]
    if deck.note is not None:
        lines.append(f"note: {deck.note}")
    lines += ["approximates the quasistatic branch (bifurcate) up to rate effects, the drag and "
              "LAMMPS's O(delta/R) conventions (docs/lammps.md, Packings)",
              f"LAMMPS writes {STRESS_FILE}: {', '.join(STRESS_COLUMNS)} ([force / length], "
              f"bifurcate's sign: sigma_ab = -P_ab without the kinetic part)",
              f"wrote {', '.join(str(p) for p in paths)}; run: cd {paths[0].parent} && lmp -in "
              f"{paths[1].name} [-var rate R] [-var gamma_end G]"]
    return lines


@dataclass(frozen=True)
class StressCurve:
    """LAMMPS's stress along its shear (STRESS_FILE): step, gamma, sigma_xx, sigma_yy, sigma_xy,
    each (k,), [force / length] in Network.stress's sign."""

    step: np.ndarray
    gamma: np.ndarray
    sigma_xx: np.ndarray
    sigma_yy: np.ndarray
    sigma_xy: np.ndarray


class NoStress(OneLineError):
    """STRESS_FILE is missing or holds no row."""


def read_stress(path: Path) -> StressCurve:
    """The rows of a STRESS_FILE (fix ave/time: comment lines start with #)."""
    path = Path(path)
    if not path.exists():
        raise NoStress(f"LAMMPS wrote no {path}")
    rows = np.loadtxt(path, comments="#", ndmin=2)
    if rows.shape[0] == 0 or rows.shape[1] != len(STRESS_COLUMNS):
        raise NoStress(f"{path} holds no rows of {', '.join(STRESS_COLUMNS)}")
    return StressCurve(rows[:, 0], *rows[:, 1:].T)
