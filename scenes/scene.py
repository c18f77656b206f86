"""The Scene: one frozen description of a disk chain, its loads and the effects simulated.

Units are the scene's raw units (docs/model.md, Units): lengths in units where the disk
diameter is 2R, masses in units of m, stiffnesses k_n [force / length^p] (p = 3/2, Hertz), forces
[force]. Scene and Effects check every field with its rule (scenes/rules.py) when constructed,
and a Scene checks that its derived quantities (L, I, delta_w0, tau) are finite: a bad value is a
SceneValueError, one line naming the field and the value.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, ClassVar

from diskfriction.scenes.rules import (CONVENTIONS, EFFECTS_RULES, FRICTION_KINDS, MATRICES,
                                       NEGATIVE_LOAD, NORMAL_LAWS, SCENE_RULES, TANGENTIAL_LAWS,
                                       Invalid, normal_positive)

__all__ = ["CONVENTIONS", "FRICTION_KINDS", "MATRICES", "NEGATIVE_LOAD", "NORMAL_LAWS",
           "TANGENTIAL_LAWS", "Effects", "Scene", "SceneValueError"]


class SceneValueError(ValueError):
    """A Scene or Effects given a value it does not take, in one line: ``Scene.R: must be > 0
    (got -1)``, or for a derived quantity ``Scene: I = c m R^2 = inf, not a finite normal number
    (got inertia = 0.5, m = 1.0, R = 1e+308)``.

    ``owner`` is "Scene" or "Effects"; ``fields`` the fields to blame (one, or those a derived
    quantity is made of), ``values`` their values, ``what`` what is wrong.
    """

    def __init__(self, owner: str, fields: tuple[str, ...], values: tuple[Any, ...],
                 what: str) -> None:
        self.owner, self.fields, self.values, self.what = owner, fields, values, what
        given = repr(values[0]) if len(fields) == 1 else ", ".join(
            f"{field} = {value!r}" for field, value in zip(fields, values))
        where = f"{owner}.{fields[0]}" if len(fields) == 1 else owner
        super().__init__(f"{where}: {what} (got {given})")


def _check_fields(instance: Any, rules: dict) -> None:
    """Check every field of the frozen ``instance`` with its rule and store what the rule
    returns (floats for numbers given as integers, a tuple for F_x_range)."""
    owner = type(instance).__name__
    for field, rule in rules.items():
        value = getattr(instance, field)
        try:
            object.__setattr__(instance, field, rule.check(value))
        except Invalid as invalid:
            raise SceneValueError(owner, (field,), (value,), invalid.what) from None


@dataclass(frozen=True)
class Effects:
    """Which physics a scene simulates; the symbolic layer derives exactly these.

    normal          contact law for the normal force F_n = k_n delta^p (rules.NORMAL_LAWS):
                    "hertz" (p = 3/2, the paper) or "hooke" (p = 1, a linear spring).
    tangential      contact law for the tangential force (docs/model.md#contacts): "mindlin-smooth" (paper
                    eq. 5), "mindlin-linear" (k_t delta^(1/2) xi, hard cap at mu F_n), "none".
    pair_friction   tangential force at disk-disk contacts.
    wall_friction   tangential force at disk-substrate contacts.
    rotation        disks rotate (3N degrees of freedom) or not (2N).
    conventions     how a disk-disk contact's torque and history increment are discretised
                    (docs/physics.md, "Conventions"): "model" (docs/model.md#contacts: lever arm R, history
                    increment along the tangent at the middle of a step, a contact closing
                    during a step charges only the part after first contact) or "lammps"
                    (LAMMPS's granular package: lever arm R - delta/2, increment along the
                    tangent at the end of the step, all of it charged on closing).
    """

    tangential: str = "mindlin-smooth"
    pair_friction: bool = True
    wall_friction: bool = True
    rotation: bool = True
    conventions: str = "model"
    normal: str = "hertz"

    def __post_init__(self) -> None:
        _check_fields(self, EFFECTS_RULES)

    @property
    def pair_law(self) -> str:
        """Tangential law at disk-disk contacts after the friction switch."""
        return self.tangential if self.pair_friction else "none"

    @property
    def wall_law(self) -> str:
        """Tangential law at disk-substrate contacts after the friction switch."""
        return self.tangential if self.wall_friction else "none"

    @property
    def contact_conventions(self) -> str:
        """The conventions that change anything: "model" when no contact has friction (the
        lever arm then multiplies a zero tangential force and no history is charged)."""
        frictionless = self.pair_law == "none" and self.wall_law == "none"
        return "model" if frictionless else self.conventions

    @property
    def dof_per_disk(self) -> int:
        return 3 if self.rotation else 2


DERIVED = (
    ("L", "2 N R (1 - eps)", ("N", "R", "eps")),
    ("I", "c m R^2", ("inertia", "m", "R")),
    ("delta_w0", "(F_y / k_n)^(1/p)", ("F_y", "k_n")),
    ("tau", "sqrt(m / (k_n (2R)^(1/2)))", ("m", "k_n", "R")),
)
"""The derived quantities a Scene checks at construction (name, formula, the fields it is made
of): each must be a finite normal number (rules.normal_positive), so that neither it nor its
reciprocal overflows to inf or underflows to 0 where the mass matrix, the stiffnesses and the
time unit use it."""


@dataclass(frozen=True)
class Scene:
    """A chain of N disks on the substrate y = 0, periodic in x with ring length L.

    Raw units throughout. ``inertia`` is c in I = c m R^2; ``F_x_range`` = (start, stop) of the
    quasistatic load on disk 1; ``matrix`` is the stability matrix ("J" or "M^-1 J").
    """

    geometry: ClassVar[str] = "chain"
    """The scene file's top-level ``geometry`` (scenes/rules.py GEOMETRIES): the model that
    computes this scene (diskfriction.models)."""

    N: int = 10
    R: float = 0.5
    m: float = 1.0
    inertia: float = 0.5
    eps: float = 0.0
    k_n: float = 2000.0
    k_t: float = 2000.0 * 2.0 / 7.0
    mu: float = 10.0
    F_y: float = 0.1
    F_x_range: tuple[float, float] = (0.0, 0.12)
    matrix: str = "J"
    effects: Effects = Effects()
    name: str = "paper"
    source: str = "<defaults>"

    def __post_init__(self) -> None:
        _check_fields(self, SCENE_RULES)
        if not isinstance(self.effects, Effects):
            raise SceneValueError("Scene", ("effects",), (self.effects,), "expected an Effects")
        for name, formula, fields in DERIVED:
            try:
                value = getattr(self, name)
            except OverflowError:
                value = math.inf
            if not normal_positive(value):
                raise SceneValueError("Scene", fields, tuple(getattr(self, f) for f in fields),
                                      f"{name} = {formula} = {value!r}, not a finite normal number")

    @property
    def L(self) -> float:
        """Ring length L = 2 N R (1 - eps)."""
        return 2.0 * self.N * self.R * (1.0 - self.eps)

    @property
    def I(self) -> float:  # noqa: E743 - the physicist's name for the moment of inertia
        """Moment of inertia I = c m R^2."""
        return self.inertia * self.m * self.R**2

    @property
    def delta_w0(self) -> float:
        """Substrate overlap of the F_x = 0 equilibrium, F_n(delta_w) = F_y: delta_w =
        (F_y / k_n)^(1/p), p the normal law's exponent (2/3 for Hertz) [length]."""
        return (self.F_y / self.k_n) ** float(1 / NORMAL_LAWS[self.effects.normal])

    @property
    def kappa_w0(self) -> float:
        """Normal stiffness of a substrate contact at rest, dF_n/ddelta at delta_w0 = p F_y /
        delta_w0 (p k_n delta^(p - 1) with k_n delta_w0^p = F_y) [force / length]: what the
        y modes of the rest state sit at (docs/model.md#units), for estimates before any kernel
        is loaded; the kernels' own is kernels.normal_stiffness."""
        return float(NORMAL_LAWS[self.effects.normal]) * self.F_y / self.delta_w0

    @property
    def tau(self) -> float:
        """The paper's time unit tau = sqrt(m / (k_n (2R)^(1/2))) in raw time."""
        return math.sqrt(self.m / (self.k_n * math.sqrt(2.0 * self.R)))

    @property
    def resolved_effects(self) -> Effects:
        """Effects actually simulated: mu = 0 carries no tangential force, so friction is off."""
        if self.mu == 0.0 and self.effects.tangential != "none":
            return dataclasses.replace(self.effects, tangential="none", pair_friction=False,
                                       wall_friction=False)
        return self.effects

    @property
    def ndof(self) -> int:
        return self.N * self.resolved_effects.dof_per_disk

    def physics_fields(self) -> dict:
        """Every field that enters physics (all but ``name`` and ``source``, so renaming or
        moving a scene file changes nothing), as JSON values: what cache keys record."""
        fields = dataclasses.asdict(self)
        del fields["name"], fields["source"]
        fields["F_x_range"] = list(fields["F_x_range"])
        return fields
