"""The rules a scene's values obey: one Rule per field of Scene and Effects, the only place a
bound is written.

Scene and Effects check every field with its rule when constructed (scenes/scene.py); the scene
loader checks each key of a file with the rule of the field it sets and states the rule's bound
in the comments it writes (scenes/load.py). A rule takes the value as a TOML file or a caller
gives it (a boolean is never a number, an integer is a number) and returns the value stored
(numbers as float, N as int, F_x as a tuple), or raises Invalid saying what is wrong.
"""
from __future__ import annotations

import datetime
import math
import numbers
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Callable

from diskfriction.matrices import Matrix

NORMAL_LAWS = {"hertz": Fraction(3, 2), "hooke": Fraction(1)}
"""Normal contact laws F_n = k_n delta^p [force] by name, each with its exponent p (k_n in
force / length^p): the one place a normal law is added. symbolic/laws.py derives from it, with
sympy, the kernels' forces and stiffness and the generated normal_force, normal_stiffness,
normal_energy and coulomb_limit; Scene the rest overlap delta_w0 = (F_y / k_n)^(1/p)
(docs/physics.md, "Where to add a law")."""
TANGENTIAL_LAWS = ("mindlin-smooth", "mindlin-linear", "none")
FRICTION_KINDS = ("disk-disk", "substrate")
CONVENTIONS = ("model", "lammps")
MATRICES = tuple(Matrix)  # diskfriction.matrices: the one definition of the names
NEGATIVE_LOAD = ("a negative load is the mirror image of a positive one (x -> -x, theta -> "
                 "-theta, disk i -> disk 2 - i mod N), so use |F_x| (docs/physics.md)")
"""Why F_x < 0 is refused, by the scene loader and by every command."""
INT64 = (-(2**63), 2**63 - 1)
"""The integers TOML can write; N beyond them is refused from a caller too."""


class Invalid(ValueError):
    """A value breaking a rule; ``what`` says which. Whoever checks adds the field or key."""

    def __init__(self, what: str) -> None:
        super().__init__(what)
        self.what = what


@dataclass(frozen=True)
class Rule:
    """The values one field takes.

    check   value -> the value stored; raises Invalid for a value the field does not take.
    bound   the rule in words, as comments state it ("> 0", "in [0, 0.1)"); "" for a plain kind.
    """

    check: Callable[[Any], Any]
    bound: str


def kind(value: Any) -> str:
    """The kind of a value, as TOML names it, for "expected X, not Y" messages."""
    kinds = ((bool, "a boolean"), (numbers.Integral, "an integer"), (numbers.Real, "a float"),
             (str, "a string"), ((list, tuple), "an array"), (dict, "a table"),
             ((datetime.date, datetime.time), "a date/time"))
    return next((name for cls, name in kinds if isinstance(value, cls)), type(value).__name__)


def expect(value: Any, cls: type | tuple[type, ...], expected: str) -> Any:
    """``value`` if it is an instance of ``cls`` (a boolean only if ``cls`` is bool), else
    Invalid; an integer beyond TOML's 64 bits is Invalid too."""
    is_bool = isinstance(value, bool)
    if not isinstance(value, cls) or (is_bool and cls is not bool):
        raise Invalid(f"expected {expected}, not {kind(value)}")
    if isinstance(value, numbers.Integral) and not is_bool and not INT64[0] <= value <= INT64[1]:
        raise Invalid("integer outside TOML's 64-bit range")
    return value


def number(value: Any) -> float:
    """A finite float from an integer or a float; never a boolean or a string."""
    real = float(expect(value, numbers.Real, "a number"))
    if not math.isfinite(real):
        raise Invalid("must be a finite number")
    return real


def _number_rule(holds: Callable[[float], bool], bound: str) -> Rule:
    """A finite number for which ``holds``: "must be BOUND" otherwise."""

    def check(value: Any) -> float:
        real = number(value)
        if not holds(real):
            raise Invalid(f"must be {bound}")
        return real

    return Rule(check, bound)


def _count(value: Any) -> int:
    """N: an integer (not a boolean or a float) of at least 2."""
    count = int(expect(value, numbers.Integral, "an integer"))
    if count < 2:
        raise Invalid("must be >= 2")
    return count


PACKING_MIN_N = 16
"""The fewest disks a packing scene takes. A periodic box jams a bidisperse packing only with
enough disks: isostaticity asks 2 (N' - 1) + 1 contacts of the N' disks that are not rattlers,
each with at least 3, and with nearest-image contacts a pair touches once, so the box must also
be wider than twice the largest contact distance. Measured with the default mixture (radius
ratio 1.4, half small) at P = 0.1: N = 4 and 5 never jam (5 seeds each; FIRE stalls at max
|F| = 15 to 190, the box at phi = 0.88, L = 2.3 and 2.65, narrower than 4 R_max = 2.8); N = 6
to 12 jam, but seeds repeat the same few packings (N = 10: 4 of 10 seeds give phi = 0.8361, 3
give 0.8021), most of them exactly isostatic (z = 4 - 2/N'), and the shear to gamma = 0.005
raised in 4 of 10 seeds at N = 10; from N = 14 on 10 seeds gave 10 distinct packings at or
above isostaticity, and N = 12 to 24 sheared to gamma = 0.005 in every one of 10 seeds. 16
leaves a margin over 14."""


