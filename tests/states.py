"""Random admissible states of small chains, shared by the kernel tests and the benchmarks."""
from __future__ import annotations

import itertools

import numpy as np

import reference_model as ref
from scenes import Effects

XI_RATIOS = (0.0, 1e-8, 0.5, 1.0 - 1e-8)
"""|xi| / t* values every test visits, besides uniformly random ones."""

TINY_DELTA = 1e-10

PARAMS = dict(R=0.5, k_n=2000.0, k_t=2000.0 * 2 / 7, mu=10.0, F_y=0.1)


def all_effects() -> list[Effects]:
    """Every distinct effect combination (with tangential "none" the friction switches are moot)."""
    combos = [Effects(law, pf, wf, rot) for law in ("mindlin-smooth", "mindlin-linear")
              for pf, wf, rot in itertools.product((True, False), repeat=3)]
    return combos + [Effects("none", False, False, rot) for rot in (True, False)]


def effects_id(e: Effects) -> str:
    fr = "+".join(n for n, on in (("pair", e.pair_friction), ("wall", e.wall_friction)) if on)
    return f"{e.tangential}[{fr or 'nofric'}]{'-rot' if e.rotation else '-norot'}"


def reference(effects: Effects, N: int, L: float) -> ref.Ref:
    return ref.Ref(N=N, L=L, pair_law=effects.pair_law, wall_law=effects.wall_law,
                   rotation=effects.rotation, **PARAMS)


def random_state(rng: np.random.Generator, N: int, rotation: bool, case: int):
    """(q, xi, L) of an N-disk chain with random overlaps in [1e-4, 1e-2].

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
    t_star = PARAMS["mu"] * PARAMS["k_n"] * np.clip(delta, 0, None) / PARAMS["k_t"]
    xi = rng.choice((-1.0, 1.0), 2 * N) * ratios * t_star
    return q, xi, L
