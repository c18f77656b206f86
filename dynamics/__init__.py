"""Newtonian dynamics of the disk chain: velocity Verlet with the history carried and the
Coulomb cap (sliding), started from a branch point, with observables and a growth check.

    traj = simulate(system, q, xi, F_x, t_end, perturbation=Perturbation("eigenvector", 1e-9))
    summary = summarize(traj)

Data flow: symbolic (kernels, System) -> dynamics; the step loop is compiled against the
scene's kernel module (dynamics/stepper.py).
"""
from diskfriction.dynamics.growth import GrowthFit, fit_growth
from diskfriction.dynamics.onset import OnsetParams, sliding_onset
from diskfriction.dynamics.simulate import choose_dt, simulate, summarize
from diskfriction.dynamics.start import KINDS, Perturbation, Spectrum, perturb, spectrum
from diskfriction.dynamics.stepper import Stepper, load_stepper
from diskfriction.dynamics.trajectory import Trajectory

__all__ = [
    "GrowthFit", "KINDS", "OnsetParams", "Perturbation", "Spectrum", "Stepper", "Trajectory",
    "choose_dt", "fit_growth", "load_stepper", "perturb", "simulate", "sliding_onset",
    "spectrum", "summarize",
]
