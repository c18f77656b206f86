"""A PackingScene's packing: its preparation protocol run with the scene's own kernels
(docs/packings.md#preparation)."""
from __future__ import annotations

from typing import Optional

from diskfriction.models.packing.fire import Progress
from diskfriction.models.packing.network import frictionless_forces
from diskfriction.models.packing.prepare import Packing, contacts, prepare
from diskfriction.scenes.packing import PackingScene
from diskfriction.symbolic.kernels import load_packing_kernels

F_TOL = 1e-9
"""FIRE stops when every disk's force is below F_TOL times the force a contact carries at the
target pressure, P 2R [force]: the pressure is then measured to about 1e-9 relative, far inside
the search's 1e-3, and a Newton solve with friction starts from a force balance it can keep."""


def prepare_scene(scene: PackingScene, progress: Optional[Progress] = None) -> Packing:
    """The frictionless packing of `scene` at its target pressure (models/packing/prepare.py), its
    forces from the scene's generated kernels. Deterministic: the same scene gives the same
    packing bit for bit."""
    kernels = load_packing_kernels(scene.resolved_effects)
    return prepare(scene.N, scene.seed, scene.R, scene.k_n, scene.size_ratio,
                   scene.fraction_small, pressure=scene.pressure,
                   pair_forces=frictionless_forces(kernels, scene.k_n),
                   f_tol=F_TOL * scene.pressure * 2.0 * scene.R, progress=progress)


def contact_number(packing: Packing) -> tuple[int, float]:
    """(the number of contacts, z = 2 x the contacts between non-rattlers / the non-rattlers):
    the mean contact number of the rigid part, isostatic at 4 for frictionless disks."""
    i, j = contacts(packing.positions, packing.radii, packing.L)
    loose = packing.rattlers
    kept = int(((~loose[i]) & (~loose[j])).sum())
    return len(i), 2 * kept / max(1, int((~loose).sum()))
