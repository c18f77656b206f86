# Assembly source of the chain's generated kernel module (see codegen.py), rendered by
# symbolic/template.py: each "...  # @fragment NAME" line becomes the per-contact code the dynamics
# stepper pastes too, for the scene's conventions.
# Not importable on its own: math, numba, np, D, coulomb_limit, two_diff, pair_overlap,
# commit_history (symbolic/contact_src.py), pair_contact, pair_force,
# pair_increment_coeffs, wall_contact, wall_force, wall_increment_coeffs, PAIR_FRICTION,
# WALL_FRICTION and CONVENTIONS are defined by the generated part above it.
#
# Every function uses error_model="numpy" (no zero-division checks: a fifth of a dynamics step
# at N = 10): each division is by a quantity kept positive (2R + rho, delta > 0, k_t).
#
# Layout (docs/model.md#history): q = (x_1..x_N, y_1..y_N[, theta_1..theta_N]); dof (c, i) -> c * N + i.
# History xi has 2N entries: pairs k = 0..N-1 (disk k with disk k+1, the last one with disk 0
# across the periodic boundary), then substrate contacts k = 0..N-1. Entries of a frictionless
# contact kind stay 0. params = (R, k_n, k_t, mu, F_y, L).


@numba.njit(cache=True, error_model="numpy")
def pair_dofs(k, N, idx):
    """Local dofs of pair k: disk i = k then disk j = k + 1 (mod N). Returns j."""
    j = k + 1 if k + 1 < N else 0
    for c in range(D):
        idx[c] = c * N + k
        idx[D + c] = c * N + j
    return j


@numba.njit(cache=True, error_model="numpy")
def pair_separation(q, k, N, L):
    """r_i - r_j of pair k (the last pair sees disk 0 shifted by the ring length L) and the
    rounding errors of its two components: (dx, dy, ex, ey) with r_i - r_j = (dx + ex, dy + ey)."""
    j = k + 1 if k + 1 < N else 0
    dx, ex = two_diff(q[k], q[j])
    if j == 0:
        dx, e = two_diff(dx, L)
        ex += e
    dy, ey = two_diff(q[N + k], q[N + j])
    return dx, dy, ex, ey


@numba.njit(cache=True, error_model="numpy")
def wall_dofs(k, N, idx):
    for c in range(D):
        idx[c] = c * N + k


@numba.njit(cache=True, error_model="numpy")
def jacobian_pattern(N):
    """Row and column of every stored value of J (pair blocks, then substrate blocks)."""
    nnz = N * (2 * D) ** 2 + N * D * D
    rows = np.empty(nnz, np.int64)
    cols = np.empty(nnz, np.int64)
    idx = np.empty(2 * D, np.int64)
    pos = 0
    for k in range(N):
        pair_dofs(k, N, idx)
        for a in range(2 * D):
            for b in range(2 * D):
                rows[pos] = idx[a]
                cols[pos] = idx[b]
                pos += 1
    for k in range(N):
        wall_dofs(k, N, idx)
        for a in range(D):
            for b in range(D):
                rows[pos] = idx[a]
                cols[pos] = idx[b]
                pos += 1
    return rows, cols


@numba.njit(cache=True, error_model="numpy")
def add_loads(F, F_x, F_y, N):
    """External dead loads: F_x on disk 1 along +x, F_y on every disk along -y."""
    F[0] += F_x
    for i in range(N):
        F[N + i] -= F_y


@numba.njit(cache=True, error_model="numpy")
def evaluate(q, xi, F_x, params, F, Jvals):
    """F(q, xi; F_x) [force, torque] and the values of J = -dF/dq (total, history following q)
    in the order of jacobian_pattern [force / length]. Returns the number of active contacts."""
    N = q.shape[0] // D
    R, k_n, k_t, mu, F_y, L = params[0], params[1], params[2], params[3], params[4], params[5]
    F[:] = 0.0
    f = np.empty(2 * D)
    Jb = np.empty((2 * D, 2 * D))
    idx = np.empty(2 * D, np.int64)
    pos = 0
    active = 0
    for k in range(N):
        dx, dy, ex, ey = pair_separation(q, k, N, L)
        delta = pair_overlap(dx, dy, ex, ey, R)
        active += pair_contact(dx, dy, delta, xi[k], R, k_n, k_t, mu, f, Jb)
        pair_dofs(k, N, idx)
        for a in range(2 * D):
            F[idx[a]] += f[a]
            for b in range(2 * D):
                Jvals[pos] = Jb[a, b]
                pos += 1
    for k in range(N):
        active += wall_contact(R - q[N + k], xi[N + k], R, k_n, k_t, mu, f, Jb)
        wall_dofs(k, N, idx)
        for a in range(D):
            F[idx[a]] += f[a]
            for b in range(D):
                Jvals[pos] = Jb[a, b]
                pos += 1
    add_loads(F, F_x, F_y, N)
    return active