def _packing_count(value: Any) -> int:
    """A packing's N: an integer of at least PACKING_MIN_N (its docstring says why)."""
    count = int(expect(value, numbers.Integral, "an integer"))
    if count < PACKING_MIN_N:
        raise Invalid(f"must be >= {PACKING_MIN_N}: fewer disks in a periodic box jam into "
                      f"the same few packings or not at all (docs/packings.md, Preparation)")
    return count


def _load_range(value: Any) -> tuple[float, float]:
    """F_x: an array [start, stop] of two finite numbers with 0 <= start < stop (NEGATIVE_LOAD
    says why not below 0)."""
    if len(expect(value, (list, tuple), "an array [start, stop]")) != 2:
        raise Invalid(f"expected exactly two numbers [start, stop], not {len(value)}")
    start, stop = map(number, value)
    if start < 0:
        raise Invalid(f"must be >= 0: {NEGATIVE_LOAD}")
    if start == stop:
        raise Invalid("empty range: start == stop")
    if start > stop:
        raise Invalid("reversed range: start > stop")
    return (start, stop)


GAMMA_MAX = 1.0
"""The largest shear strain a packing scene asks for. Quasistatic shear to order-one strain
already takes a jammed packing through its transient to steady plastic flow, and past it the
analysis is hours to days: a unit of strain takes 32 disks 6 to 12 minutes with full spectra,
64 disks 50 to 90 minutes (2026-12-02, 9b7bcfe), 256 disks with a window [-3, 8] about 1.6
hours (2026-11-29, 856a534; docs/packings.md, What the tool finds, Cost and limits);
the longest shear the tool was checked on is 256 disks to gamma = 0.05, and the 1000 plastic
events a command passes last 32 disks at mu = 10 a strain of 0.4 (P = 0.01) to 5 (P = 0.1)."""


MAX_OVERLAP = 0.1
"""The largest typical overlap of a packing scene, delta_0 = (2 R P / k_n)^(1/p) at most this
times R (PackingScene checks it): Hertz's law and the linear spring are laws of small overlaps
(Hertz's contact radius sqrt(R_eff delta) is already 0.2 R at delta = 0.1 R), and the
preparation finds no jammed state above phi = 0.95, which an affine compression of phi_J = 0.84
by overlaps of 0.1 R nearly reaches (0.84 / (1 - 0.05)^2 = 0.93; measured: 32 disks at
delta_0 = 0.1 R, P = 22.4 with the default k_n, jam at phi = 0.925 and 0.927 for seeds 1, 2)."""


def _strain_range(value: Any) -> tuple[float, float]:
    """gamma: an array [start, stop] of two finite numbers with 0 <= start < stop <= GAMMA_MAX
    (a negative strain is the mirror image x -> -x of a positive one; GAMMA_MAX says why no
    further)."""
    if len(expect(value, (list, tuple), "an array [start, stop]")) != 2:
        raise Invalid(f"expected exactly two numbers [start, stop], not {len(value)}")
    start, stop = map(number, value)
    if start < 0:
        raise Invalid("must be >= 0: a negative strain is the mirror image x -> -x of a positive one")
    if start >= stop:
        raise Invalid("empty range: start == stop" if start == stop else "reversed range: start > stop")
    if stop > GAMMA_MAX:
        raise Invalid(f"must be <= {GAMMA_MAX:g}: quasistatic shear to order-one strain already "
                      f"reaches steady plastic flow, and beyond it takes hours to days "
                      f"(docs/packings.md, What a packing scene may ask for)")
    return (start, stop)


SPECTRA = ("auto", "none", "full", "sample:DGAMMA")
"""What a packing's shear computes of the spectrum (PackingScene.spectra, docs/packings.md,
Spectra): chosen from N (auto), nothing (none: equilibria, contact and plastic events, stress),
the spectrum on the strain grid gamma = k DGAMMA (sample:DGAMMA: counts and growth rates there,
no collision located) or at every accepted state with every collision located (full)."""


def spectra_choice(value: Any) -> str:
    """A packing's spectra: "auto", "none", "full" or "sample:DGAMMA" with DGAMMA a finite
    number > 0 (stored as written, DGAMMA as repr(float))."""
    text = expect(value, str, "a string")
    kind, colon, every = text.partition(":")
    if kind == "sample" and colon:
        try:
            spacing = float(every)
        except ValueError:
            spacing = math.nan
        if not (math.isfinite(spacing) and spacing > 0.0):
            raise Invalid(f"sample:DGAMMA needs DGAMMA a finite number > 0, not {every!r}")
        return f"sample:{spacing!r}"
    if text not in SPECTRA[:3]:
        raise Invalid(f"must be one of {' | '.join(SPECTRA)}")
    return text


