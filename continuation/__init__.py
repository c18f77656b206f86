"""Generic continuation core: pseudo-arclength branches of G(u, p) = 0, tracked spectra and
located eigenvalue collisions (births/deaths of complex pairs). Knows nothing of disks.

The public front end (api.py, docs/api.md):

    problem = problem_from_functions(G, A=A)          # or problem_from_sympy, or a Problem
    result = solve_branch(problem, u0, (p_start, p_stop), Options(...))
    Options(eigensolver=SpectralWindow(lo, hi))       # how spectra are computed (DenseSpectra,
                                                      # RefinedSpectra, SpectralWindow)
    Options(linear_solver=LinearSolver("MMD_AT_PLUS_A"))  # how the bordered systems are solved
    with spectra_on("gpu"): ...                       # dense spectra on a GPU (CuPy)

The core underneath:

    branch = continuation(problem, u0, p0, ContinuationParams(...), DetectionParams(...))
"""
from diskfriction.continuation.api import (BifurcationProblem, BranchResult, Options, ProblemError, check_problem,
                  problem_from_functions, problem_from_sympy, solve_branch, switch_branch)
from diskfriction.continuation.stepping.arclength import ContinuationError, ContinuationParams, continuation
from diskfriction.continuation.detection.bifurcations import SpecialPoint
from diskfriction.continuation.branch import Branch, Stop, StopCode
from diskfriction.continuation.detection.collisions import Collision, DetectionParams
from diskfriction.continuation.linalg.solves import LinearSolver
from diskfriction.continuation.stepping.differences import DerivativeWarning
from diskfriction.continuation.problem import FunctionProblem, Problem
from diskfriction.continuation.spectra.eigensolvers import DenseSpectra, Eigensolver, RefinedSpectra
from diskfriction.continuation.spectra.structure import StructuredMatrix
from diskfriction.continuation.spectra.tracking import (NoGpu, SpectraDevice, count_complex_pairs, eigen_status, match_eigenvalues,
                      spectra_on, track)
from diskfriction.continuation.spectra.window import SpectralWindow

__all__ = [
    "BifurcationProblem", "Branch", "BranchResult", "Collision", "ContinuationError",
    "ContinuationParams", "DenseSpectra", "DerivativeWarning", "DetectionParams", "Eigensolver",
    "FunctionProblem", "LinearSolver", "NoGpu", "Options", "Problem", "ProblemError", "RefinedSpectra",
    "SpectraDevice", "SpecialPoint", "SpectralWindow", "Stop", "StopCode", "StructuredMatrix",
    "check_problem", "continuation", "count_complex_pairs", "eigen_status", "match_eigenvalues",
    "problem_from_functions", "problem_from_sympy", "solve_branch", "spectra_on", "switch_branch", "track",
]
