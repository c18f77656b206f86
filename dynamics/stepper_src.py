# Stepper source appended to a generated header (see dynamics/stepper.py), rendered by
# symbolic/template.py: each "...  # @fragment NAME" line becomes the per-contact code the kernel
# module's forces, history_increment and commit_history are made of, for the scene's
# conventions. Not importable on its own: numba, np, D, PAIR_FRICTION, WALL_FRICTION and the kernel module's
# pair_separation, pair_overlap, pair_force, pair_increment_coeffs, pair_dofs, wall_force,
# wall_increment_coeffs, wall_dofs, add_loads, commit_history, normal_energy and ring_of_two are
# bound by the header.
#
# One velocity-Verlet step (dynamics/stepper.py explains the scheme), for the layout of
# docs/model.md#history: q = (x, y[, theta]) blocks of N, contacts c = pairs 0..N-1 then substrate N..2N-1.
#
#   kick   v += dt/2 M^-1 F(q0, xi0)
#   drift  q1 = q0 + dt v
#   commit dxi = w . (q1 - q0) (midpoint tangent; end-of-step with conventions "lammps"),
#          xi1 = commit_history(xi0, dxi, ...): reset on opening, first contact, Coulomb cap
#          (the quasistatic rule, cap on)
#   force  F(q1, xi1) and the scalar tangential force f_t of every contact
#   kick   v += dt/2 M^-1 F(q1, xi1)
#
# The tangential work of the step is sum_c (f_t0 + f_t1)/2 dxi_c (trapezoid in time, midpoint
# increment; with the "lammps" lever arm the torques' extra path (delta/2)(dtheta_i + dtheta_j)
# is added to dxi_c, symbolic/template.py). Of it, the part done on the distance a capped contact slid, xi0 + dxi - xi1, is
# booked as dissipated, with the force at the end of the step, where the cap acts:
# f_t1 = -mu F_n sign(xi1) there, so every booked term is <= 0. (The trapezoid force would
# give a term of the wrong sign when the history reverses within one step near an opening.)
#
# scal layout (float64): 0 t, 1 tangential work W_t, 2 of which dissipated at caps W_slip.
# ints layout (int64):   0 steps done, 1 frames written.

SCAL_T, SCAL_W_T, SCAL_W_SLIP = 0, 1, 2
INT_STEP, INT_FRAME = 0, 1
E_KIN, E_NORMAL, E_LOAD, E_W_T, E_W_SLIP = 0, 1, 2, 3, 4


@numba.njit(cache=True, error_model="numpy")
def record(q, v, mass, delta, F_x, params, scal, slip, frame, t, frames_q, frames_v, energy,
           frames_slip):
    """Frame `frame`: time, q, v, the substrate slip of every disk, and the energy budget
    (E_kin, U_n = sum of normal_energy(delta) over active contacts (Hertz: 2/5 k_n delta^(5/2)),
    U_load = -F_x x_1 + F_y sum y_i, W_t, W_slip)."""
    N = q.shape[0] // D
    k_n, F_y = params[1], params[4]
    t[frame] = scal[SCAL_T]
    e_kin = 0.0
    for a in range(q.shape[0]):
        frames_q[frame, a] = q[a]
        frames_v[frame, a] = v[a]
        e_kin += 0.5 * mass[a] * v[a] * v[a]
    u_n = 0.0
    for c in range(2 * N):
        if delta[c] > 0.0:
            u_n += normal_energy(delta[c], k_n)
    u_load = -F_x * q[0]
    for i in range(N):
        u_load += F_y * q[N + i]
        frames_slip[frame, i] = slip[i]
    energy[frame, E_KIN] = e_kin
    energy[frame, E_NORMAL] = u_n
    energy[frame, E_LOAD] = u_load
    energy[frame, E_W_T] = scal[SCAL_W_T]
    energy[frame, E_W_SLIP] = scal[SCAL_W_SLIP]


