"""The contact kernels, derived once per contact law (never per system).

Disk-disk pair (i, j): inputs dx, dy = r_i - r_j (image already applied) and the history xi.
    rho = |r_ij|, n = r_ij / rho, s = (-n_y, n_x), delta = 2R - rho.
    Force on i: F_n n + F_t s, on j the opposite; torques T_i = T_j = -a F_t with the lever arm
    a = R (conventions "model", docs/model.md#contacts) or a = R - delta/2, the distance from each centre to
    the middle of the overlap (conventions "lammps", LAMMPS's granular package).
    History increment: d xi = s . d r_ij - R (d theta_i + d theta_j).
Grain pair (i, j) of a packing (docs/packings.md): the disk-disk pair with radii R_i, R_j,
    delta = R_i + R_j - rho, torques T_i = -R_i F_t, T_j = -R_j F_t (conventions "model"),
    d xi = s . d r_ij - (R_i d theta_i + R_j d theta_j); with R_i = R_j = R it is the pair.
Disk-substrate (i): inputs y_i and xi.  delta = R - y_i.
    Force on i: (F_t, F_n), torque T_i = +R F_t.  History increment: d xi = dx_i + R d theta_i.

For each kernel we derive, symbolically, the generalized force vector f over the contact's local
degrees of freedom (x_i, y_i[, theta_i][, x_j, y_j, theta_j]), the increment coefficients w with
d xi = w . dq, and the total stiffness block J = -(df/dq + df/dxi w^T) (docs/model.md#stability: the history
follows q). rho and delta are carried as symbols with explicit chain rules
d rho / d dx = dx / rho, d delta / d dx = -dx / rho, so that powers of delta stay symbolic and
combine (see laws.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from diskfriction.symbolic import laws
from diskfriction.symbolic.laws import R, delta, xi

dx, dy, y = sp.symbols("dx dy y", real=True)
rho = sp.Symbol("rho", positive=True)
R_i, R_j = sp.symbols("R_i R_j", positive=True)

RADII = {"pair": (R, R), "grain": (R_i, R_j)}
"""The radii of the two disks of each disk-disk kernel: the chain's equal disks, a packing's two."""


@dataclass(frozen=True)
class ContactExprs:
    """Symbolic result for one contact kernel.

    kind   "pair" or "wall";  dofs  names of the local degrees of freedom;
    f      generalized forces on the local dofs [force, torque];
    J      total stiffness block -d f / d q (history following q) [force / length];
    w      history increment coefficients, d xi = w . dq [1, length for angles];
    law    tangential law this kernel was derived for;  normal  its normal law.
    """

    kind: str
    law: str
    normal: str
    dofs: tuple[str, ...]
    f: sp.Matrix
    J: sp.Matrix
    w: sp.Matrix


def _stiffness(f: sp.Matrix, dfdq: sp.Matrix, w: sp.Matrix, normal: str) -> sp.Matrix:
    """J = -(df/dq + df/dxi w^T), then in Coulomb units (u = xi / t*)."""
    J = -(dfdq + f.diff(xi) * w.T)
    return J.applyfunc(lambda e: laws.in_coulomb_units(e, normal))


LEVER_ARMS = {"model": lambda radius: radius, "lammps": lambda radius: radius - delta / 2}
"""Disk-disk torque lever arm of a disk of `radius` per conventions [length]. The history
increment keeps the arm R (d xi = s . dr_ij - R (dtheta_i + dtheta_j)) in both: LAMMPS charges
the history with the relative velocity of the surface points at distance R from each centre."""


def pair_contact(law: str, rotation: bool, conventions: str = "model", normal: str = "hertz",
                 kind: str = "pair") -> ContactExprs:
    """Disk-disk kernel for a tangential and a normal law; local dofs of disk i then disk j;
    torque lever arm LEVER_ARMS[conventions]; radii RADII[kind]."""
    n = sp.Matrix([dx / rho, dy / rho])
    s = sp.Matrix([-n[1], n[0]])
    F_n, F_t = laws.normal_force(normal), laws.tangential_force(law, normal)
    force_i = F_n * n + F_t * s
    radius_i, radius_j = RADII[kind]
    torque_i = -LEVER_ARMS[conventions](radius_i) * F_t
    torque_j = -LEVER_ARMS[conventions](radius_j) * F_t

    def total(e, var):  # d/d(var) with rho(dx, dy) and delta = 2R - rho
        return sp.diff(e, var) + (sp.diff(e, rho) - sp.diff(e, delta)) * var / rho

    if rotation:
        dofs = ("x_i", "y_i", "theta_i", "x_j", "y_j", "theta_j")
        f = sp.Matrix([force_i[0], force_i[1], torque_i, -force_i[0], -force_i[1], torque_j])
        w = sp.Matrix([s[0], s[1], -radius_i, -s[0], -s[1], -radius_j])
        cols = [(dx, 1), (dy, 1), None, (dx, -1), (dy, -1), None]
    else:
        dofs = ("x_i", "y_i", "x_j", "y_j")
        f = sp.Matrix([force_i[0], force_i[1], -force_i[0], -force_i[1]])
        w = sp.Matrix([s[0], s[1], -s[0], -s[1]])
        cols = [(dx, 1), (dy, 1), (dx, -1), (dy, -1)]
    dfdq = sp.Matrix(len(dofs), len(dofs),
                     lambda a, b: 0 if cols[b] is None else cols[b][1] * total(f[a], cols[b][0]))
    return _contact(kind, law, normal, dofs, f, dfdq, w)


def _contact(kind: str, law: str, normal: str, dofs: tuple[str, ...], f: sp.Matrix,
             dfdq: sp.Matrix, w: sp.Matrix) -> ContactExprs:
    """The ContactExprs of forces f with derivative dfdq, both in Coulomb units."""
    in_units = f.applyfunc(lambda e: laws.in_coulomb_units(e, normal))
    return ContactExprs(kind, law, normal, dofs, in_units, _stiffness(f, dfdq, w, normal), w)


def wall_contact(law: str, rotation: bool, normal: str = "hertz") -> ContactExprs:
    """Disk-substrate kernel for a tangential and a normal law; local dofs (x_i, y_i[, theta_i])."""
    F_n, F_t = laws.normal_force(normal), laws.tangential_force(law, normal)
    if rotation:
        dofs = ("x_i", "y_i", "theta_i")
        f = sp.Matrix([F_t, F_n, R * F_t])
        w = sp.Matrix([1, 0, R])
    else:
        dofs = ("x_i", "y_i")
        f = sp.Matrix([F_t, F_n])
        w = sp.Matrix([1, 0])
    # f depends on y only through delta = R - y, so d/dy = -d/ddelta; x, theta enter via xi only.
    dfdq = sp.zeros(len(dofs), len(dofs))
    dfdq[:, 1] = -f.diff(delta)
    return _contact("wall", law, normal, dofs, f, dfdq, w)
