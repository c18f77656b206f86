"""A scene as LAMMPS input: a data file and an input deck that reproduce it.

LAMMPS's GRANULAR package (`pair_style granular` between disks, `fix wall/gran granular` for
the substrate) writes the Hertz and Mindlin forces with the contact radius a = sqrt(R_eff delta),
R_eff = R_i R_j / (R_i + R_j): R/2 for two disks, R for the flat wall,

    F_n = k a delta,    F_t = -k_t' a xi,    |F_t| <= mu F_n (the history rescaled to the cap).

docs/model.md's F_n = k_n delta^(3/2) and linear Mindlin F_t = -k_t delta^(1/2) xi (the
"mindlin-linear" effect; LAMMPS has no smoothed law) are these with

    hertz k = k_n / sqrt(R_eff),    tangential mindlin k_t' = k_t / sqrt(R_eff),

and zero damping (`damping viscoelastic`, every damping coefficient 0: the model has none). A
contact kind without friction gets `tangential linear_nohistory 0 0` (no tangential force).
The rest of the scene: `units lj` with the scene's raw units, `dimension 2`, `atom_style
sphere`, `boundary p f p` (x periodic with ring length L), `fix addforce` for F_y on every disk
and F_x on disk 1, `fix nve/sphere disc` (I = m R^2 / 2, c = 1/2; plain `nve/sphere` for c = 2/5)
or `fix nve` without rotation (omega stays 0), `fix enforce2d`. Every number is printed with
17 significant digits, so LAMMPS reads back the same doubles.

What LAMMPS cannot represent is refused (Unrepresentable, one line): the smoothed Mindlin law,
an inertia c other than 1/2 or 2/5 of rotating disks, and N = 2 (docs/model.md's two-disk ring has
two contacts, left and right; LAMMPS's minimum image sees one). LAMMPS integrates with its own
conventions, which a scene can ask of ours too ([effects] conventions = "lammps",
docs/physics.md); the deck says which ones the scene uses.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from diskfriction.errors import OneLineError
from diskfriction.files import save_text
from diskfriction.scenes import Scene
from diskfriction.symbolic import System

DATA_FILE = "scene.data"
INPUT_FILE = "in.scene"
DUMP_FILE = "dump.disks"
DUMP_COLUMNS = ("id", "xu", "yu", "vx", "vy", "omegaz", "fx", "fy", "tqz", "f_omega_mean")
"""Columns of the dump, one row per disk sorted by id; f_omega_mean is the mean of omega_z
over the `every` steps ending at the dump (peers/lammps_run.py rebuilds theta from it)."""
INTEGRATORS = {0.5: "nve/sphere disc", 0.4: "nve/sphere"}
"""LAMMPS's sphere integrators by c in I = c m R^2: the only two moments of inertia it knows."""
STARTS = ("rest", "branch")
SKIN_PER_R = 0.5
"""Neighbour skin [R]: lists are rebuilt when a disk has moved a quarter radius."""
Y_BOX = (-1.0, 5.0)
"""The box in y [R]: the substrate is the wall y = 0; a disk leaving the box is lost (LAMMPS
stops), which no run of a chain pressed onto the substrate comes near."""


def number(x: float) -> str:
    """A double with 17 significant digits: LAMMPS reads back exactly the same double."""
    return f"{float(x):.17g}"


class Unrepresentable(OneLineError):
    """The scene has physics LAMMPS cannot express; str() names the scene file and why."""

    exit_code = 2


def check_representable(scene: Scene) -> None:
    """Raise Unrepresentable if LAMMPS's granular package cannot reproduce `scene`."""
    effects = scene.resolved_effects
    why = None
    if effects.normal != "hertz":
        why = (f'normal = "{effects.normal}": the deck writes LAMMPS\'s hertz normal model only '
               f'(normal = "hertz")')
    elif "mindlin-smooth" in (effects.pair_law, effects.wall_law):
        why = ('tangential = "mindlin-smooth" (paper eq. 5) has no LAMMPS counterpart; LAMMPS\'s '
               'mindlin is the linear law with a hard cap, tangential = "mindlin-linear"')
    elif effects.rotation and scene.inertia not in INTEGRATORS:
        why = (f"disks.inertia = {scene.inertia:g}: LAMMPS integrates rotating spheres with "
               f"I = c m R^2 for c = 1/2 (nve/sphere disc) or 2/5 (nve/sphere) only")
    elif scene.N == 2:
        why = ("disks.N = 2: the two-disk ring has two contacts (left and right side), LAMMPS's "
               "minimum image sees one")
    if why:
        raise Unrepresentable(f"{scene.source}: LAMMPS cannot represent this scene: {why}")


