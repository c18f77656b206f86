"""Ziegler's double pendulum under a follower force: flutter from a collision of frequencies.

Two rigid bars of length l (angles theta1, theta2 from the vertical), rotational springs k at
the base and at the joint, masses 2m at the joint and m at the tip, and a force P at the tip
that stays along the upper bar (a follower force). Derived below from the kinetic energy T,
the spring energy V and the virtual work of the force, Q_i = F . d r_tip / d theta_i, and
linearised about the upright state:

    M theta'' + K(P) theta = 0,   M = m l^2 [[3, 1], [1, 1]],   K(P) = [[2k - P l, P l - k], [-k, k]].

The squared frequencies omega^2 are the eigenvalues of M^-1 K(P): det(K - omega^2 M) = 0 is
2 s^2 + (2P - 7) s + 1 = 0 (k = l = m = 1, s = omega^2), whose discriminant vanishes at
P = (7/2 -+ sqrt 2) k/l: the two frequencies collide and leave the real axis (flutter) at the
first and return at the second. Units: k = l = m = 1, so P is in k/l and omega^2 in k/(m l^2).

    diskfriction bifurcate --problem examples/ziegler.py
"""
import numpy as np
import sympy as sp

from diskfriction.continuation import BifurcationProblem, Options, problem_from_sympy

P, k, l, m, t = sp.symbols("P k l m t", positive=True)
theta = [sp.Function(f"theta{i}")(t) for i in (1, 2)]
q = sp.symbols("theta1 theta2")
joint = l * sp.Matrix([sp.sin(theta[0]), sp.cos(theta[0])])
tip = joint + l * sp.Matrix([sp.sin(theta[1]), sp.cos(theta[1])])
T = (2 * m * joint.diff(t).dot(joint.diff(t)) + m * tip.diff(t).dot(tip.diff(t))) / 2
V = k * theta[0] ** 2 / 2 + k * (theta[1] - theta[0]) ** 2 / 2
force = -P * sp.Matrix([sp.sin(theta[1]), sp.cos(theta[1])])  # along the upper bar, downwards
Q = [force.dot(tip.diff(th)) for th in theta]

rest = {th: 0 for th in theta} | {th.diff(t): 0 for th in theta}
rates = [th.diff(t) for th in theta]
M = sp.hessian(T, rates).subs(rest).applyfunc(sp.simplify)
K = (sp.hessian(V, theta) - sp.Matrix([Q]).T.jacobian(theta)).subs(rest).applyfunc(sp.simplify)
M, K = (X.subs(dict(zip(theta, q))) for X in (M, K))

units = {k: 1.0, l: 1.0, m: 1.0}
problem = BifurcationProblem(
    problem_from_sympy(list(K * sp.Matrix(q)), q, P, A=M.inv() * K, values=units),
    u0=np.zeros(2), p_span=(0.0, 6.0), parameter="P", units="k/l", matrix="M^-1 K",
    eigenvalue_units="k/(m l^2)", options=Options(ds_max=0.2, special_points=("fold",)))
