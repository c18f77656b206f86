"""An independent, plain transcription of docs/model.md in mpmath, for high-precision references.

Nothing here shares code with symbolic/: forces are written straight from the equations, and
the total stiffness is obtained by central finite differences in 50-digit arithmetic with the
history following q along each step (midpoint rule, docs/model.md's increments).

conventions "lammps" (docs/physics.md): the disk-disk torque lever arm is R - delta/2 and a
step's pair increment takes the tangent at the end of the step. Normal laws F_n = k_n delta^p:
Hertz p = 3/2 (the paper), Hooke p = 1; the Coulomb limit t* is where the Mindlin force
k_t delta^(1/2) |xi| reaches mu F_n.
"""
from __future__ import annotations

from dataclasses import dataclass

import mpmath as mp

mp.mp.dps = 50


@dataclass(frozen=True)
class Ref:
    N: int
    R: float
    k_n: float
    k_t: float
    mu: float
    F_y: float
    L: float
    pair_law: str
    wall_law: str
    rotation: bool
    conventions: str = "model"
    normal: str = "hertz"

    @property
    def D(self) -> int:
        return 3 if self.rotation else 2


EXPONENTS = {"hertz": mp.mpf(3) / 2, "hooke": mp.mpf(1)}


def normal_force(normal, k_n, delta):
    """F_n = k_n delta^p."""
    return k_n * delta ** EXPONENTS[normal]


def coulomb_limit(normal, k_n, k_t, mu, delta):
    """t* with k_t delta^(1/2) t* = mu F_n."""
    return mu * normal_force(normal, k_n, delta) / (k_t * mp.sqrt(delta))


def tangential(law, k_n, k_t, mu, delta, xi, normal="hertz"):
    """F_t along s on the first body: smoothed Mindlin (paper eq. 5), linear, or none."""
    if law == "none":
        return mp.mpf(0)
    if law == "mindlin-linear":
        return -k_t * mp.sqrt(delta) * xi
    t_star = coulomb_limit(normal, k_n, k_t, mu, delta)
    x = xi / t_star
    return -k_t * mp.sqrt(delta) * (1 + abs(x) - x * x) * xi


def pair_geometry(m: Ref, q, k):
    """(i, j, dx, dy) of pair k with the periodic image of disk 0 for the last pair."""
    N = m.N
    i, j = k, (k + 1) % N
    dx = q[i] - q[j] - (m.L if j == 0 else 0)
    return i, j, dx, q[N + i] - q[N + j]


def add(F, m: Ref, disk, fx, fy, torque):
    N = m.N
    F[disk] += fx
    F[N + disk] += fy
    if m.rotation:
        F[2 * N + disk] += torque


def pair_force(m: Ref, q, xi, k, F):
    i, j, dx, dy = pair_geometry(m, q, k)
    rho = mp.sqrt(dx * dx + dy * dy)
    delta = 2 * m.R - rho
    if delta <= 0:
        return
    nx, ny = dx / rho, dy / rho
    sx, sy = -ny, nx
    Fn = normal_force(m.normal, m.k_n, delta)
    Ft = tangential(m.pair_law, m.k_n, m.k_t, m.mu, delta, xi[k], m.normal)
    fx, fy = Fn * nx + Ft * sx, Fn * ny + Ft * sy
    arm = m.R - delta / 2 if m.conventions == "lammps" else m.R
    add(F, m, i, fx, fy, -arm * Ft)
    add(F, m, j, -fx, -fy, -arm * Ft)


def wall_force(m: Ref, q, xi, k, F):
    delta = m.R - q[m.N + k]
    if delta <= 0:
        return
    Ft = tangential(m.wall_law, m.k_n, m.k_t, m.mu, delta, xi[m.N + k], m.normal)
    add(F, m, k, Ft, normal_force(m.normal, m.k_n, delta), m.R * Ft)


