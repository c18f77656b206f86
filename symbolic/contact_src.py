# What every generated kernel module shares (the chain's and the packing's, see codegen.py): an
# overlap delta = R_i + R_j - |r_ij| to full relative accuracy, from a separation computed with
# its rounding error, and the history rule of a step (commit_history). Rendered by
# symbolic/template.py. Not importable on its own: math, numba, coulomb_limit come from the
# generated part above it; params[1:4] = (k_n, k_t, mu) in both modules' params.


@numba.njit(cache=True, error_model="numpy")
def two_diff(a, b):
    """s = fl(a - b) and its rounding error e = (a - b) - s, exactly (Knuth's TwoSum)."""
    s = a - b
    bb = s - a
    return s, (a - (s - bb)) - (b + bb)


@numba.njit(cache=True, error_model="numpy")
def pair_overlap(dx, dy, ex, ey, R):
    """delta = 2R - |r_ij| [length] to full relative accuracy even for delta << 2R.

    2R - rho cancels: a rounding of ~1e-16 in dx is a relative error 1e-16 / delta in delta
    (1e-6 at delta = 1e-10). Instead delta = (4R^2 - |r_ij|^2) / (2R + rho) with
    4R^2 - |r_ij|^2 = (2R - a)(2R + a) - b^2 - 2 (dx ex + dy ey), a = max(|dx|, |dy|),
    b = min(...): 2R - a is exact for a in [R, 4R] (Sterbenz) and the TwoSum errors ex, ey of
    the separation are restored to first order (their squares are below 1e-32). Disks of radii
    R_i, R_j: R = (R_i + R_j) / 2 (the halving and doubling are exact)."""
    a = max(abs(dx), abs(dy))
    b = min(abs(dx), abs(dy))
    two_R = 2.0 * R
    num = (two_R - a) * (two_R + a) - b * b - 2.0 * (dx * ex + dy * ey)
    return num / (two_R + math.sqrt(dx * dx + dy * dy))


@numba.njit(cache=True, error_model="numpy")
def commit_history(xi0, dxi, delta0, delta1, params, cap, xi1, slid):
    """docs/model.md's history rule for one step with increment dxi, into xi1 [length].

    Open at the end (delta1 <= 0): xi1 = 0. Closed during the step (delta0 <= 0 < delta1): the
    contact starts from zero at first contact ("t = 0 upon first contact", paper) and charges the
    part of the increment after it, delta1 / (delta1 - delta0) of dxi with delta taken linear
    along the step (a contact touching at delta0 = 0 charges all of it); conventions "lammps"
    charge all of dxi (symbolic/template.py, first_contact). Otherwise
    xi1 = xi0 + dxi. With `cap`, a history beyond its Coulomb limit t* = coulomb_limit(delta1)
    (Hertz: mu k_n delta1 / k_t) is set to sign(xi1) t* (the contact slides) and slid[c] is
    True. Returns the number capped."""
    k_n, k_t, mu = params[1], params[2], params[3]
    n_slid = 0
    for c in range(xi0.shape[0]):
        slid[c] = False
        if delta1[c] <= 0.0:
            xi1[c] = 0.0
            continue
        if delta0[c] <= 0.0:
            ...  # @fragment first_contact
        else:
            xi1[c] = xi0[c] + dxi[c]
        t_star = coulomb_limit(delta1[c], k_n, k_t, mu)
        if cap and abs(xi1[c]) > t_star:
            xi1[c] = t_star if xi1[c] > 0.0 else -t_star
            slid[c] = True
            n_slid += 1
    return n_slid
