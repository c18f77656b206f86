"""Beck's column: a cantilever under a tangential (follower) load P at its free end.

Length L, bending stiffness EI, mass per length mu; deflection w(x, t) with
EI w'''' + P w'' + mu w_tt = 0, clamped at x = 0 (w = w' = 0) and free at x = L with the load
along the tangent (w'' = 0, EI w''' = 0). The weak form adds P w'(L) v(L) to the usual terms:
no potential gives it, so the stiffness is not symmetric. With n Hermite cubic elements
(length h = L / n; nodal w and w' = theta) the linearised equations are

    M u'' + K(P) u = 0,    K(P) = K_e - P K_g + P e_w e_theta^T,

K_e = EI/h^3 [[12, 6h, -12, 6h], [6h, 4h^2, -6h, 2h^2], ...] the elastic stiffness,
K_g = 1/(30h) [[36, 3h, -36, 3h], [3h, 4h^2, -3h, -h^2], ...] from the integral of w' v',
M = mu h/420 [[156, 22h, 54, -13h], [22h, 4h^2, 13h, -3h^2], ...] the consistent mass, and
e_w e_theta^T the follower load's term, row w and column theta of the tip node. The tracked
matrix M^-1 K(P) has the squared frequencies as eigenvalues; the first two collide (flutter)
at P L^2 / EI = 20.05 (Beck 1952). The example tracks the inverse, K(P)^-1 M, whose eigenvalues
1/omega^2 collide at the same P: there the lowest modes are the largest eigenvalues, while in
M^-1 K they would be ~5e-7 of the mesh's highest frequency (16 elements), near the threshold
that tells a complex pair from a real one (docs/api.md, "Choosing the tracked matrix"). K(P)
stays regular over the span (the follower load has no divergence). Units: L = EI = mu = 1, so
P is in EI/L^2.

    diskfriction bifurcate --problem examples/beck.py
"""
import numpy as np

from diskfriction.continuation import BifurcationProblem, Options, problem_from_functions

ELASTIC = np.array([[12, 6, -12, 6], [6, 4, -6, 2], [-12, -6, 12, -6], [6, 2, -6, 4]], float)
GEOMETRIC = np.array([[36, 3, -36, 3], [3, 4, -3, -1], [-36, -3, 36, -3], [3, -1, -3, 4]], float) / 30
MASS = np.array([[156, 22, 54, -13], [22, 4, 13, -3], [54, 13, 156, -22], [-13, -3, -22, 4]], float) / 420


def matrices(n: int):
    """(M, K_e, K_g, F) of n elements on a unit cantilever (EI = mu = 1), the clamped node's
    two dofs removed; element matrices scaled by h: w-dofs by 1, theta-dofs by h."""
    h = 1.0 / n
    s = np.array([1.0, h, 1.0, h])
    size = 2 * (n + 1)
    M, K_e, K_g = (np.zeros((size, size)) for _ in range(3))
    for e in range(n):
        dofs = slice(2 * e, 2 * e + 4)
        K_e[dofs, dofs] += ELASTIC * np.outer(s, s) / h**3
        K_g[dofs, dofs] += GEOMETRIC * np.outer(s, s) / h
        M[dofs, dofs] += MASS * np.outer(s, s) * h
    F = np.zeros((size, size))
    F[-2, -1] = 1.0  # P w'(L) v(L): row w, column theta of the tip
    return tuple(X[2:, 2:] for X in (M, K_e, K_g, F))


def beck(n: int = 16) -> BifurcationProblem:
    """The column with n elements as a BifurcationProblem in P (units EI/L^2)."""
    M, K_e, K_g, F = matrices(n)
    K = lambda P: K_e - P * K_g + P * F  # noqa: E731
    equations = problem_from_functions(
        lambda u, P: K(P) @ u, dG_du=lambda u, P: K(P), dG_dp=lambda u, P: (F - K_g) @ u,
        A=lambda u, P: np.linalg.solve(K(P), M))
    return BifurcationProblem(equations, u0=np.zeros(2 * n), p_span=(0.0, 25.0), parameter="P",
                              units="EI/L^2", matrix="K^-1 M", eigenvalue_units="mu L^4/EI",
                              options=Options(ds_max=0.5, special_points=("fold",)))


problem = beck()

if __name__ == "__main__":  # the convergence table of docs/gallery.md
    loads = {n: beck(n).solve().collisions[0].p for n in (2, 4, 8, 16, 32, 64)}
    print("elements  P L^2/EI           observed order log2((P_n/2 - P_n) / (P_n - P_2n))")
    for n, P in loads.items():
        rows = [loads.get(n // 2), P, loads.get(2 * n)]
        order = np.log2((rows[0] - rows[1]) / (rows[1] - rows[2])) if None not in rows else np.nan
        print(f"{n:8d}  {P:.12f}  {order:.2f}")
