"""Bifurcation outputs: branch.npz, collisions.json and the diagram (the paper's Fig. 2).

Files hold raw units (MODEL.md: m = 1, 2R = 1, k_n = 2000); the diagram shows the paper's units
(reports/units.py: eigenvalues / k_n for the paper's scene) and F_x as the paper quotes it.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from diskfriction.continuation.sweep import DiskBranch
from diskfriction.reports.files import save_json, save_npz, write_atomic
from diskfriction.reports.units import F_X_LABEL, PaperUnits, eig_label
from diskfriction.scenes import Scene


def collision_records(branch: DiskBranch) -> list[dict]:
    """One JSON object per located collision of the requested leg, raw units.

    At a collision the two eigenvalues coincide on the real axis: lambda_im is 0 by definition
    and lambda_re is the double eigenvalue. `bracket` is the F_x interval (width <= 1e-10)
    across which the count of complex pairs changes; `eigenvector` and `jordan_vector` form the
    Jordan chain (A - lambda) v = 0, (A - lambda) w = v of the stability matrix.
    """
    return [{"F_x": float(c.p), "kind": c.kind, "lambda_re": float(c.eigenvalue), "lambda_im": 0.0,
             "matrix": branch.matrix, "bracket": [float(b) for b in c.bracket],
             "resolved": bool(c.resolved), "residual": float(c.residual),
             "eigenvector": np.asarray(c.eigenvector, dtype=float).tolist(),
             "jordan_vector": np.asarray(c.generalized_eigenvector, dtype=float).tolist()}
            for c in branch.collisions]


def save_branch(out: Path, branch: DiskBranch, scene: Scene) -> None:
    """DIR/branch.npz (every accepted point: F_x, q, xi, eigenvalues, n_complex, residual,
    leg) and DIR/collisions.json, each written atomically."""
    save_npz(Path(out) / "branch.npz", F_x=branch.F_x, q=branch.q, xi=branch.xi,
             eigenvalues=branch.eigenvalues, n_complex=branch.n_complex,
             residual=branch.residual, leg=branch.leg, matrix=np.array(branch.matrix),
             k_n=np.array(scene.k_n), N=np.array(scene.N))
    save_json(Path(out) / "collisions.json", collision_records(branch))


def draw_spectrum(top, bottom, F_x: np.ndarray, lam: np.ndarray, leg: np.ndarray,
                  collisions: list[tuple[float, str, float]], matrix: str) -> None:
    """Im (top) and Re (bottom, symlog) of every eigenvalue `lam` (rows: points at F_x, already
    in the paper's unit of `matrix`) against F_x; the requested leg (1) in colour, a preparation
    leg (0) in grey; collisions (F_x, "birth" | "death", double eigenvalue in the same unit)
    marked ^ (birth) and v (death). Plots only: no physics."""
    F = np.repeat(F_x[:, None], lam.shape[1], axis=1)
    for leg_id, style in ((0, dict(color="0.75", s=2)), (1, dict(color="C0", s=3))):
        rows = leg == leg_id
        complex_ = rows[:, None] & (np.abs(lam.imag) > 0) & (lam.imag >= 0)
        top.scatter(F[complex_], lam.imag[complex_], **style)
        bottom.scatter(F[rows], lam.real[rows], **style)
    for p, kind, value in collisions:
        marker, color = ("^", "C3") if kind == "birth" else ("v", "C2")
        for ax in (top, bottom):
            ax.axvline(p, color=color, lw=0.4, alpha=0.5)
        bottom.plot(p, value, marker, color=color, ms=5)
        top.plot(p, 0.0, marker, color=color, ms=5)
    top.set_ylabel(eig_label("Im", matrix))
    bottom.set_ylabel(eig_label("Re", matrix))
    bottom.set_yscale("symlog", linthresh=1e-4)
    bottom.set_xlabel(F_X_LABEL)


def plot_diagram(branch: DiskBranch, scene: Scene, path: Path) -> None:
    """Im(lambda) (top) and Re(lambda) (bottom) of every eigenvalue against F_x in the paper's
    units (lambda / k_n for the paper's scene), births (^) and deaths (v) marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    unit = PaperUnits.of(scene).eigenvalue(branch.matrix)
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 6.5))
    draw_spectrum(top, bottom, branch.F_x, branch.eigenvalues / unit, branch.leg,
                  [(c.p, c.kind, c.eigenvalue / unit) for c in branch.collisions], branch.matrix)
    top.set_title(f"{scene.name}: spectrum of {branch.matrix}, N = {scene.N}; "
                  f"births ^ ({sum(c.kind == 'birth' for c in branch.collisions)}), "
                  f"deaths v ({sum(c.kind == 'death' for c in branch.collisions)})", fontsize=9)
    fig.tight_layout()
    write_atomic(Path(path), lambda tmp: fig.savefig(tmp, dpi=110, format="png"))
    plt.close(fig)