def _seed(value: Any) -> int:
    """A seed: an integer >= 0 (numpy's generators take no negative seed)."""
    seed = int(expect(value, numbers.Integral, "an integer"))
    if seed < 0:
        raise Invalid("must be >= 0")
    return seed


def _one_of(options: tuple[str, ...], effect: str) -> Rule:
    """A string naming one of ``options``; anything else is an unknown effect."""

    def check(value: Any) -> str:
        if expect(value, str, "a string") not in options:
            raise Invalid(f"unknown effect: {effect} must be one of {' | '.join(options)}")
        return value

    return Rule(check, " | ".join(options))


TEXT = Rule(lambda value: expect(value, str, "a string"), "")
FLAG = Rule(lambda value: expect(value, bool, "a boolean (true or false)"), "")
POSITIVE = _number_rule(lambda x: x > 0.0, "> 0")

SCENE_RULES: dict[str, Rule] = {
    "N": Rule(_count, "an integer >= 2"),
    "R": POSITIVE,
    "m": POSITIVE,
    "inertia": POSITIVE,
    "eps": _number_rule(lambda x: 0.0 <= x < 0.1, "in [0, 0.1)"),
    "k_n": POSITIVE,
    "k_t": POSITIVE,
    "mu": _number_rule(lambda x: x >= 0.0, ">= 0"),
    "F_y": POSITIVE,
    "F_x_range": Rule(_load_range, "0 <= start < stop"),
    "matrix": _one_of(MATRICES, "stability matrix"),
    "name": TEXT,
    "source": TEXT,
}
"""Scene field -> its rule (``effects`` is an Effects, which checks its own fields)."""

RELAXATIONS = ("fire", "damped")
"""How a packing relaxes after a plastic event (models/packing/plastic.py): FIRE, or Newtonian dynamics
with a viscous drag of rate `damping` omega_0."""

GEOMETRIES = ("chain", "packing")
"""What a scene file's top-level ``geometry`` names: the paper's chain on a substrate (the
default), or a 2D packing in a sheared periodic box (scenes/packing.py, docs/packings.md)."""

PACKING_RULES: dict[str, Rule] = {
    "N": Rule(_packing_count, f"an integer >= {PACKING_MIN_N}"),
    "size_ratio": _number_rule(lambda x: x >= 1.0, ">= 1"),
    "fraction_small": _number_rule(lambda x: 0.0 <= x <= 1.0, "in [0, 1]"),
    "pressure": POSITIVE,
    "seed": Rule(_seed, "an integer >= 0"),
    "R": POSITIVE,
    "m": POSITIVE,
    "inertia": POSITIVE,
    "k_n": POSITIVE,
    "k_t": POSITIVE,
    "mu": _number_rule(lambda x: x >= 0.0, ">= 0"),
    "gamma_range": Rule(_strain_range, f"0 <= start < stop <= {GAMMA_MAX:g}"),
    "relaxation": _one_of(RELAXATIONS, "relaxation"),
    "damping": POSITIVE,
    "matrix": _one_of(MATRICES, "stability matrix"),
    "spectra": Rule(spectra_choice, " | ".join(SPECTRA)),
    "name": TEXT,
    "source": TEXT,
}
"""PackingScene field -> its rule."""

EFFECTS_RULES: dict[str, Rule] = {
    "normal": _one_of(tuple(NORMAL_LAWS), "normal law"),
    "tangential": _one_of(TANGENTIAL_LAWS, "tangential law"),
    "pair_friction": FLAG,
    "wall_friction": FLAG,
    "rotation": FLAG,
    "conventions": _one_of(CONVENTIONS, "conventions"),
}
"""Effects field -> its rule."""


def friction_kinds(value: Any) -> tuple[str, ...]:
    """A scene file's effects.friction: an array of distinct strings from FRICTION_KINDS (may be
    empty), each turning on one of Effects' switches pair_friction and wall_friction."""
    kinds = expect(value, list, "an array of strings")
    if not all(isinstance(each, str) for each in kinds):
        raise Invalid("expected an array of strings")
    unknown = [each for each in kinds if each not in FRICTION_KINDS]
    if unknown:
        raise Invalid(f"unknown effect: friction kind {unknown[0]!r}, "
                      f"expected a subset of {', '.join(FRICTION_KINDS)}")
    if len(set(kinds)) != len(kinds):
        raise Invalid("duplicated friction kind")
    return tuple(kinds)


FRICTION = Rule(friction_kinds, "a subset of " + ", ".join(FRICTION_KINDS) + ", may be empty")


def normal_positive(value: float) -> bool:
    """Whether ``value`` is a finite number no smaller than the smallest normal double: one
    whose powers and reciprocal a derived quantity may take without overflowing to inf or
    underflowing to 0."""
    return math.isfinite(value) and value >= 2.2250738585072014e-308
