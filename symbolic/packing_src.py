# Assembly source of a packing's generated kernel module (see codegen.py, kernels.py:
# load_packing_kernels; docs/packings.md). Not importable on its own: math, numba, np, D,
# normal_force, normal_energy, coulomb_limit, grain_contact, grain_force,
# grain_increment_coeffs (the grain-pair kernel), two_diff, pair_overlap and commit_history
# (symbolic/contact_src.py) come from the generated part above it.
#
# Layout: q = (x_1..x_N, y_1..y_N, theta_1..theta_N), unwrapped coordinates; dof (c, i) -> c N + i.
# A contact is a row (i, j, cx, cy) of an int64 array, i < j: disk i touches the image of disk j
# shifted by (cx L + cy gamma L, cy L), the Lees-Edwards image of the square periodic box of
# side L sheared by the strain gamma (a disk leaving through the top comes back at the bottom
# shifted by -gamma L in x). The history xi has one entry per contact, in the same order.
# params = (R, k_n, k_t, mu, 0, L, gamma): R the small radius, params[1:4] as the chain's, L and
# gamma in 5 and 6.


@numba.njit(cache=True, error_model="numpy")
def grain_dofs(i, j, N, idx):
    """Local dofs of a contact: disk i's (x, y, theta), then disk j's."""
    for c in range(D):
        idx[c] = c * N + i
        idx[D + c] = c * N + j


@numba.njit(cache=True, error_model="numpy")
def grain_separation(q, i, j, cx, cy, N, L, gamma):
    """r_i - r_j - (cx L + cy gamma L, cy L) and the rounding errors of its components: (dx, dy,
    ex, ey), r_i - r_j - shift = (dx + ex, dy + ey) to first order."""
    dx, ex = two_diff(q[i], q[j])
    if cx != 0 or cy != 0:
        dx, e = two_diff(dx, cx * L + cy * gamma * L)
        ex += e
    dy, ey = two_diff(q[N + i], q[N + j])
    if cy != 0:
        dy, e = two_diff(dy, cy * L)
        ey += e
    return dx, dy, ex, ey


@numba.njit(cache=True, error_model="numpy")
def nearest_image(q, i, j, N, L, gamma):
    """(cx, cy) of the Lees-Edwards image of disk j nearest disk i: cy = round(dy / L) first,
    then cx = round((dx - cy gamma L) / L)."""
    dy = q[N + i] - q[N + j]
    cy = int(np.rint(dy / L))
    dx = q[i] - q[j] - cy * gamma * L
    return int(np.rint(dx / L)), cy


@numba.njit(cache=True, error_model="numpy")
def _consider(q, radii, i, j, N, L, gamma, reach, found, count):
    """Append (i, j, cx, cy) to `found` if the nearest images overlap by more than -reach."""
    cx, cy = nearest_image(q, i, j, N, L, gamma)
    dx, dy, ex, ey = grain_separation(q, i, j, cx, cy, N, L, gamma)
    if pair_overlap(dx, dy, ex, ey, 0.5 * (radii[i] + radii[j])) > -reach:
        if count == found.shape[0]:
            grown = np.empty((2 * count, 4), np.int64)
            grown[:count] = found
            found = grown
        found[count, 0], found[count, 1], found[count, 2], found[count, 3] = i, j, cx, cy
        count += 1
    return found, count


