"""The disk chain of Charan et al. (PRL 124, 030602) through the public API, as `bifurcate` runs it.

The chain is a Problem subclass (models/chain/equilibria.py) that carries the contacts' tangential
history in its commit hook; the branch starts at F_1 = 1e-4 F_y, reached from rest by
relaxation (models/chain/sweep.py explains why F_x = 0 itself is singular).

    diskfriction bifurcate --problem examples/disk_chain.py
"""
from diskfriction.continuation import BifurcationProblem, Options
from diskfriction.models.chain.equilibria import DiskEquilibria, relax
from diskfriction.models.chain.sweep import START_FRACTION
from diskfriction.scenes.load import default_scene_path, load_scene
from diskfriction.symbolic import System


def disk_chain(scene_file=default_scene_path(), F_max: float = 0.12) -> BifurcationProblem:
    """The scene's chain loaded from F_1 to F_max, with bifurcate's steps (span / 60)."""
    scene = load_scene(scene_file)
    system = System.from_scene(scene)
    F_1 = START_FRACTION * scene.F_y
    q, xi = relax(system, *system.rest_state(), F_1)
    options = Options(ds_max=F_max / 60, ds=F_1, ds_min=1e-10, newton_tol=1e-11, max_steps=20_000,
                      theta=None, p_scale=1.0, residual_scale=1.0)  # bifurcate's raw units
    return BifurcationProblem(DiskEquilibria(system, q, xi, F_1), u0=q, p_span=(F_1, F_max),
                              parameter="F_x", units="raw force", matrix=scene.matrix, options=options)


problem = disk_chain()
