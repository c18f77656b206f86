"""Session fixtures: computations that several test modules check, done once per session; and
the tiers: `-m "not slow and not subprocess"` is the fast tier (README, Tests)."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest


@pytest.fixture(scope="session")
def sheared():
    """sheared(scene) -> (packing, branch, ends): prepare_scene(scene) and its shear with
    ShearParams(workers=0), once per session and scene (test_packing_shear and
    test_packing_dynamics shear the same 24-disk packing: 3-4 s each time). `ends`: for every
    step cut at an event, the strain between the step's end and the crossed event function's
    zero (|g| over its mean slope across the step), recorded by wrapping
    PackingEquilibria.commit; the wrapper only evaluates the event functions, and the branch is
    a plain run's bit for bit. Read them, never change them."""
    from diskfriction.models.packing import equilibria
    from diskfriction.models.packing.prepared import prepare_scene
    from diskfriction.models.packing.shear import ShearParams, shear

    done = {}

    def run(scene):
        if scene not in done:
            packing = prepare_scene(scene)
            ends = []
            commit = equilibria.PackingEquilibria.commit

            def recording(self, q_old, g_old, q_new, g_new):
                before = self.event_functions(q_old, g_old)
                after = self.event_functions(q_new, g_new)
                crossed = ((before > 0) & (after <= 0)) | ((before < 0) & (after > 0))
                if crossed.any():
                    slope = np.abs(after[crossed] - before[crossed]) / abs(g_new - g_old)
                    ends.append(float(np.min(np.abs(after[crossed]) / slope)))
                return commit(self, q_old, g_old, q_new, g_new)

            equilibria.PackingEquilibria.commit = recording
            try:
                branch = shear(scene, packing, ShearParams(workers=0))
            finally:
                equilibria.PackingEquilibria.commit = commit
            done[scene] = packing, branch, ends
        return done[scene]

    return run


@pytest.fixture(scope="session")
def chain_sweep():
    """chain_sweep(scene, matrix=None, F_from=0.0, F_to=0.12, params=None) -> (branch, spectra):
    sweep(System.from_scene(scene), F_from, F_to, matrix, params) and the full spectra it took
    (linalg.measured), once per session and arguments: the paper's sweep of J alone was run by
    six tests in five modules (0.3 s each; N = 20 and 40 ones up to 1.5 s). Its arrays are
    made read-only, so that a test changing a shared branch fails instead of passing on others."""
    from diskfriction.continuation.linalg.solves import measured
    from diskfriction.models.chain.sweep import SweepParams, sweep
    from diskfriction.matrices import Matrix
    from diskfriction.symbolic import System

    done = {}

    def run(scene, matrix=None, F_from=0.0, F_to=0.12, params=None):
        params = SweepParams() if params is None else params
        key = (scene, str(Matrix(matrix or scene.matrix)), F_from, F_to, params)
        if key not in done:
            with measured() as work:
                branch = sweep(System.from_scene(scene), F_from, F_to, key[1], params)
            for field in dataclasses.fields(branch):
                value = getattr(branch, field.name)
                if isinstance(value, np.ndarray):
                    value.flags.writeable = False
            done[key] = branch, work.spectra
        return done[key]

    return run


FRESH_INTERPRETER = {"run_cli", "subprocess"}
"""Names a test function calls to run in a fresh interpreter: commandline.run_cli (the
diskfriction command) or the subprocess module."""


def pytest_collection_modifyitems(config, items):
    """Mark `subprocess` every test whose function calls a FRESH_INTERPRETER name directly (its
    code's global names): a second or more of start-up each, left out of the fast tier."""
    for item in items:
        function = getattr(item, "function", None)
        if function is not None and FRESH_INTERPRETER & set(function.__code__.co_names):
            item.add_marker(pytest.mark.subprocess)
