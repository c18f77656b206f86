"""The Lorenz system's equilibria in r: a pitchfork, then a collision and a Hopf point.

    x' = sigma (y - x),   y' = r x - y - x z,   z' = x y - b z,   sigma = 10, b = 8/3.

The origin is an equilibrium for every r; at r = 1 an eigenvalue of its Jacobian passes zero
and the two branches C+- (x = y = +-sqrt(b (r - 1)), z = r - 1) branch off it: a pitchfork,
which the run reports as a branch point (not a fold: p does not turn back on the origin's
branch, and on C+- it does only because C+ and C- are one curve through the point). On C+-
two real eigenvalues collide at r = 1.3456 (a root of the cubic's discriminant) and the pair
they form crosses the imaginary axis at r = sigma (sigma + b + 3) / (sigma - b - 1) = 470/19:
Lorenz's Hopf point, where the chaotic attractor's equilibria lose stability.

    diskfriction bifurcate --problem examples/lorenz.py              # the origin, r = 1 found
    diskfriction bifurcate --problem examples/lorenz.py --switch 1   # C+ from r = 1 to 30
"""
import numpy as np
import sympy as sp

from diskfriction.continuation import BifurcationProblem, problem_from_sympy

x, y, z, r, sigma, b = sp.symbols("x y z r sigma b")
G = [sigma * (y - x), r * x - y - x * z, x * y - b * z]
constants = {sigma: 10.0, b: sp.Rational(8, 3)}

problem = BifurcationProblem(problem_from_sympy(G, (x, y, z), r, values=constants),
                             u0=np.zeros(3), p_span=(0.0, 30.0), parameter="r", matrix="dG/du")