@numba.njit(cache=True, error_model="numpy")
def evaluate_dense(q, xi, F_x, params, F, J, Jvals, rows, cols):
    """As evaluate, with J scattered into the dense matrix J (3N x 3N or 2N x 2N)."""
    active = evaluate(q, xi, F_x, params, F, Jvals)
    J[:, :] = 0.0
    for p in range(Jvals.shape[0]):
        J[rows[p], cols[p]] += Jvals[p]
    return active


@numba.njit(cache=True, error_model="numpy")
def forces(q, xi, F_x, params, F):
    """F(q, xi; F_x) only: the dynamics' hot path."""
    N = q.shape[0] // D
    R, k_n, k_t, mu, F_y, L = params[0], params[1], params[2], params[3], params[4], params[5]
    F[:] = 0.0
    f = np.empty(2 * D)
    idx = np.empty(2 * D, np.int64)
    for k in range(N):
        dx, dy, ex, ey = pair_separation(q, k, N, L)
        delta_k = pair_overlap(dx, dy, ex, ey, R)
        xi_k = xi[k]
        if delta_k > 0.0:
            ...  # @fragment pair_force
    for k in range(N):
        delta_k = R - q[N + k]
        xi_k = xi[N + k]
        if delta_k > 0.0:
            ...  # @fragment wall_force
    add_loads(F, F_x, F_y, N)


@numba.njit(cache=True, error_model="numpy")
def overlaps(q, params, delta):
    """delta of every contact [length]: pairs 2R - |r_ij|, then substrate R - y_i."""
    N = q.shape[0] // D
    R, L = params[0], params[5]
    for k in range(N):
        dx, dy, ex, ey = pair_separation(q, k, N, L)
        delta[k] = pair_overlap(dx, dy, ex, ey, R)
        delta[N + k] = R - q[N + k]


@numba.njit(cache=True, error_model="numpy")
def history_increment(q0, q1, params, dxi):
    """Delta xi along the straight step q0 -> q1: w . (q1 - q0) [length], the pair tangent
    taken at the middle of the step (conventions "model": the exact path integral differs by
    O(|q1 - q0|^3)) or at its end ("lammps", first order); symbolic/template.py."""
    N = q0.shape[0] // D
    R, L = params[0], params[5]
    w = np.empty(2 * D)
    idx = np.empty(2 * D, np.int64)
    dq = q1 - q0
    dxi[:] = 0.0
    for k in range(N):
        if PAIR_FRICTION:
            dx0, dy0, _, _ = pair_separation(q0, k, N, L)
            dx, dy, _, _ = pair_separation(q1, k, N, L)
            ...  # @fragment pair_increment
        if WALL_FRICTION:
            ...  # @fragment wall_increment


def ring_of_two():
    """(params, q) of a 2-disk ring slightly pressed into the substrate: a state to warm up on."""
    params = np.array([0.5, 2000.0, 4000.0 / 7.0, 10.0, 0.1, 2.0])  # (R, k_n, k_t, mu, F_y, L)
    q = np.zeros(2 * D)
    q[:2] = (0.5, 1.5)
    q[2:4] = 0.499
    return params, q


def warm_up(progress=None):
    """Call each compiled entry point of System once, on a 2-disk ring, with the argument types
    System passes (C-contiguous float64 arrays, a float load, the int64 pattern, a bool cap; the
    law functions on a float and on an array of delta, as System and the continuation call them):
    numba compiles each now, or loads it from its cache (symbolic/generated.py checks that this
    succeeds). progress(fraction) after each call."""
    N, n = 2, 2 * D
    params, q0 = ring_of_two()
    q1 = q0 + 1e-4
    F, J, xi, slid = np.empty(n), np.empty((n, n)), np.zeros(2 * N), np.empty(2 * N, np.bool_)
    delta0, delta1, dxi, xi1 = np.empty(2 * N), np.empty(2 * N), np.empty(2 * N), np.empty(2 * N)
    rows, cols = jacobian_pattern(N)
    Jvals = np.empty(rows.size)
    k_n, k_t, mu = params[1], params[2], params[3]
    calls = [lambda: forces(q0, xi, 0.0, params, F),
             lambda: evaluate(q0, xi, 0.0, params, F, Jvals),
             lambda: evaluate_dense(q0, xi, 0.0, params, F, J, Jvals, rows, cols),
             lambda: overlaps(q0, params, delta0),
             lambda: overlaps(q1, params, delta1),
             lambda: normal_stiffness(delta1[2], k_n),
             lambda: coulomb_limit(np.maximum(delta1, 0.0), k_n, k_t, mu),
             lambda: history_increment(q0, q1, params, dxi),
             lambda: commit_history(xi, dxi, delta0, delta1, params, True, xi1, slid)]
    for k, call in enumerate(calls):
        call()
        if progress is not None:
            progress((k + 1) / len(calls))
