"""The scene files' schemas: each dotted key with the rule of the field it sets (scenes/rules.py),
its meaning and unit, for a chain (SCHEMA) and a packing (PACKING_SCHEMA), and the fields each
key sets. Read and written by scenes/load.py."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from diskfriction.scenes.rules import (EFFECTS_RULES, FRICTION, PACKING_RULES, SCENE_RULES,
                                       Invalid, Rule)

# Scene field -> dotted key, for the fields a file sets one to one.
FIELDS = {
    "name": "name",
    "N": "disks.N",
    "R": "disks.R",
    "m": "disks.m",
    "inertia": "disks.inertia",
    "eps": "disks.eps",
    "k_n": "contacts.k_n",
    "k_t": "contacts.k_t",
    "mu": "contacts.mu",
    "F_y": "load.F_y",
    "F_x_range": "load.F_x",
    "matrix": "stability.matrix",
}
# Effects field -> dotted key, for the effects a file sets one to one.
EFFECT_FIELDS = {
    "normal": "effects.normal",
    "tangential": "effects.tangential",
    "rotation": "effects.rotation",
    "conventions": "effects.conventions",
}
# Friction kind in a file -> the Effects switch it turns on.
FRICTION_SWITCHES = {"disk-disk": "pair_friction", "substrate": "wall_friction"}




@dataclass(frozen=True)
class Key:
    """One key of the schema: the rule of the field it sets (scenes/rules.py), what it means and
    its unit ("[length]"; "" for a pure number)."""

    rule: Rule
    meaning: str
    unit: str = ""

    @property
    def comment(self) -> str:
        """What format_scene writes beside the key: meaning, unit and the rule's bound."""
        text = f"{self.meaning} {self.unit}".strip()
        return f"{text}; {self.rule.bound}" if self.rule.bound else text


STIFFNESS = "[force / length^(3/2)]"
# Dotted key -> its rule, meaning and unit, in the order format_scene writes them.
SCHEMA: dict[str, Key] = {
    "name": Key(SCENE_RULES["name"], "label"),
    "disks.N": Key(SCENE_RULES["N"], "number of disks"),
    "disks.R": Key(SCENE_RULES["R"], "disk radius", "[length]"),
    "disks.m": Key(SCENE_RULES["m"], "disk mass", "[mass]"),
    "disks.inertia": Key(SCENE_RULES["inertia"], "c in I = c m R^2 (0.5: uniform disk)"),
    "disks.eps": Key(SCENE_RULES["eps"], "pre-compression, L = 2 N R (1 - eps)"),
    "contacts.k_n": Key(SCENE_RULES["k_n"], "normal stiffness, F_n = k_n delta^p",
                         "[force / length^p]"),
    "contacts.k_t": Key(SCENE_RULES["k_t"], "Mindlin tangential stiffness", STIFFNESS),
    "contacts.mu": Key(SCENE_RULES["mu"], "friction coefficient (0 turns friction off)"),
    "load.F_y": Key(SCENE_RULES["F_y"], "downward force on every disk", "[force]"),
    "load.F_x": Key(SCENE_RULES["F_x_range"], "quasistatic range [start, stop] of the force on "
                                               "disk 1", "[force]"),
    "effects.normal": Key(EFFECTS_RULES["normal"], "normal contact law, F_n = k_n delta^p "
                                                    "(hertz: p = 3/2, hooke: p = 1)"),
    "effects.tangential": Key(EFFECTS_RULES["tangential"], "tangential contact law"),
    "effects.friction": Key(FRICTION, "where the tangential law acts"),
    "effects.rotation": Key(EFFECTS_RULES["rotation"],
                             "disks rotate (3 dof per disk) or not (2)"),
    "effects.conventions": Key(EFFECTS_RULES["conventions"], "disk-disk lever arm and history "
                                                              "increment (docs/physics.md)"),
    "stability.matrix": Key(SCENE_RULES["matrix"], "stability matrix"),
}
KEYS = {**FIELDS, **EFFECT_FIELDS}
"""Scene or Effects field -> the dotted key that sets it (effects.friction sets two switches)."""


