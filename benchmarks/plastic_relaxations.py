"""The relaxations after plastic events (models/packing/plastic.py): a packing is sheared
(window LO:HI, as `bifurcate --window`, scans inline) until it has passed EVENTS plastic events,
and the state at each fold is relaxed again here with each rule:
- "fire": FIRE with plastic.time_step (dt_max from the state's ||J||_inf, the default);
- "fire dt0": FIRE with prepare.first_time_step, the preparation's dt0 (an earlier rule, for comparison);
- "damped D" for each D of --damping: Newtonian dynamics with the drag D omega_0
  (plastic.damped, the scene's relaxation = "damped").
Prints per fold the strain, then per rule the steps, seconds ("failed": the relaxation raised
RelaxationFailed), the relative drop of sigma_xy from the fold state to the relaxed one, and,
for every rule after the first, the mass-free distance |q - q_fire| of its relaxed state from
FIRE's; then the totals and microseconds per step. Every rule starts from the same fold state.

Run: python benchmarks/plastic_relaxations.py [N:SEED:EVENTS[:LO:HI]] [--damping 0.1,2]
     (default 256:1:8:-3:8)
"""
from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

from diskfriction.models.packing import plastic
from diskfriction.models.packing.equilibria import mass_diagonal
from diskfriction.models.packing.prepare import first_time_step
from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.shear import ShearParams, network_of, shear
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


def relaxed(network, state, f_tol: float, mass, eta):
    """(q, steps, seconds, stress drop) of past_fold from the fold state by FIRE (eta None) or
    by the damped dynamics with drag rate eta; q None where it raised RelaxationFailed (steps:
    all it was allowed, plastic.ATTEMPTS FIRE runs or one damped run of plastic.MAX_STEPS)."""
    start = time.perf_counter()
    try:
        q, xi, rows, gamma, steps = plastic.past_fold(network, *state, f_tol, mass, eta)
        drop = 1.0 - network.stress(q, xi, rows, gamma)[2] / network.stress(*state)[2]
        return q, steps, time.perf_counter() - start, drop
    except plastic.RelaxationFailed:
        allowed = plastic.MAX_STEPS * (plastic.ATTEMPTS if eta is None else 1)
        return None, allowed, time.perf_counter() - start, float("nan")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("case", nargs="?", default="256:1:8:-3:8")
    parser.add_argument("--damping", default="0.1,2", help="the damped rules' D, comma-separated")
    args = parser.parse_args()
    N, seed, events, window = read_case(parser, args.case, "EVENTS", int)
    try:
        dampings = [float(d) for d in args.damping.split(",")]
        scene = PackingScene(N=N, seed=seed, gamma_range=(0.0, 1.0), spectra="full")
        for d in dampings:
            replace(scene, relaxation="damped", damping=d)
    except (ValueError, SceneValueError) as error:
        parser.error(f"--damping {args.damping}: {error}")
    network, folds = fold_states(scene, events, window)
    if not folds:
        raise SystemExit(f"{N} disks, seed {seed}: the shear passed no plastic event, no fold to relax")
    f_tol = ShearParams().newton_tol
    mass = mass_diagonal(network, scene.m, scene.inertia)
    state_rule = plastic.time_step
    dt0 = lambda net, q, xi, rows, gamma: first_time_step(net.constants[1], net.constants[0])  # noqa: E731
    rules = {"fire": (state_rule, None), "fire dt0": (dt0, None),
             **{f"damped {d:g}": (state_rule, d * scene.omega_0) for d in dampings}}
    relaxed(network, folds[0], f_tol, mass, None)  # kernels compiled or loaded
    relaxed(network, folds[0], f_tol, mass, rules[f"damped {dampings[0]:g}"][1])
    print(f"{N} disks, seed {seed}, window {window}: {len(folds)} folds; omega_0 = {scene.omega_0:.4g}")
    print(f"{'gamma':>12} " + " ".join(f"{name + ' steps':>16} {'s':>6} {'drop':>7} {'|dq|':>8}"
                                       for name in rules))
    totals = {name: [0, 0.0] for name in rules}
    for state in folds:
        cells, reference = [], None
        for name, (rule, eta) in rules.items():
            plastic.time_step = rule
            q, steps, seconds, drop = relaxed(network, state, f_tol, mass, eta)
            reference = q if reference is None else reference
            totals[name][0] += steps
            totals[name][1] += seconds
            far = "-" if q is None or reference is None or q is reference else f"{np.linalg.norm(q - reference):.2e}"
            cells.append(f"{steps if q is not None else 'failed':>16} {seconds:>6.2f} {drop:>7.2%} {far:>8}")
        print(f"{state[3]:>12.6e} " + " ".join(cells))
    plastic.time_step = state_rule
    for name, (steps, seconds) in totals.items():
        print(f"{name}: {steps} steps in {seconds:.2f} s, {seconds / steps * 1e6:.1f} us a step")


if __name__ == "__main__":
    main()