def forces(m: Ref, q, xi, F_x, contacts=None):
    """Generalized forces; `contacts` restricts to some ("pair", k) / ("wall", k) contacts."""
    F = [mp.mpf(0)] * (m.D * m.N)
    for k in range(m.N):
        if contacts is None or ("pair", k) in contacts:
            pair_force(m, q, xi, k, F)
        if contacts is None or ("wall", k) in contacts:
            wall_force(m, q, xi, k, F)
    if contacts is None:
        F[0] += F_x
        for i in range(m.N):
            F[m.N + i] -= m.F_y
    return F


def increment(m: Ref, q0, q1):
    """Delta xi along q0 -> q1 by the midpoint rule of docs/model.md's increments (the pair tangent
    at q1 with conventions "lammps")."""
    N = m.N
    qm = list(q1) if m.conventions == "lammps" else [(a + b) / 2 for a, b in zip(q0, q1)]
    dq = [b - a for a, b in zip(q0, q1)]
    dth = (lambda i: dq[2 * N + i]) if m.rotation else (lambda i: 0)
    dxi = [mp.mpf(0)] * (2 * N)
    for k in range(N):
        i, j, dx, dy = pair_geometry(m, qm, k)
        rho = mp.sqrt(dx * dx + dy * dy)
        sx, sy = -dy / rho, dx / rho
        if m.pair_law != "none":
            dxi[k] = sx * (dq[i] - dq[j]) + sy * (dq[N + i] - dq[N + j]) - m.R * (dth(i) + dth(j))
        if m.wall_law != "none":
            dxi[N + k] = dq[k] + m.R * dth(k)
    return dxi


def displaced_states(m: Ref, q, xi, h):
    """The states stiffness_fd differences, (q + sign h e_c, xi following q), for every column
    c and sign +1, -1 in turn: the same whichever contacts' forces are then taken."""
    q = [mp.mpf(v) for v in q]
    xi = [mp.mpf(v) for v in xi]
    states = []
    for c in range(len(q)):
        for sign in (1, -1):
            qs = list(q)
            qs[c] += sign * h
            states.append((qs, [a + b for a, b in zip(xi, increment(m, q, qs))]))
    return states


def stiffness_fd(m: Ref, q, xi, h, contacts=None, states=None):
    """J = -dF/dq by central differences with xi following q: columns in 50-digit arithmetic.
    `states`: displaced_states(m, q, xi, h) when already at hand (a caller taking the matrix of
    several sets of contacts at one state computes the increments once: they were half the
    time of test_symbolic's Jacobian test)."""
    states = displaced_states(m, q, xi, h) if states is None else states
    n = len(q)
    J = [[mp.mpf(0)] * n for _ in range(n)]
    for c in range(n):
        side = [forces(m, qs, xs, 0, contacts) for qs, xs in states[2 * c:2 * c + 2]]
        for r in range(n):
            J[r][c] = -(side[0][r] - side[1][r]) / (2 * h)
    return J


def overlaps(m: Ref, q):
    """delta of pairs then walls, in mpmath."""
    q = [mp.mpf(v) for v in q]
    out = []
    for k in range(m.N):
        _, _, dx, dy = pair_geometry(m, q, k)
        out.append(2 * m.R - mp.sqrt(dx * dx + dy * dy))
    return out + [m.R - q[m.N + k] for k in range(m.N)]


def hertz_energy(m: Ref, q, F_x):
    """U = sum k_n delta^(p+1) / (p+1) over active contacts (Hertz: 2/5 k_n delta^(5/2))
    + F_y sum y_i - F_x x_1."""
    p = EXPONENTS[m.normal]
    U = -F_x * mp.mpf(q[0]) + m.F_y * sum(mp.mpf(q[m.N + i]) for i in range(m.N))
    for d in overlaps(m, q):
        if d > 0:
            U += m.k_n * d ** (p + 1) / (p + 1)
    return U