def packing_friction(value: Any) -> tuple[str, ...]:
    """A packing file's effects.friction: [] or ["disk-disk"] (a packing has no substrate)."""
    kinds = FRICTION.check(value)
    if "substrate" in kinds:
        raise Invalid("a packing has no substrate: friction is a subset of disk-disk")
    return kinds


# PackingScene field -> dotted key, for the fields a packing file sets one to one.
PACKING_FIELDS = {
    "name": "name",
    "N": "packing.N",
    "size_ratio": "packing.size_ratio",
    "fraction_small": "packing.fraction_small",
    "pressure": "packing.pressure",
    "seed": "packing.seed",
    "R": "disks.R",
    "m": "disks.m",
    "inertia": "disks.inertia",
    "k_n": "contacts.k_n",
    "k_t": "contacts.k_t",
    "mu": "contacts.mu",
    "gamma_range": "shear.gamma",
    "relaxation": "shear.relaxation",
    "damping": "shear.damping",
    "matrix": "stability.matrix",
    "spectra": "stability.spectra",
}
PACKING_EFFECTS = {"normal": "effects.normal", "tangential": "effects.tangential"}
PACKING_SCHEMA: dict[str, Key] = {
    "name": Key(PACKING_RULES["name"], "label"),
    "packing.N": Key(PACKING_RULES["N"], "number of disks"),
    "packing.size_ratio": Key(PACKING_RULES["size_ratio"], "large / small radius"),
    "packing.fraction_small": Key(PACKING_RULES["fraction_small"], "fraction of small disks"),
    "packing.pressure": Key(PACKING_RULES["pressure"], "target pressure of the preparation",
                             "[force / length]"),
    "packing.seed": Key(PACKING_RULES["seed"], "seed of the initial positions"),
    "disks.R": Key(PACKING_RULES["R"], "small disk radius", "[length]"),
    "disks.m": Key(PACKING_RULES["m"], "small disk mass (same density for all)", "[mass]"),
    "disks.inertia": Key(PACKING_RULES["inertia"], "c in I = c m_i R_i^2 (0.5: uniform disk)"),
    "contacts.k_n": SCHEMA["contacts.k_n"],
    "contacts.k_t": SCHEMA["contacts.k_t"],
    "contacts.mu": SCHEMA["contacts.mu"],
    "shear.gamma": Key(PACKING_RULES["gamma_range"], "quasistatic range [start, stop] of the "
                                                      "shear strain (Lees-Edwards)"),
    "shear.relaxation": Key(PACKING_RULES["relaxation"], "relaxation after a plastic event: FIRE, "
                                                         "or dynamics with a drag"),
    "shear.damping": Key(PACKING_RULES["damping"], "drag rate of the damped relaxation, in units "
                                                   "of omega_0 (2: critical)"),
    "effects.normal": SCHEMA["effects.normal"],
    "effects.tangential": SCHEMA["effects.tangential"],
    "effects.friction": Key(Rule(packing_friction, "[] or [\"disk-disk\"]"),
                             "where the tangential law acts"),
    "stability.matrix": SCHEMA["stability.matrix"],
    "stability.spectra": Key(PACKING_RULES["spectra"], "what the shear computes of the spectrum "
                                                       "(auto: chosen from N)"),
}
PACKING_KEYS = {**PACKING_FIELDS, **PACKING_EFFECTS}
SCHEMAS = {"chain": SCHEMA, "packing": PACKING_SCHEMA}


def tables(schema: dict[str, Key]) -> tuple[str, ...]:
    return tuple(dict.fromkeys(key.partition(".")[0] for key in schema if "." in key))


TABLES = tables(SCHEMA)
