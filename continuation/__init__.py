"""Generic continuation core: pseudo-arclength branches of G(u, p) = 0, tracked spectra and
located eigenvalue collisions (births/deaths of complex pairs). Knows nothing of disks.

    branch = continuation(problem, u0, p0, ContinuationParams(...), DetectionParams(...))
"""
from .arclength import ContinuationError, ContinuationParams, continuation
from .branch import Branch
from .collisions import Collision, DetectionParams
from .problem import FunctionProblem, Problem
from .spectra import count_complex_pairs, eigen_status, match_eigenvalues, track

__all__ = [
    "Branch", "Collision", "ContinuationError", "ContinuationParams", "DetectionParams",
    "FunctionProblem", "Problem", "continuation", "count_complex_pairs", "eigen_status",
    "match_eigenvalues", "track",
]