@numba.njit(cache=True, error_model="numpy")
def near_pairs(q, radii, L, gamma, reach):
    """Every pair i < j whose nearest Lees-Edwards images overlap by delta > -reach [length], as
    contact rows (i, j, cx, cy) sorted by (i, j). A cell list of cells no narrower than
    2 max(R) + reach, the rows across the periodic y boundary searched around the sheared
    column; every pair when the box holds fewer than 3 cells a side. O(N) for a dense packing."""
    N = radii.shape[0]
    cut = 2.0 * radii.max() + reach
    n = int(L // cut)
    found = np.empty((4 * N + 4, 4), np.int64)
    count = 0
    if n < 3:
        for i in range(N):
            for j in range(i + 1, N):
                found, count = _consider(q, radii, i, j, N, L, gamma, reach, found, count)
        return found[:count]
    width = L / n
    col, row = np.empty(N, np.int64), np.empty(N, np.int64)
    head, following = np.full(n * n, -1, np.int64), np.empty(N, np.int64)
    for i in range(N):  # wrap into the box: through y first (shifting x), then x
        k = math.floor(q[N + i] / L)
        x = q[i] - k * gamma * L
        col[i] = min(int((x - math.floor(x / L) * L) / width), n - 1)
        row[i] = min(int((q[N + i] - k * L) / width), n - 1)
        cell = row[i] * n + col[i]
        following[i], head[cell] = head[cell], i
    for i in range(N):
        x_i = q[i] - math.floor(q[N + i] / L) * gamma * L
        for dr in range(-1, 2):
            r = row[i] + dr
            shift = 0.0  # the image rows across the y boundary are sheared by gamma L
            if r < 0:
                r, shift = r + n, gamma * L
            elif r >= n:
                r, shift = r - n, -gamma * L
            c0 = col[i] if shift == 0.0 else int(math.floor(((x_i + shift) % L) / width)) % n
            for dc in range(-1, 2):
                j = head[r * n + (c0 + dc) % n]
                while j >= 0:
                    if j > i:
                        found, count = _consider(q, radii, i, j, N, L, gamma, reach, found, count)
                    j = following[j]
    found = found[:count]
    return found[np.argsort(found[:, 0] * N + found[:, 1], kind="mergesort")]


@numba.njit(cache=True, error_model="numpy")
def overlaps(q, radii, contacts, params, delta):
    """delta = R_i + R_j - |r_ij| of every contact row [length] (negative: open)."""
    N, L, gamma = radii.shape[0], params[5], params[6]
    for c in range(contacts.shape[0]):
        i, j = contacts[c, 0], contacts[c, 1]
        dx, dy, ex, ey = grain_separation(q, i, j, contacts[c, 2], contacts[c, 3], N, L, gamma)
        delta[c] = pair_overlap(dx, dy, ex, ey, 0.5 * (radii[i] + radii[j]))


@numba.njit(cache=True, error_model="numpy")
def jacobian_pattern(N, contacts):
    """Row and column of every stored value of J: a (2D)^2 block per contact row."""
    m = 2 * D
    rows = np.empty(contacts.shape[0] * m * m, np.int64)
    cols = np.empty_like(rows)
    idx = np.empty(m, np.int64)
    pos = 0
    for c in range(contacts.shape[0]):
        grain_dofs(contacts[c, 0], contacts[c, 1], N, idx)
        for a in range(m):
            for b in range(m):
                rows[pos], cols[pos] = idx[a], idx[b]
                pos += 1
    return rows, cols


@numba.njit(cache=True, error_model="numpy")
def evaluate(q, xi, radii, contacts, params, F, Jvals, F_gamma):
    """F(q, xi; gamma) [force, torque], the values of J = -dF/dq (total: the history follows q)
    in the order of jacobian_pattern [force / length], and F_gamma = dF/dgamma (total: the
    image shift of a contact across the y boundary moves with gamma, d dx / dgamma = -cy L,
    and charges its history by s_x d dx) [force]. Returns the number of active contacts."""
    N, m = radii.shape[0], 2 * D
    k_n, k_t, mu, L, gamma = params[1], params[2], params[3], params[5], params[6]
    F[:] = 0.0
    F_gamma[:] = 0.0
    f, Jb, idx = np.empty(m), np.empty((m, m)), np.empty(m, np.int64)
    pos, active = 0, 0
    for c in range(contacts.shape[0]):
        i, j, cy = contacts[c, 0], contacts[c, 1], contacts[c, 3]
        dx, dy, ex, ey = grain_separation(q, i, j, contacts[c, 2], cy, N, L, gamma)
        delta = pair_overlap(dx, dy, ex, ey, 0.5 * (radii[i] + radii[j]))
        active += grain_contact(dx, dy, delta, xi[c], radii[i], radii[j], k_n, k_t, mu, f, Jb)
        grain_dofs(i, j, N, idx)
        for a in range(m):
            F[idx[a]] += f[a]
            F_gamma[idx[a]] += Jb[a, 0] * (cy * L)
            for b in range(m):
                Jvals[pos] = Jb[a, b]
                pos += 1
    return active


@numba.njit(cache=True, error_model="numpy")
def contact_force(q, xi_c, radii, contacts, c, N, params, f):
    """The force kernel of contact row c at q with history xi_c into f (disk i's x, y, theta,
    then disk j's); returns (dx, dy, active): r_i - r_j of the row's image and delta > 0."""
    i, j = contacts[c, 0], contacts[c, 1]
    dx, dy, ex, ey = grain_separation(q, i, j, contacts[c, 2], contacts[c, 3], N, params[5],
                                      params[6])
    delta = pair_overlap(dx, dy, ex, ey, 0.5 * (radii[i] + radii[j]))
    if delta > 0.0:
        grain_force(dx, dy, delta, xi_c, radii[i], radii[j], params[1], params[2], params[3], f)
    return dx, dy, delta > 0.0


@numba.njit(cache=True, error_model="numpy")
def forces(q, xi, radii, contacts, params, F):
    """F(q, xi; gamma) only [force, torque]."""
    N, m = radii.shape[0], 2 * D
    F[:] = 0.0
    f, idx = np.empty(m), np.empty(m, np.int64)
    for c in range(contacts.shape[0]):
        if contact_force(q, xi[c], radii, contacts, c, N, params, f)[2]:
            grain_dofs(contacts[c, 0], contacts[c, 1], N, idx)
            for a in range(m):
                F[idx[a]] += f[a]


@numba.njit(cache=True, error_model="numpy")
def stress(q, xi, radii, contacts, params, sigma):
    """The contact (virial) stress sigma_ab = -(1 / L^2) sum_c r_ij,a f_ij,b over the contacts
    [force / length], f_ij the force on i (so that compression is a negative normal stress, as
    in continuum mechanics): sigma = (sigma_xx, sigma_yy, sigma_xy, sigma_yx); the pressure is
    P = -(sigma_xx + sigma_yy) / 2."""
    N, L = radii.shape[0], params[5]
    f = np.empty(2 * D)
    sigma[:] = 0.0
    for c in range(contacts.shape[0]):
        dx, dy, active = contact_force(q, xi[c], radii, contacts, c, N, params, f)
        if active:
            sigma[0] -= dx * f[0]
            sigma[1] -= dy * f[1]
            sigma[2] -= dx * f[1]
            sigma[3] -= dy * f[0]
    sigma /= L * L


@numba.njit(cache=True, error_model="numpy")
def history_increment(q0, q1, gamma0, gamma1, radii, contacts, params, dxi):
    """Delta xi of every contact along the straight step (q0, gamma0) -> (q1, gamma1) [length]:
    d xi = s . d r_ij - (R_i d theta_i + R_j d theta_j) with d r_ij including the image shift's
    change -cy L d gamma, the tangent s at the middle of the step (as the chain's "model")."""
    N, m, L = radii.shape[0], 2 * D, params[5]
    w, idx = np.empty(m), np.empty(m, np.int64)
    for c in range(contacts.shape[0]):
        i, j, cx, cy = contacts[c, 0], contacts[c, 1], contacts[c, 2], contacts[c, 3]
        dx0, dy0, _, _ = grain_separation(q0, i, j, cx, cy, N, L, gamma0)
        dx1, dy1, _, _ = grain_separation(q1, i, j, cx, cy, N, L, gamma1)
        grain_increment_coeffs(0.5 * (dx0 + dx1), 0.5 * (dy0 + dy1), radii[i], radii[j], w)
        grain_dofs(i, j, N, idx)
        dxi[c] = -w[0] * cy * L * (gamma1 - gamma0)
        for a in range(m):
            dxi[c] += w[a] * (q1[idx[a]] - q0[idx[a]])


@numba.njit(cache=True, error_model="numpy")
def carried_forces(q0, q1, xi0, delta0, radii, contacts, params, F, xi1, delta1):
    """One force evaluation of a relaxation at fixed strain params[6]: the history carried over
    the straight step q0 -> q1 (history_increment, then commit_history with the Coulomb cap)
    from xi0 [length] into xi1, the overlaps at q1 into delta1 (delta0: those at q0) [length],
    and F = F(q1, xi1) [force, torque] into F. One call where history_step and forces take
    five (256 sheared disks, a prototype of it: 37 microseconds against 16.5 + 27.5 for the
    two wrappers)."""
    m, gamma = contacts.shape[0], params[6]
    dxi, slid = np.empty(m), np.empty(m, np.bool_)
    history_increment(q0, q1, gamma, gamma, radii, contacts, params, dxi)
    overlaps(q1, radii, contacts, params, delta1)
    commit_history(xi0, dxi, delta0, delta1, params, True, xi1, slid)
    forces(q1, xi1, radii, contacts, params, F)


@numba.njit(cache=True, error_model="numpy")
def tangential_forces(q, xi, radii, contacts, params, ft):
    """F_t of every contact row, the tangential force along s on disk i [force] (0 if open):
    from the torque the kernel writes on disk i, T_i = -R_i F_t."""
    N = radii.shape[0]
    f = np.empty(2 * D)
    for c in range(contacts.shape[0]):
        active = contact_force(q, xi[c], radii, contacts, c, N, params, f)[2]
        ft[c] = -f[D - 1] / radii[contacts[c, 0]] if active else 0.0


@numba.njit(cache=True, error_model="numpy")
def normal_energy_sum(q, radii, contacts, params):
    """U_n = sum of normal_energy(delta) over the contact rows [energy]."""
    N, L, gamma, k_n = radii.shape[0], params[5], params[6], params[1]
    U = 0.0
    for c in range(contacts.shape[0]):
        i, j = contacts[c, 0], contacts[c, 1]
        dx, dy, ex, ey = grain_separation(q, i, j, contacts[c, 2], contacts[c, 3], N, L, gamma)
        delta = pair_overlap(dx, dy, ex, ey, 0.5 * (radii[i] + radii[j]))
        if delta > 0.0:
            U += normal_energy(delta, k_n)
    return U


@numba.njit(cache=True, error_model="numpy")
def advance(q, v, xi, radii, contacts, params, inv_mass, dt, steps, F, work, damping):
    """`steps` velocity Verlet steps of M q'' = F(q, xi) - damping M q' over fixed contact rows
    (the strain fixed): drag, kick, drift, the history of the drift by the chain's rule
    (midpoint increment, reset on opening, the part after first contact on closing, the
    Coulomb cap), forces, kick, drag. The drag is exact, v *= exp(-damping dt / 2) at either
    end of a step (Strang splitting; damping [1 / time], 0: none, and the Coulomb cap is the only
    dissipation). F holds the forces at q on entry and on return. work[0] gains the trapezoid
    work of the tangential forces on the disks, sum F_t dxi [energy], so that E_k + U_n - work
    is conserved while nothing slides and nothing is damped. Returns the number of capped
    (sliding) contact updates."""
    n, m = q.shape[0], contacts.shape[0]
    dxi, xi1, slid = np.empty(m), np.empty(m), np.empty(m, np.bool_)
    delta0, delta1 = np.empty(m), np.empty(m)
    ft0, ft1, q0 = np.empty(m), np.empty(m), np.empty(n)
    gamma, capped = params[6], 0
    overlaps(q, radii, contacts, params, delta0)
    tangential_forces(q, xi, radii, contacts, params, ft0)
    drag = math.exp(-0.5 * damping * dt)
    for _ in range(steps):
        for k in range(n):
            v[k] = v[k] * drag + 0.5 * dt * F[k] * inv_mass[k]
            q0[k] = q[k]
            q[k] += dt * v[k]
        history_increment(q0, q, gamma, gamma, radii, contacts, params, dxi)
        overlaps(q, radii, contacts, params, delta1)
        capped += commit_history(xi, dxi, delta0, delta1, params, True, xi1, slid)
        tangential_forces(q, xi1, radii, contacts, params, ft1)
        for c in range(m):
            work[0] += 0.5 * (ft0[c] + ft1[c]) * dxi[c]
            xi[c], ft0[c], delta0[c] = xi1[c], ft1[c], delta1[c]
        forces(q, xi, radii, contacts, params, F)
        for k in range(n):
            v[k] = (v[k] + 0.5 * dt * F[k] * inv_mass[k]) * drag
    return capped


@numba.njit(cache=True, error_model="numpy")
def frictionless(q, radii, L, k_n, F):
    """The frictionless packing at rest (gamma = 0) for a minimiser: q = (x_1..x_N, y_1..y_N),
    F = -dU/dq [force] into F (same layout), and returns (U, W): the energy U = sum of
    normal_energy(delta) [energy] and the virial W = sum r_ij . f_ij = sum |r_ij| F_n [energy]
    over the touching pairs (pressure P = W / (2 L^2))."""
    N = radii.shape[0]
    q3 = np.zeros(3 * N)
    q3[:2 * N] = q
    contacts = near_pairs(q3, radii, L, 0.0, 0.0)
    F[:] = 0.0
    U, W = 0.0, 0.0
    for c in range(contacts.shape[0]):
        i, j = contacts[c, 0], contacts[c, 1]
        dx, dy, ex, ey = grain_separation(q3, i, j, contacts[c, 2], contacts[c, 3], N, L, 0.0)
        delta = pair_overlap(dx, dy, ex, ey, 0.5 * (radii[i] + radii[j]))
        if delta > 0.0:
            rho = math.sqrt(dx * dx + dy * dy)
            F_n = normal_force(delta, k_n)
            F[i] += F_n * dx / rho
            F[N + i] += F_n * dy / rho
            F[j] -= F_n * dx / rho
            F[N + j] -= F_n * dy / rho
            U += normal_energy(delta, k_n)
            W += rho * F_n
    return U, W


def three_grains():
    """(q, radii, params) of three touching disks in a small sheared box: a state to warm up on."""
    radii = np.array([0.5, 0.7, 0.5])
    q = np.array([0.3, 1.45, 0.9, 0.5, 0.6, 1.5, 0.0, 0.0, 0.0])
    params = np.array([0.5, 2000.0, 4000.0 / 7.0, 10.0, 0.0, 2.5, 0.01])
    return q, radii, params


def warm_up(progress=None):
    """Call each compiled entry point once with the argument types models/packing/ passes, so that
    numba compiles it now or loads it from its cache (symbolic/generated.py)."""
    q, radii, params = three_grains()
    contacts = near_pairs(q, radii, params[5], params[6], 0.1)
    m, n = contacts.shape[0], q.size
    rows, cols = jacobian_pattern(3, contacts)
    F, Jvals, F_gamma, xi = np.empty(n), np.empty(rows.size), np.empty(n), np.zeros(m)
    delta0, delta1, dxi, xi1 = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    slid, sigma, F2 = np.empty(m, np.bool_), np.empty(4), np.empty(6)
    calls = [lambda: evaluate(q, xi, radii, contacts, params, F, Jvals, F_gamma),
             lambda: forces(q, xi, radii, contacts, params, F),
             lambda: stress(q, xi, radii, contacts, params, sigma),
             lambda: overlaps(q, radii, contacts, params, delta0),
             lambda: overlaps(q + 1e-4, radii, contacts, params, delta1),
             lambda: history_increment(q, q + 1e-4, 0.0, 1e-4, radii, contacts, params, dxi),
             lambda: commit_history(xi, dxi, delta0, delta1, params, True, xi1, slid),
             lambda: carried_forces(q, q + 1e-4, xi, delta0, radii, contacts, params, F, xi1,
                                    delta1),
             lambda: frictionless(q[:6].copy(), radii, params[5], params[1], F2),
             lambda: normal_energy_sum(q, radii, contacts, params),
             lambda: advance(q.copy(), np.zeros(n), xi.copy(), radii, contacts, params,
                             np.ones(n), 1e-3, 2, F.copy(), np.zeros(1), 0.0)]
    for k, call in enumerate(calls):
        call()
        if progress is not None:
            progress((k + 1) / len(calls))
