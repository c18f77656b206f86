"""The contact assembly and the history increment, written once, for both generated modules.

Two generated modules assemble the same contacts: the kernel module (symbolic/assembly_src.py:
`forces`, `history_increment`, `commit_history`, used by continuation) and the dynamics
stepper (dynamics/stepper_src.py: `advance`, the whole step loop). The step loop cannot call a
helper that takes arrays on every step (numba's reference counting would cost a quarter of a
step at N = 10), so the per-contact code is pasted into it as text. This module is the one
place that text is written: both sources mark where a fragment goes with a line

    ...  # @fragment NAME

(a statement, so that both sources stay valid Python) and `render` replaces each marker line by
the fragment NAME for the scene's conventions, indented as the marker. The conventions
(docs/physics.md) change only fragments, so a scene pays only for the ones it calls for: the
"model" fragments are the plain code.

Each fragment uses local names its host defines (the generated module supplies D,
pair_increment_coeffs, pair_force, pair_dofs, wall_*):
  pair_increment   k, N, R, w, idx, dq (displacement of every dof over the step), dxi,
                   dx0, dy0 (r_i - r_j of pair k at the start of the step), dx, dy (at the end):
                   adds d xi = s . dr_ij - R (dtheta_i + dtheta_j) of pair k to dxi[k], with the
                   tangent s at the middle of the step ("model", error O(|dq|^3)) or at its end
                   ("lammps", as LAMMPS integrates v_t dt with the current normal).
  wall_increment   k, N, R, w, idx, dq, dxi: adds d xi = dx_i + R dtheta_i to dxi[N + k].
  pair_force       k, N, R, k_n, k_t, mu, f, idx, F, dx, dy, delta_k, xi_k: adds the forces and
                   torques of pair k at separation (dx, dy), overlap delta_k, history xi_k to F.
  wall_force       k, N, R, k_n, k_t, mu, f, idx, F, delta_k, xi_k: the same for the substrate.
  first_contact    c, xi1, dxi, delta0, delta1: the history of contact c closing during the
                   step (delta0 <= 0 < delta1): the part of dxi after first contact, taking delta
                   linear along the step ("model"), or all of dxi ("lammps": a contact found
                   closed at the end of a step is charged with the whole step).
and, in the stepper only, the tangential work of a step (dynamics/stepper_src.py):
  arm_path_array   N: the array arm_path (the "lammps" lever arm's extra torque path).
  pair_arm_path    k, N, idx (after pair_increment), dq, delta, delta1, arm_path: with the
                   lever arm R - delta/2 the torques of a pair do the work
                   -(R - delta/2) F_t (dtheta_i + dtheta_j) = F_t (d xi - s . dr_ij) + F_t
                   (delta/2) (dtheta_i + dtheta_j): arm_path[k] = (delta/2)(dtheta_i +
                   dtheta_j), delta the mean over the step.
  tangential_work  c, ft, ft1, dxi, arm_path, w_t: adds the trapezoid work of contact c's
                   tangential force over its path, dxi[c] (+ arm_path[c]), to w_t.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from diskfriction.scenes.scene import CONVENTIONS

_PAIR_INCREMENT = """\
pair_increment_coeffs({tangent}, R, w)
pair_dofs(k, N, idx)
for a in range(2 * D):
    dxi[k] += w[a] * dq[idx[a]]"""

_TANGENTS = {"model": "0.5 * (dx0 + dx), 0.5 * (dy0 + dy)", "lammps": "dx, dy"}

_COMMON = {
    "wall_increment": """\
wall_increment_coeffs(R, w)
wall_dofs(k, N, idx)
for a in range(D):
    dxi[N + k] += w[a] * dq[idx[a]]""",
    "pair_force": """\
pair_force(dx, dy, delta_k, xi_k, R, k_n, k_t, mu, f)
pair_dofs(k, N, idx)
for a in range(2 * D):
    F[idx[a]] += f[a]""",
    "wall_force": """\
wall_force(delta_k, xi_k, R, k_n, k_t, mu, f)
wall_dofs(k, N, idx)
for a in range(D):
    F[idx[a]] += f[a]""",
}

_BY_CONVENTIONS = {
    "model": {
        "first_contact": "xi1[c] = dxi[c] * (delta1[c] / (delta1[c] - delta0[c]))",
        "arm_path_array": "",
        "pair_arm_path": "",
        "tangential_work": "w_t += 0.5 * (ft[c] + ft1[c]) * dxi[c]",
    },
    "lammps": {
        "first_contact": "xi1[c] = dxi[c]",
        "arm_path_array": "arm_path = np.zeros(2 * N)",
        "pair_arm_path": "arm_path[k] = 0.25 * (delta[k] + delta1[k]) * (dq[idx[D - 1]] + dq[idx[2 * D - 1]])",
        "tangential_work": "w_t += 0.5 * (ft[c] + ft1[c]) * (dxi[c] + arm_path[c])",
    },
}

MARKER = re.compile(r"^(?P<indent>[ \t]*)\.\.\.  # @fragment (?P<name>\w+)[ \t]*\n", re.MULTILINE)


@dataclass(frozen=True)
class Dialect:
    """What the fragments depend on: the conventions and whether the disks rotate (the lever
    arm's extra path needs the angle dofs)."""

    conventions: str = "model"
    rotation: bool = True

    def __post_init__(self):
        if self.conventions not in CONVENTIONS:
            raise ValueError(f"unknown conventions {self.conventions!r}")

    def fragments(self) -> dict[str, str]:
        """Every fragment's text for this dialect, by name."""
        out = dict(_COMMON)
        out["pair_increment"] = _PAIR_INCREMENT.format(tangent=_TANGENTS[self.conventions])
        out.update(_BY_CONVENTIONS[self.conventions])
        if not self.rotation:
            out["pair_arm_path"] = ""
        return out


def _lines(text: str, indent: str) -> str:
    """`text` as lines with `indent` before each; an empty fragment leaves no line at all."""
    return "".join(f"{indent}{line}\n" for line in text.splitlines())


def render(source: str, dialect: Dialect) -> str:
    """`source` with every `...  # @fragment NAME` line replaced by the fragment NAME; an unknown
    NAME raises KeyError (a host naming a fragment that does not exist)."""
    fragments = dialect.fragments()
    return MARKER.sub(lambda match: _lines(fragments[match["name"]], match["indent"]), source)
