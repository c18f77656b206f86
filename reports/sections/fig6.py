"""Fig. 6: the pure y shear-wave eigenmode of J projected on x, y, theta (l = 1..3N)."""
from __future__ import annotations

import numpy as np

from diskfriction.reports.registry import Section
from diskfriction.reports.figures import new_figure
from diskfriction.reports.sections.common import failures, mode_needs, table


def needs(scene, settings):
    return mode_needs(scene, settings)


def mode_numbers(mode: dict, units) -> dict:
    """omega [1/tau], wavelength [2R], V2 = omega / k [2R/tau] of a shear_mode result."""
    return {"omega": mode["omega"] * units.time, "wavelength": mode["wavelength"] / units.length,
            "V2": mode["V2"] / units.velocity}


def plot(ctx, found):
    fig, axes = new_figure(len(found), 1, figsize=(8, 2.6 * len(found)), squeeze=False)
    N = ctx.scene.N
    for ax, (label, mode) in zip(axes[:, 0], found):
        v = mode["vector"]
        l = np.arange(1, 3 * N + 1)
        for part, (lo, color) in enumerate(((0, "C0"), (N, "C3"), (2 * N, "C2"))):
            ax.bar(l[lo:lo + N], v[lo:lo + N], color=color, label=("x", "y", r"$R\theta$")[part])
        num = mode_numbers(mode, ctx.units)
        ax.set_title(f"{label}: omega = {num['omega']:.4f} / tau, wavelength = "
                     f"{num['wavelength']:.3g} (2R), V2 = {num['V2']:.4f} 2R/tau; weight on y "
                     f"{mode['w_y']:.4f}", fontsize=8)
        ax.set_ylabel(r"$q_\ell$ component (unit norm)")
        ax.axhline(0, color="k", lw=0.5)
        ax.legend(fontsize=7, ncol=3)
    axes[-1, 0].set_xlabel(r"$\ell$ (1..N: x, N+1..2N: y, 2N+1..3N: $R\theta$; lengths in 2R)")
    fig.tight_layout()
    return fig


def render(ctx):
    found = [(need.label, ctx.get(need.label)) for need in mode_needs(ctx.scene, ctx.settings)]
    found = [(label, mode) for label, mode in found if mode is not None]
    text = []
    if found:
        text.append(ctx.figure(plot(ctx, found), "fig6", "Fig. 6: the eigenvector of J with "
                               "most weight on one y wave, components on x, y and R theta"))
        rows = []
        for label, mode in found:
            num = mode_numbers(mode, ctx.units)
            rows.append([label, f"{mode['lambda_J'] / ctx.units.eig_J:.5f}", f"{num['omega']:.4f}",
                         f"{mode['n']}", f"{num['wavelength']:.3g}", f"{num['V2']:.4f}",
                         f"{mode['w_y']:.5f}", f"{mode['purity']:.3f}", f"{mode['runner_up']:.3f}",
                         f"{np.min(mode['pair_overlaps']):.2e} .. {np.max(mode['pair_overlaps']):.2e}"])
        text.append(table(["state", "lambda_J [k_n (2R)^1/2]", "omega [1/tau]", "n", "wavelength [2R]",
                           "V2 = omega/k [2R/tau]", "weight on y", "wave purity", "next best score",
                           "pair overlaps [raw length]"], rows))
    s = ctx.scene
    omega0 = np.sqrt(s.kappa_w0 / s.m) * ctx.units.time
    text.append(
        "Selection (reports/compute/branches.py `shear_mode`): every real eigenvector of J, theta "
        "scaled by R and normalised, scored by (weight on y) x (fraction of its y pattern in one "
        "wavenumber n != 0); the best is shown. omega^2 is the eigenvalue of M^-1 J whose "
        "eigenvector overlaps it most. The paper does not say at which F_x it took the mode. "
        "On the paper's branch (eps = 0) the pair contacts are compressed only near disk 1 and "
        "the pair across the boundary is open, so no eigenvector is a clean plane wave there; "
        "a ring with uniform pre-compression (second row) has the exact pure-y mode of "
        "wavelength 2 (alternating disks; pair and substrate shear decouple from theta at "
        f"k = pi). At eps = 0, F_x = 0 all y-modes are degenerate at omega tau = "
        f"(1.5 k_n delta_w^(1/2) / m)^(1/2) tau = {omega0:.4f} (docs/model.md#units), the eps -> 0 limit "
        f"of the second row; wavelength 2 then gives V2 = {omega0:.4f}/pi = {omega0 / np.pi:.4f}.\n")
    return "\n".join(text) + failures(ctx)


SECTION = Section("fig6", "Fig. 6: the pure y shear-wave eigenmode", needs, render)
