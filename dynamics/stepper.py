"""Newton's equations M q'' = F(q, xi; F_x) with the history carried, stepped inside numba.

Scheme: velocity Verlet (kick-drift-kick), with the history advanced over the drift by the same
rule as a quasistatic step (midpoint increment, reset on opening, first contact, Coulomb cap;
conventions "lammps": end-of-step increment, docs/physics.md).
M = diag(m, m, I) (diag(m, m) without rotation); no damping anywhere.

Why this scheme. The state is (q, v, xi), and the equations are

    q' = v,   M v' = F(q, xi; F_x),   xi' = w(q) . v  (sticking; capped at |xi| = t*(delta)),

with F independent of v. Velocity Verlet is the Strang splitting of this flow into
  B: v' = M^-1 F(q, xi), (q, xi) frozen: solved exactly by a kick, and
  A: q' = v, xi' = w(q) . v, v frozen: q moves on a straight line, so xi changes by the path
     integral of w along that segment, which the midpoint rule gives to O(|dq|^3) (the
     quasistatic rule, exactly).
Strang splitting B(h/2) A(h) B(h/2) is second order and symmetric (time reversible while no
contact caps, opens or closes), with one force evaluation per step, and explicit because F does
not depend on v. Without friction xi is absent, the scheme is the symplectic Stormer-Verlet
method and the energy error stays bounded, O(dt^2), with no secular drift. With friction the
system is not Hamiltonian: the 1-form F_n d delta + F_t d xi of the Mindlin law is not exact
(F_t depends on delta), J is not symmetric and there is no conserved energy to preserve;
"symplectic" then means only that the scheme reduces to Stormer-Verlet in every frictionless
limit. What is conserved is the budget E_kin + U_n + U_load - W_t, where W_t is the work of the
tangential forces along the path; the stepper integrates W_t by the trapezoid rule in time over
the midpoint increments, so the budget closes to O(dt^2) (dynamics/simulate.py checks it).
The cap is applied at the end of the drift, as in a quasistatic step; a contact slides for the
whole step in which its cap acts (no splitting of steps at events: dt is small against every
contact time, and the error of this is O(dt) per event, not per step).

The kernel module is generated per effect set, so the step loop is compiled against it: a small
module is written beside the kernel module in the cache directory (its name carries the kernel
hash and a digest of stepper_src.py), importing the kernel module by path and appending
stepper_src.py rendered for the kernel module's conventions: its per-contact code (increments,
forces, first contact, tangential work) is the fragments of symbolic/template.py, the text the
kernel module's forces, history_increment and commit_history are rendered from too. numba's cache=True then keeps the compiled loop beside it: a second process
starts without compiling. (Passing the kernel functions as arguments instead makes numba's
cache miss in every new process: a dispatcher's type is its identity.)
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Optional

import numpy as np

from diskfriction.files import source_digest
from diskfriction.symbolic import System
from diskfriction.symbolic.generated import Progress, load_generated
from diskfriction.symbolic.template import Dialect, render

_SOURCE = Path(__file__).with_name("stepper_src.py")
_GENERATOR = ("diskfriction.dynamics.stepper", "diskfriction.dynamics.stepper_src",
              "diskfriction.symbolic.template")

_CONSTANTS = ("D", "PAIR_FRICTION", "WALL_FRICTION")
_FUNCTIONS = ("pair_separation", "pair_overlap", "pair_force", "pair_increment_coeffs",
              "pair_dofs", "wall_force", "wall_increment_coeffs", "wall_dofs", "add_loads",
              "commit_history", "normal_energy", "ring_of_two")

_HEADER = '''"""diskfriction dynamics stepper over {kernels}. Do not edit: regenerated from dynamics/.