@dataclass(frozen=True)
class Contact:
    """LAMMPS coefficients of one contact kind (raw units): R_eff [length], hertz k and
    mindlin k_t' [force / length^2], mu, and whether it carries a tangential force."""

    R_eff: float
    k: float
    k_t: float
    mu: float
    friction: bool

    @classmethod
    def of(cls, scene: Scene, R_eff: float, friction: bool) -> Contact:
        """k = k_n / sqrt(R_eff), k_t' = k_t / sqrt(R_eff) (module docstring); `scene` a chain's or
        a packing's (peers/packing_deck.py: one Contact per pair of radii)."""
        root = math.sqrt(R_eff)
        return cls(R_eff, scene.k_n / root, scene.k_t / root, scene.mu, friction)

    def model(self) -> str:
        """The granular model arguments of pair_coeff and fix wall/gran."""
        tangential = (f"tangential mindlin {number(self.k_t)} 0 {number(self.mu)}" if self.friction
                      else "tangential linear_nohistory 0 0")
        return f"hertz {number(self.k)} 0 {tangential} damping viscoelastic"

    def comments(self, what: str, kind: str) -> list[str]:
        """Comment lines naming each correspondence."""
        lines = [f"# {what}: R_eff = {kind} = {number(self.R_eff)}; docs/model.md F_n = k_n delta^(3/2) is "
                 f"LAMMPS's k sqrt(R_eff delta) delta with hertz k = k_n / sqrt(R_eff)"]
        if self.friction:
            lines.append("#   linear Mindlin F_t = -k_t delta^(1/2) xi is LAMMPS's -k_t' sqrt(R_eff "
                         "delta) xi with k_t' = k_t / sqrt(R_eff); mu as in the scene; |F_t| <= mu F_n")
        else:
            lines.append("#   no friction at this contact kind: no tangential force")
        lines.append("#   every damping coefficient 0 (the model has no damping)")
        return lines


@dataclass(frozen=True)
class Start:
    """The state handed to LAMMPS: positions q (docs/model.md layout), load F_x [force], kind
    ("rest" or "branch") and a sentence saying what it is. Velocities and histories are 0."""

    kind: str
    F_x: float
    q: np.ndarray
    note: str


def start_state(system: System, F_x: float, kind: str) -> Start:
    """"rest": the F_x = 0 equilibrium (docs/model.md#history), the load F_x switched on at t = 0.
    "branch": the equilibrium on the branch from rest at F_x (models.chain.equilibrium.equilibrium_at,
    which raises NoEquilibrium past the branch's end) with zero histories: LAMMPS cannot be
    given tangential histories, so unless F_x = 0 it is not an equilibrium there."""
    if kind not in STARTS:
        raise ValueError(f"start must be one of {', '.join(STARTS)} (got {kind!r})")
    if kind == "rest" or F_x == 0:
        q, _ = system.rest_state()
        return Start("rest", F_x, q, f"the rest state (F_x = 0 equilibrium, docs/model.md), at rest, "
                                    f"with the load F_x = {F_x:g} switched on at t = 0")
    from diskfriction.models.chain.equilibrium import equilibrium_at

    eq = equilibrium_at(system, F_x)
    return Start("branch", F_x, eq.q, f"the equilibrium on the branch from rest at F_x = {F_x:g}, "
                                      f"at rest, with zero tangential histories (LAMMPS cannot be "
                                      f"given histories): not an equilibrium of the model")


@dataclass(frozen=True)
class Deck:
    """The two files (their text) and the defaults of the deck's variables: dt [time], steps,
    every (steps between dumps; 0 when the deck records nothing)."""

    data: str
    inputs: str
    dt: float
    steps: int
    every: int

    def save(self, out: Path) -> list[Path]:
        """OUT/scene.data and OUT/in.scene, written atomically; their paths."""
        paths = [Path(out) / DATA_FILE, Path(out) / INPUT_FILE]
        for path, text in zip(paths, (self.data, self.inputs)):
            save_text(path, text)
        return paths


def data_file(scene: Scene, q: np.ndarray) -> str:
    """The LAMMPS data file (atom_style sphere): N disks of diameter 2R at q, at rest. A disk
    outside [0, L) in x is written inside with its image flag."""
    N, R = scene.N, scene.R
    density = 3.0 * scene.m / (4.0 * math.pi * R**3)
    image = np.floor(q[:N] / scene.L).astype(int)
    lines = [f"LAMMPS data file: diskfriction scene {scene.name!r}, {N} disks (raw units, docs/model.md)",
             "", f"{N} atoms", "1 atom types", "",
             f"0 {number(scene.L)} xlo xhi", f"{number(Y_BOX[0] * R)} {number(Y_BOX[1] * R)} ylo yhi",
             f"{number(-R)} {number(R)} zlo zhi", "", "Atoms # sphere", ""]
    for i in range(N):
        x = q[i] - image[i] * scene.L if image[i] else q[i]
        lines.append(f"{i + 1} 1 {number(2 * R)} {number(density)} {number(x)} {number(q[N + i])} 0 "
                     f"{image[i]} 0 0")
    lines += ["", "Velocities", ""] + [f"{i + 1} 0 0 0 0 0 0" for i in range(N)]
    return "\n".join(lines) + "\n"


