"""The relaxations after plastic events (issue 25, packings/plastic.py): a packing is sheared
(window LO:HI, as `bifurcate --window`, scans inline) until it has passed EVENTS plastic events,
and the state at each fold is relaxed again here, once with each time-step rule:
"state" (plastic.time_step: dt_max from the state's ||J||_inf, the rule in use) and
"preparation" (prepare.first_time_step, the preparation's dt0, the rule before stop 43).
Prints per fold the strain, the FIRE steps and seconds of each rule ("failed": every one of
plastic.ATTEMPTS runs, the step halved each time, ended away from the tolerance), then the
totals and microseconds per step. Both rules run the same compiled step and the same retries,
so the columns compare the first time step alone.

Run: python benchmarks/plastic_relaxations.py [N:SEED:EVENTS[:LO:HI]]   (default 256:1:8:-3:8)
"""
from __future__ import annotations

import argparse
import time

from diskfriction.packings import plastic
from diskfriction.packings.prepare import first_time_step
from diskfriction.packings.prepared import prepare_scene
from diskfriction.packings.shear import ShearParams, network_of, shear
from diskfriction.scenes.packing import PackingScene
from diskfriction.scenes.scene import SceneValueError
from packing_cases import read_case


def fold_states(scene: PackingScene, events: int, window):
    """(network, [(q, xi, rows, gamma)] at each fold passed): the last point of every segment
    that ended at a plastic event."""
    packing = prepare_scene(scene)
    branch = shear(scene, packing, ShearParams(workers=0), plastic_events=events, window=window)
    network = network_of(scene, packing)
    last = [k for k in range(len(branch) - 1) if branch.segment[k + 1] != branch.segment[k]]
    return network, [(branch.q[k], branch.xi[k], branch.rows[k], branch.gamma[k]) for k in last]


def relaxed(network, state, f_tol: float) -> tuple[int, float, bool]:
    """(FIRE steps, seconds, settled) of past_fold from the fold state (not settled: it raised
    RelaxationFailed after its plastic.ATTEMPTS runs of plastic.MAX_STEPS)."""
    start = time.perf_counter()
    try:
        steps, settled = plastic.past_fold(network, *state, f_tol)[4], True
    except plastic.RelaxationFailed:
        steps, settled = plastic.ATTEMPTS * plastic.MAX_STEPS, False
    return steps, time.perf_counter() - start, settled


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("case", nargs="?", default="256:1:8:-3:8")
    case = parser.parse_args().case
    N, seed, events, window = read_case(parser, case, "EVENTS", int)
    try:
        scene = PackingScene(N=N, seed=seed, gamma_range=(0.0, 1.0))
    except SceneValueError as error:
        parser.error(str(error))
    network, folds = fold_states(scene, events, window)
    if not folds:
        raise SystemExit(f"{N} disks, seed {seed}: the shear passed no plastic event, no fold to relax")
    f_tol = ShearParams().newton_tol
    state_rule = plastic.time_step
    rules = {"state": state_rule,
             "preparation": lambda net, q, xi, rows, gamma: first_time_step(net.constants[1],
                                                                            net.constants[0])}
    relaxed(network, folds[0], f_tol)  # kernels compiled or loaded
    print(f"{N} disks, seed {seed}, window {window}: {len(folds)} folds")
    print(f"{'gamma':>12} " + " ".join(f"{name + ' steps':>18} {'s':>7}" for name in rules))
    totals = {name: [0, 0.0] for name in rules}
    for state in folds:
        cells = []
        for name, rule in rules.items():
            plastic.time_step = rule
            steps, seconds, settled = relaxed(network, state, f_tol)
            totals[name][0] += steps
            totals[name][1] += seconds
            cells.append(f"{steps if settled else 'failed':>18} {seconds:>7.2f}")
        print(f"{state[3]:>12.6e} " + " ".join(cells))
    plastic.time_step = state_rule
    for name, (steps, seconds) in totals.items():
        print(f"{name}: {steps} steps in {seconds:.2f} s, {seconds / steps * 1e6:.1f} us a step")


if __name__ == "__main__":
    main()
