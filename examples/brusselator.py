"""The Brusselator's equilibrium in B: a complex pair born, its Hopf point, and its death.

    u' = A - (B + 1) u + u^2 v,   v' = B u - u^2 v,   equilibrium (u, v) = (A, B / A).

The Jacobian there, [[B - 1, A^2], [-B, -A^2]], has trace B - 1 - A^2 and determinant A^2: its
eigenvalues are complex for (1 - A)^2 < B < (1 + A)^2 (where (B - 1 - A^2)^2 < 4 A^2), and the
pair crosses the imaginary axis at B = 1 + A^2 with omega = A (the Hopf point where the
chemical oscillation starts). A = 1.5: birth at B = 0.25, Hopf at 3.25, death at 6.25.

    diskfriction bifurcate --problem examples/brusselator.py
"""
import numpy as np
import sympy as sp

from diskfriction.continuation import BifurcationProblem, problem_from_sympy

u, v, A, B = sp.symbols("u v A B")
G = [A - (B + 1) * u + u**2 * v, B * u - u**2 * v]
a = 1.5

problem = BifurcationProblem(problem_from_sympy(G, (u, v), B, values={A: a}),
                             u0=lambda B: np.array([a, B / a]), p_span=(0.0, 8.0), parameter="B",
                             matrix="dG/du")