stepper digest: {digest}
"""
import importlib.util
import os
import sys

import numba
import numpy as np


def _kernel_module():
    name = "{kernels}"
    if name not in sys.modules:
        path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "{kernel_file}")
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


_k = _kernel_module()
{bindings}
'''


def stepper_digest(kernels: ModuleType) -> str:
    """Names the stepper of this kernel module: sha256 of the kernel module's name and the
    sources of this generator (stepper.py's header, stepper_src.py)."""
    text = f"{kernels.__name__}|{source_digest(_GENERATOR)}"
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def stepper_source(kernels: ModuleType, digest: str) -> str:
    """The source of the stepper compiled against this kernel module: stepper_src.py rendered
    with the kernel module's conventions (symbolic/template.py)."""
    bindings = "\n".join(f"{name} = _k.{name}" for name in _CONSTANTS + _FUNCTIONS)
    header = _HEADER.format(kernels=kernels.__name__, kernel_file=Path(kernels.__file__).name,
                            digest=digest, bindings=bindings)
    dialect = Dialect(kernels.CONVENTIONS, kernels.D == 3)
    return header + "\n\n" + render(_SOURCE.read_text(), dialect)


def load_stepper(kernels: ModuleType, progress: Optional[Progress] = None) -> ModuleType:
    """The stepper module for this kernel module: written beside it once, checked on every
    load and repaired when damaged (symbolic/generated.py), compiled or loaded from numba's
    cache. progress(stage, fraction) as in generated.load_generated."""
    digest = stepper_digest(kernels)
    return load_generated(Path(kernels.__file__).with_name(f"stepper_{digest}.py"),
                          f"diskfriction_stepper_{digest}",
                          lambda: stepper_source(kernels, digest), progress)


@dataclass
class Frames:
    """Recorded frames (raw units): t (f,), q and v (f, ndof), energy (f, 5) columns
    (E_kin, U_n, U_load, W_t, W_slip), slip (f, N) signed distance slid at each substrate contact."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    energy: np.ndarray
    slip: np.ndarray

    @classmethod
    def empty(cls, n_frames: int, ndof: int, N: int) -> Frames:
        return cls(np.empty(n_frames), np.empty((n_frames, ndof)), np.empty((n_frames, ndof)),
                   np.empty((n_frames, 5)), np.empty((n_frames, N)))

    def head(self, n: int) -> Frames:
        return Frames(self.t[:n], self.q[:n], self.v[:n], self.energy[:n], self.slip[:n])


class Stepper:
    """The integrator's state (q, v, xi) and its bookkeeping, advanced in place.

    Construction writes frame 0; then `advance(n_steps)` any number of times (Python only
    between calls, never per step; a run split into calls is bit-identical to one call);
    `frames()` returns what was recorded every `stride` steps. breach_t[i] (-1 until it
    happens), breach_x[i]: first Coulomb cap at the substrate contact of disk i. slip[i]:
    signed distance the substrate contact of disk i has slid.
    """

    def __init__(self, system: System, q: np.ndarray, v: np.ndarray, xi: np.ndarray,
                 F_x: float, dt: float, stride: int, max_frames: int):
        if not (dt > 0 and np.isfinite(dt)):
            raise ValueError(f"dt must be a positive number (got {dt})")
        if stride < 1:
            raise ValueError(f"stride must be >= 1 (got {stride})")
        n, N = system.ndof, system.N
        if q.shape != (n,) or v.shape != (n,) or xi.shape != (2 * N,):
            raise ValueError(f"state shapes {q.shape}, {v.shape}, {xi.shape} do not fit "
                             f"ndof = {n}, 2N = {2 * N}")
        self.system, self.module = system, load_stepper(system.kernels)
        self.F_x, self.dt, self.stride = float(F_x), float(dt), int(stride)
        self.q, self.v, self.xi = (np.array(a, dtype=float) for a in (q, v, xi))
        self.mass = system.mass_diagonal()
        self.scal = np.zeros(3)  # t, W_t, W_slip
        self.ints = np.zeros(2, np.int64)  # steps, frames
        self.slip = np.zeros(N)
        self.breach_t, self.breach_x = np.full(N, -1.0), np.full(N, np.nan)
        self._frames = Frames.empty(max_frames, n, N)
        self.advance(0)  # frame 0

    @property
    def steps(self) -> int:
        return int(self.ints[0])

    @property
    def t(self) -> float:
        return float(self.scal[0])

    def advance(self, n_steps: int) -> None:
        """n_steps steps inside numba; raises if the frame buffer would overflow."""
        needed = (self.steps + n_steps) // self.stride - self.steps // self.stride
        if self.ints[1] + needed + (self.ints[1] == 0) > self._frames.t.size:
            raise ValueError(f"frame buffer of {self._frames.t.size} frames too small")
        fr = self._frames
        self.module.advance(self.q, self.v, self.xi, self.mass, self.F_x, self.system.params,
                            self.dt, n_steps, self.stride, self.scal, self.ints, self.slip,
                            self.breach_t, self.breach_x, fr.t, fr.q, fr.v, fr.energy, fr.slip)

    def frames(self) -> Frames:
        return self._frames.head(int(self.ints[1]))
