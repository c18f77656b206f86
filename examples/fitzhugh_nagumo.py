"""FitzHugh-Nagumo with a constant current I: folds, Hopf points and collisions in closed form.

    v' = v - v^3/3 - w + I,    w' = eps (v + a - b w),      u = (v, w), p = I,

with a = 0.7, b = 2, eps = 0.1 (b > 1 makes the branch of equilibria S-shaped). On the branch
w = (v + a)/b and I(v) = v^3/3 - v + (v + a)/b; the Jacobian is [[1 - v^2, -1], [eps, -eps b]]:
  folds     dI/dv = 0:                  v^2 = 1 - 1/b
  Hopf      trace 0 with det > 0:       v^2 = 1 - eps b,  omega^2 = det = eps (1 - eps b^2)
  collisions  trace^2 = 4 det:          v^2 = 1 + eps b -+ 2 sqrt(eps)
each at v = +-sqrt(...), so I = I(v). Dimensionless: I in the units of v' (a current).

    diskfriction bifurcate --problem examples/fitzhugh_nagumo.py
"""
import numpy as np

from diskfriction.continuation import BifurcationProblem, problem_from_functions

a, b, eps = 0.7, 2.0, 0.1


def G(u, I):
    v, w = u
    return np.array([v - v**3 / 3 - w + I, eps * (v + a - b * w)])


def dG_du(u, I):
    return np.array([[1.0 - u[0] ** 2, -1.0], [eps, -eps * b]])


def dG_dI(u, I):
    return np.array([1.0, 0.0])


def current(v):
    """I(v) on the branch of equilibria."""
    return v**3 / 3 - v + (v + a) / b


def fitzhugh_nagumo(derivatives: bool = True) -> BifurcationProblem:
    """The problem in I from v = -1.6 to 1.6; without `derivatives` dG/du and dG/dI are computed
    by central differences (and the tracked Jacobian with them)."""
    given = {"dG_du": dG_du, "dG_dp": dG_dI} if derivatives else {}
    v0 = -1.6
    return BifurcationProblem(problem_from_functions(G, **given), u0=np.array([v0, (v0 + a) / b]),
                              p_span=(current(v0), current(-v0)), parameter="I", matrix="dG/du")


problem = fitzhugh_nagumo()
