"""What the preparation (prepare.py, prepared.py) can make of a PackingScene, known before any
work: a box wide enough for its contacts, and a target pressure whose forces double precision
resolves to the preparation's tolerance (models/packing/commands_checks.check_packing refuses the others).

Both are set by the preparation's first relaxation, at PHI_START = 0.88 whatever the target
(prepare.py), in a box of side L_s = sqrt(pi sum R_i^2 / PHI_START):

- Contacts are taken by nearest image, so a pair touches once only while L_s / 2 exceeds the
  largest contact distance, the sum of the two largest radii. N = 5 of the default mixture
  (L_s = 2.65 against 2.8) stalls there at max |F| = 15 to 65 in every seed; 16 disks, one of
  radius 10 R, (L_s = 10.1 against 11) at max |F| = 604; one of radius 4 R (5.26 against 5)
  jams.
- FIRE stops when every disk's force is below F_TOL of a contact's force at the target, F_TOL
  2 R P (prepared.F_TOL: 1e-9). Coordinates lie in [0, L), rounded to eps L (eps = 2.2e-16), so
  a disk's force is resolved no better than the change of a contact's force over that,
  p k_n delta^(p - 1) eps L, at the overlaps of the first relaxation, delta_s = 2 <R> (1 -
  sqrt(JAMMING_FRACTION / PHI_START)) (an affine compression from jamming). A target below
  RESOLUTION_MARGIN times that floor over F_TOL 2 R is never reached: FIRE stalls at PHI_START.
  Measured with the default mixture and k_n = 2000: 32 disks prepare at P = 5e-4 in 3 of 3
  seeds and stall at 3e-4 and below (max |F| = 1.0e-12 to 1.6e-12, 1.3 to 2.3 times the floor
  7.2e-13); 256 disks prepare at 3e-3 and stall at 1e-3 (3.4e-12, 1.7 times 2.0e-12). With the
  margin 2 the smallest pressure is 1.4e-3 at 32 disks, 4.1e-3 at 256, 8.2e-3 at 1024; the
  default P = 0.1 up to about 1.5e5 disks.
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from diskfriction.models.packing.prepare import PHI_START
from diskfriction.models.packing.prepared import F_TOL
from diskfriction.scenes.packing import PackingScene
from diskfriction.scenes.rules import NORMAL_LAWS

JAMMING_FRACTION = 0.84
"""phi_J of 2D bidisperse disks (radius ratio 1.4, half small; O'Hern et al., PRE 68, 011306
(2003)), from which the overlaps at PHI_START are estimated."""

RESOLUTION_MARGIN = 2.0
"""The preparation's force tolerance must be this many times the rounding floor (module
docstring): FIRE stalled at 1.3 to 2.3 times it."""

EPS = float(np.finfo(float).eps)


def radii_counts(scene: PackingScene) -> tuple[int, int]:
    """(small, large): round(N fraction_small) disks of radius R, the rest R size_ratio."""
    small = int(round(scene.N * scene.fraction_small))
    return small, scene.N - small


def start_box(scene: PackingScene) -> float:
    """L_s = sqrt(pi sum R_i^2 / PHI_START), the box of the first relaxation [length]."""
    small, large = radii_counts(scene)
    area = math.pi * scene.R ** 2 * (small + large * scene.size_ratio ** 2)
    return math.sqrt(area / PHI_START)


def largest_contact(scene: PackingScene) -> float:
    """The sum of the two largest radii: the largest distance at which two disks touch [length]."""
    small, large = radii_counts(scene)
    radii = [scene.R * scene.size_ratio] * min(large, 2) + [scene.R] * min(small, 2)
    return radii[0] + radii[1]


def start_overlap(scene: PackingScene) -> float:
    """delta_s = 2 <R> (1 - sqrt(JAMMING_FRACTION / PHI_START)), the typical overlap of the
    first relaxation [length]."""
    small, large = radii_counts(scene)
    mean = scene.R * (small + large * scene.size_ratio) / scene.N
    return 2.0 * mean * (1.0 - math.sqrt(JAMMING_FRACTION / PHI_START))


def force_floor(scene: PackingScene) -> float:
    """p k_n delta_s^(p - 1) eps L_s: how finely double precision resolves a disk's force in the
    first relaxation [force] (module docstring)."""
    p = float(NORMAL_LAWS[scene.effects.normal])
    return p * scene.k_n * start_overlap(scene) ** (p - 1.0) * EPS * start_box(scene)


def smallest_pressure(scene: PackingScene) -> float:
    """RESOLUTION_MARGIN force_floor / (F_TOL 2 R): the smallest target pressure the preparation
    reaches for this N, mixture, k_n and R [force / length]."""
    return RESOLUTION_MARGIN * force_floor(scene) / (F_TOL * 2.0 * scene.R)


def preparation_problem(scene: PackingScene) -> Optional[tuple[str, str]]:
    """(the scene key to blame, why the preparation cannot make this scene), or None."""
    box, contact = start_box(scene), largest_contact(scene)
    if box <= 2.0 * contact:
        return ("packing.N", f"the preparation's box at phi = {PHI_START:g} is {box:.3g} wide, "
                f"not wider than twice the largest contact distance, 2 x {contact:.3g}: a disk "
                f"would touch two images of one neighbour, which contacts by nearest image "
                f"cannot hold; take more disks or a smaller size_ratio")
    smallest = smallest_pressure(scene)
    if scene.pressure < smallest:
        tolerance = F_TOL * 2.0 * scene.R * scene.pressure
        return ("packing.pressure", f"the preparation relaxes first at phi = {PHI_START:g}, "
                f"where double precision resolves a disk's force to about "
                f"{force_floor(scene):.2g} in a box of side {box:.3g} (FIRE stalls at up to "
                f"twice that), and its tolerance, {F_TOL:g} of a contact's force at this "
                f"pressure, is {tolerance:.2g}; the smallest pressure it prepares with "
                f"N = {scene.N}, k_n = {scene.k_n:g} and R = {scene.R:g} is about {smallest:.2g}")
    return None
