"""Random admissible states of small chains and the Jacobian error against the 50-digit
reference: shared by tests/symbolic/test_symbolic.py and benchmarks/jacobian_accuracy.py."""
from __future__ import annotations

import itertools

import mpmath as mp
import numpy as np

import reference_model as ref
from diskfriction.scenes import Effects
from diskfriction.symbolic import load_kernels

XI_RATIOS = (0.0, 1e-8, 0.5, 1.0 - 1e-8)
"""|xi| / t* values every test visits, besides uniformly random ones."""

TINY_DELTA = 1e-10

PARAMS = dict(R=0.5, k_n=2000.0, k_t=2000.0 * 2 / 7, mu=10.0, F_y=0.1)

N = 3


def all_effects() -> list[Effects]:
    """Every distinct effect combination (with tangential "none" the friction switches are moot),
    and the "lammps" conventions with pair friction (where they act: the lever arm with
    rotation, the increment's tangent with or without)."""
    combos = [Effects(law, pf, wf, rot) for law in ("mindlin-smooth", "mindlin-linear")
              for pf, wf, rot in itertools.product((True, False), repeat=3)]
    lammps = [Effects(law, True, True, rot, "lammps")
              for law, rot in (("mindlin-smooth", True), ("mindlin-linear", True),
                               ("mindlin-linear", False))]
    hooke = [Effects(law, normal="hooke") for law in ("mindlin-smooth", "mindlin-linear")]
    return combos + lammps + hooke + [Effects("none", False, False, rot) for rot in (True, False)]


def effects_id(e: Effects) -> str:
    fr = "+".join(n for n, on in (("pair", e.pair_friction), ("wall", e.wall_friction)) if on)
    conventions = "" if e.conventions == "model" else f"-{e.conventions}"
    normal = "" if e.normal == "hertz" else f"-{e.normal}"
    return (f"{e.tangential}[{fr or 'nofric'}]{'-rot' if e.rotation else '-norot'}{conventions}"
            f"{normal}")


def reference(effects: Effects, N: int, L: float, exact: bool = False) -> ref.Ref:
    """The reference model of the chain; exact: its parameters as mpf (the same values: floats
    convert exactly, and every operation has an mpf operand), converted once instead of at
    each operation (a sixth of the finite differences' time)."""
    params = {**PARAMS, "L": L}
    if exact:
        params = {k: mp.mpf(v) for k, v in params.items()}
    return ref.Ref(N=N, pair_law=effects.pair_law, wall_law=effects.wall_law,
                   rotation=effects.rotation, conventions=effects.contact_conventions,
                   normal=effects.normal, **params)


def random_state(rng: np.random.Generator, N: int, rotation: bool, case: int,
                 normal: str = "hertz"):
    """(q, xi, L) of an N-disk chain with random overlaps in [1e-4, 1e-2], histories in units
    of the Coulomb limit t* of the normal law `normal`.

    `case` cycles through the hard cases: every 2nd state has one contact at delta ~ 1e-10,
    every 5th has one pair open (delta < 0); the histories cycle through XI_RATIOS and random
    values of |xi| / t*, with random signs.
    """
    R = PARAMS["R"]
    delta_w = rng.uniform(1e-4, 1e-2, N)
    delta_p = rng.uniform(1e-4, 1e-2, N)
    if case % 2 == 0:
        (delta_p if case % 4 == 0 else delta_w)[rng.integers(N)] = TINY_DELTA
    if case % 5 == 0:
        delta_p[rng.integers(N)] = -1e-3
    y = R - delta_w
    x = np.empty(N)
    x[0] = R + rng.uniform(-0.2, 0.2)
    for k in range(N - 1):
        x[k + 1] = x[k] + np.sqrt((2 * R - delta_p[k]) ** 2 - (y[k] - y[k + 1]) ** 2)
    L = x[-1] - x[0] + np.sqrt((2 * R - delta_p[-1]) ** 2 - (y[-1] - y[0]) ** 2)
    q = np.concatenate([x, y] + ([rng.uniform(-1, 1, N)] if rotation else []))
    m = ref.Ref(N=N, L=L, pair_law="none", wall_law="none", rotation=rotation, **PARAMS)
    delta = np.array([float(d) for d in ref.overlaps(m, q)])
    ratios = np.where(np.arange(2 * N) % 2 == 0,
                      np.resize(XI_RATIOS, 2 * N)[np.roll(np.arange(2 * N), case)],
                      rng.uniform(0, 1, 2 * N))
    t_star = np.array([float(ref.coulomb_limit(normal, PARAMS["k_n"], PARAMS["k_t"], PARAMS["mu"],
                                               mp.mpf(d))) if d > 0 else 0.0 for d in delta])
    xi = rng.choice((-1.0, 1.0), 2 * N) * ratios * t_star
    return q, xi, L


