"""The 24-disk packing the shear tests share (tests/models/packing/: test_packing_shear,
test_packing_equilibria, test_packing_shear_window; its packing and branch are fixtures of that
folder's conftest.py), and its equilibrium problem at gamma = 0."""
from __future__ import annotations

from diskfriction.models.packing.equilibria import PackingEquilibria, mass_diagonal, start
from diskfriction.models.packing.shear import network_of
from diskfriction.scenes.packing import PackingScene

SCENE = PackingScene(N=24, seed=3, gamma_range=(0.0, 0.002))


def problem_at_start(packing, matrix: str = SCENE.matrix) -> PackingEquilibria:
    network = network_of(SCENE, packing)
    q, xi, rows = start(network, packing.positions)
    return PackingEquilibria(network, q, xi, rows, 0.0,
                             mass_diagonal(network, SCENE.m, SCENE.inertia), matrix)