def _conventions_note(scene: Scene) -> str:
    if scene.effects.conventions == "lammps":
        return ("# The scene's [effects] conventions = \"lammps\": diskfriction integrates it with LAMMPS's "
                "conventions\n# (lever arm R - delta/2, end-of-step history increment, whole "
                "increment on first contact).")
    return ("# The scene uses conventions = \"model\" (docs/model.md); LAMMPS integrates with its own: "
            "lever arm R - delta/2,\n# end-of-step history increment, whole increment on first "
            "contact. Expect O(delta) differences\n# (docs/physics.md, Conventions); "
            "conventions = \"lammps\" removes them.")


def _recording(rotation: bool) -> list[str]:
    """Dump commands: every disk every ${every} steps, and the mean of omega_z over the steps
    since the last dump (for theta)."""
    lines = ["", "# Output: every ${every} steps, one row per disk (sorted by id), 17 digits. LAMMPS "
             "stores no angle:", "# theta is rebuilt from omega_z and tq_z (docs/lammps.md), with "
             "f_omega_mean the mean omega_z over the", "# ${every} steps ending at each dump."]
    if rotation:
        lines += ["compute omega_z all property/atom omegaz",
                  "fix omega_mean all ave/atom 1 ${every} ${every} c_omega_z"]
        columns = DUMP_COLUMNS
    else:
        columns = DUMP_COLUMNS[:-1]
    lines += [f"dump disks all custom ${{every}} {DUMP_FILE} {' '.join(columns)}",
              "dump_modify disks sort id format float %.17g"]
    return lines


def input_deck(scene: Scene, start: Start, dt: float, steps: int, every: int, version: str) -> str:
    """The input deck (module docstring): scene, loads, integrator, dt, and the dump when
    every > 0. Variables dt, steps, every take these values unless given with -var."""
    effects = scene.resolved_effects
    R = scene.R
    pair = Contact.of(scene, R / 2, effects.pair_law != "none")
    wall = Contact.of(scene, R, effects.wall_law != "none")
    integrator = INTEGRATORS[scene.inertia] if effects.rotation else "nve"
    inertia = (f"I = c m R^2 with c = {scene.inertia:g}" if effects.rotation
               else "rotation = false: nve integrates positions only, omega stays 0")
    record = every > 0
    lines = [
        f"# LAMMPS input deck of the diskfriction scene {scene.name!r} ({scene.source}), "
        f"diskfriction {version}.",
        f"# Start: {start.note}.",
        "# Units: the scene's raw units (docs/model.md: lengths, masses, stiffnesses and forces as "
        "the scene gives them), in LAMMPS's units lj.",
        _conventions_note(scene),
        "# Run: lmp -in in.scene [-var steps N] [-var dt DT]" + (" [-var every K]" if record else ""),
        "",
        f"variable dt index {number(dt)}       # time step [time]",
        f"variable steps index {steps}",
    ]
    if record:
        lines.append(f"variable every index {every}             # steps between dumps")
    lines += [
        "",
        "units lj",
        "dimension 2",
        "atom_style sphere",
        "boundary p f p                      # x periodic: ring length L = 2 N R (1 - eps); y: the substrate is a wall",
        "atom_modify map array",
        "comm_modify vel yes                 # granular contacts need the velocities of ghost disks",
        f"read_data {DATA_FILE}",
        f"set group all mass {number(scene.m)}   # m (read_data made it from the density)",
        "",
        *pair.comments("disk-disk contacts", "R/2"),
        "pair_style granular",
        f"pair_coeff * * {pair.model()}",
        *wall.comments("substrate y = 0", "R"),
        f"fix substrate all wall/gran granular {wall.model()} yplane 0 NULL",
        "",
        "group disk1 id 1",
        f"fix weight all addforce 0 {number(-scene.F_y)} 0    # F_y pressing every disk onto the substrate",
        f"fix load disk1 addforce {number(start.F_x)} 0 0     # F_x on disk 1",
        f"fix integrate all {integrator}   # velocity Verlet; {inertia}",
        "fix plane all enforce2d",
        "",
        f"neighbor {number(SKIN_PER_R * R)} bin",
        "neigh_modify delay 0 every 1 check yes",
        "timestep ${dt}",
        *(_recording(effects.rotation) if record else []),
        "thermo_style custom step time ke",
        "thermo ${steps}",
        "run ${steps}",
    ]
    return "\n".join(lines) + "\n"


def deck(scene: Scene, start: Start, dt: float, steps: int, every: int) -> Deck:
    """The data file and input deck of `scene` from `start` (raises Unrepresentable): dt
    [time], steps, a dump every `every` steps (0: none)."""
    import diskfriction

    check_representable(scene)
    return Deck(data_file(scene, start.q), input_deck(scene, start, dt, steps, every,
                                                      diskfriction.__version__), dt, steps, every)