def row_relative_error(J: np.ndarray, J_ref: np.ndarray) -> float:
    """max over rows of max|J - J_ref| / max|J_ref|; zero reference rows must match exactly."""
    scale = np.abs(J_ref).max(axis=1)
    diff = np.abs(J - J_ref).max(axis=1)
    if np.any(diff[scale == 0] != 0):
        return np.inf
    return float(np.max(diff[scale > 0] / scale[scale > 0], initial=0.0))


def generated(kernels, q, xi, L):
    """F, dense J and the stored block values from the generated kernels."""
    n = q.size
    params = np.array([PARAMS["R"], PARAMS["k_n"], PARAMS["k_t"], PARAMS["mu"], PARAMS["F_y"], L])
    rows, cols = kernels.jacobian_pattern(N)
    F, J, vals = np.empty(n), np.empty((n, n)), np.empty(rows.size)
    kernels.evaluate_dense(q, xi, 0.0, params, F, J, vals, rows, cols)
    return F, J, vals, rows, cols


def contact_blocks(vals, rows, cols, n, D):
    """Dense matrix of each contact's stored block: [("pair", k) ..., ("wall", k) ...]."""
    out, pos = {}, 0
    for kind, size in (("pair", (2 * D) ** 2), ("wall", D * D)):
        for k in range(N):
            J = np.zeros((n, n))
            np.add.at(J, (rows[pos:pos + size], cols[pos:pos + size]), vals[pos:pos + size])
            out[(kind, k)] = J
            pos += size
    return out


def to_array(M) -> np.ndarray:
    return np.array([[float(v) for v in row] for row in M])


def worst_errors(effects: Effects, states: int, seed: int = 20200124) -> dict[str, float]:
    """Worst row-relative error of the generated J against the 50-digit reference over
    `states` random states: per contact block ("contact"), assembled ("assembled"), and per
    contact block restricted to contacts at delta ~ 1e-10 ("tiny", and how many: "tiny_contacts").

    Reference: central differences of reference_model's forces in 50-digit arithmetic with xi
    following q (midpoint increments), step h = 1e-8 min(delta > 0); see tests/symbolic/test_symbolic.py."""
    kernels = load_kernels(effects)
    rng = np.random.default_rng(seed)
    worst = {"assembled": 0.0, "contact": 0.0, "tiny": 0.0, "tiny_contacts": 0}
    for case in range(states):
        q, xi, L = random_state(rng, N, effects.rotation, case, effects.normal)
        m = reference(effects, N, L, exact=True)
        delta = np.array([float(d) for d in ref.overlaps(m, q)])
        h = mp.mpf(1e-8) * mp.mpf(delta[delta > 0].min())
        F, J, vals, rows, cols = generated(kernels, q, xi, L)
        states = ref.displaced_states(m, q, xi, h)  # shared by the assembled and contact matrices
        worst["assembled"] = max(worst["assembled"], row_relative_error(
            J, to_array(ref.stiffness_fd(m, q, xi, h, states=states))))
        for contact, J_c in contact_blocks(vals, rows, cols, q.size, kernels.D).items():
            err = row_relative_error(J_c, to_array(ref.stiffness_fd(m, q, xi, h, contacts={contact},
                                                                    states=states)))
            worst["contact"] = max(worst["contact"], err)
            index = contact[1] + (0 if contact[0] == "pair" else N)
            if abs(delta[index] - TINY_DELTA) < 1e-12:
                worst["tiny"] = max(worst["tiny"], err)
                worst["tiny_contacts"] += 1
    return worst