@numba.njit(cache=True, error_model="numpy")
def advance(q, v, xi, mass, F_x, params, dt, n_steps, stride, scal, ints, slip, breach_t,
            breach_x, t, frames_q, frames_v, energy, frames_slip):
    """n_steps velocity-Verlet steps of the state (q, v, xi), in place.

    Iteration 0 moves nothing: it evaluates the overlaps, separations, forces and tangential
    forces of the current state (with the same code as every step's end), so the state carries
    only (q, v, xi) between calls and a run split into calls is bit-identical to one call.
    Frame 0 is written by the first call; then every `stride`-th step (counted in
    ints[INT_STEP]) is written to frame ints[INT_FRAME]. breach_t[i] < 0 until the substrate
    contact of disk i is first capped; then breach_t, breach_x hold that time and x_i.
    slip[i] accumulates xi0 + dxi - xi1 of the substrate contact over its capped steps (the
    signed distance slid) [length]. Time is dt * (steps done). Returns the frames written.

    One function on purpose: helpers taking arrays, inlined or called, cost numba reference
    counting (atomic increments) on every call, a quarter of the step at N = 10."""
    n = q.shape[0]
    N = n // D
    R, k_n, k_t, mu, F_y, L = params[0], params[1], params[2], params[3], params[4], params[5]
    half = 0.5 * dt
    w = np.empty(2 * D)
    f = np.empty(2 * D)
    idx = np.empty(2 * D, np.int64)
    F = np.empty(n)
    dq = np.zeros(n)
    q1 = np.empty(n)
    sep = np.empty((2, N))
    xi1 = np.empty(2 * N)
    delta = np.empty(2 * N)
    delta1 = np.empty(2 * N)
    ft = np.empty(2 * N)
    ft1 = np.empty(2 * N)
    dxi = np.empty(2 * N)
    slid = np.zeros(2 * N, np.bool_)
    ...  # @fragment arm_path_array
    minv = 1.0 / mass
    countdown = stride - ints[INT_STEP] % stride
    for it in range(n_steps + 1):
        moving = it > 0
        # kick, drift
        for a in range(n):
            if moving:
                v[a] += half * F[a] * minv[a]
                q1[a] = q[a] + dt * v[a]
                dq[a] = q1[a] - q[a]
            else:
                q1[a] = q[a]
        # overlaps at q1, increments over q -> q1 (the kernel module's overlaps and
        # history_increment: the same fragments)
        for k in range(N):
            dx, dy, ex, ey = pair_separation(q1, k, N, L)
            delta1[k] = pair_overlap(dx, dy, ex, ey, R)
            dxi[k] = 0.0
            if PAIR_FRICTION and moving:
                dx0 = sep[0, k]
                dy0 = sep[1, k]
                ...  # @fragment pair_increment
                ...  # @fragment pair_arm_path
            sep[0, k] = dx
            sep[1, k] = dy
            dxi[N + k] = 0.0
            if WALL_FRICTION and moving:
                ...  # @fragment wall_increment
            delta1[N + k] = R - q1[N + k]
        # the history rule: reset on opening, first contact, Coulomb cap
        if moving:
            commit_history(xi, dxi, delta, delta1, params, True, xi1, slid)
        else:
            for c in range(2 * N):
                xi1[c] = xi[c]
        # forces F(q1, xi1; F_x) (the kernel module's `forces`) and the scalar tangential
        # force of every contact: on the first disk of a pair along s = z x n, on a disk from
        # the substrate along +x
        for a in range(n):
            F[a] = 0.0
        for k in range(N):
            ft1[k] = 0.0
            delta_k = delta1[k]
            if delta_k > 0.0:
                dx = sep[0, k]
                dy = sep[1, k]
                xi_k = xi1[k]
                ...  # @fragment pair_force
                if PAIR_FRICTION:
                    ft1[k] = (f[1] * dx - f[0] * dy) / (2.0 * R - delta_k)
        for k in range(N):
            ft1[N + k] = 0.0
            delta_k = delta1[N + k]
            if delta_k > 0.0:
                xi_k = xi1[N + k]
                ...  # @fragment wall_force
                if WALL_FRICTION:
                    ft1[N + k] = f[0]
        add_loads(F, F_x, F_y, N)
        if moving:
            for a in range(n):
                v[a] += half * F[a] * minv[a]
            ints[INT_STEP] += 1
            time = dt * ints[INT_STEP]
            # tangential work (trapezoid in time over the midpoint increment); the part on
            # the distance slid at a capped contact, with the force where the cap acts
            w_t = 0.0
            w_slip = 0.0
            for c in range(2 * N):
                ...  # @fragment tangential_work
                if slid[c]:
                    # a contact closing and capped in one step slid < |dxi|: not booked
                    s = xi[c] + dxi[c] - xi1[c] if delta[c] > 0.0 else 0.0
                    w_slip += ft1[c] * s
                    if c >= N:
                        slip[c - N] += s
                        if breach_t[c - N] < 0.0:
                            breach_t[c - N] = time
                            breach_x[c - N] = q1[c - N]
            scal[SCAL_W_T] += w_t
            scal[SCAL_W_SLIP] += w_slip
            scal[SCAL_T] = time
        for a in range(n):
            q[a] = q1[a]
        for c in range(2 * N):
            xi[c] = xi1[c]
            delta[c] = delta1[c]
            ft[c] = ft1[c]
        if moving:
            countdown -= 1
        if (moving and countdown == 0) or ints[INT_FRAME] == 0:
            record(q, v, mass, delta, F_x, params, scal, slip, ints[INT_FRAME], t, frames_q,
                   frames_v, energy, frames_slip)
            ints[INT_FRAME] += 1
            if moving:
                countdown = stride
    return ints[INT_FRAME]


def warm_up(progress=None):
    """Call advance once (no step: frame 0 only) on a 2-disk ring with the argument types
    Stepper passes, so that numba compiles it now or loads it from its cache
    (symbolic/generated.py checks that this succeeds). progress(1.0) when done."""
    N, n = 2, 2 * D
    params, q = ring_of_two()
    advance(q, np.zeros(n), np.zeros(2 * N), np.ones(n), 0.0, params, 1e-3, 0, 1, np.zeros(3),
            np.zeros(2, np.int64), np.zeros(N), np.full(N, -1.0), np.full(N, np.nan),
            np.empty(1), np.empty((1, n)), np.empty((1, n)), np.empty((1, 5)), np.empty((1, N)))
    if progress is not None:
        progress(1.0)
