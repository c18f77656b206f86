"""A packing's shear branch as files and a figure (issue 25, docs/packings.md#shear):
branch.npz, collisions.json and diagram.png of `diskfriction bifurcate PACKING_SCENE`."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from diskfriction.files import save_json, save_npz
from diskfriction.packings.shear import PackingBranch, collision_records
from diskfriction.reports.figures import new_figure, save_figure
from diskfriction.scenes.packing import PackingScene


def save_packing_branch(out: Path, branch: PackingBranch, scene: PackingScene) -> None:
    """branch.npz (every PackingBranch array, raw units) and collisions.json."""
    save_npz(out / "branch.npz", gamma=branch.gamma, q=branch.q, eigenvalues=branch.eigenvalues,
             condition=branch.condition,
             segment=branch.segment, plastic_gamma=np.array([e.gamma for e in branch.plastic]),
             n_complex=branch.n_complex, residual=branch.residual, contacts=branch.contacts,
             loose=branch.loose, stress=branch.stress, matrix=np.array(str(branch.matrix)),
             status=np.array(str(branch.status)))
    save_json(out / "collisions.json", {"scene": scene.name, "matrix": str(branch.matrix),
                                        "collisions": collision_records(branch)})


def plot_packing_diagram(branch: PackingBranch, scene: PackingScene, path: Path) -> None:
    """Three panels against the strain: the shear stress sigma_xy with the collisions marked,
    the number of complex pairs, and Im lambda of every complex eigenvalue (raw units of the
    matrix; a point per eigenvalue with Im lambda > 0)."""
    fig, (stress, pairs, im) = new_figure(3, 1, figsize=(7, 8), sharex=True)
    gamma = branch.gamma
    for segment in np.unique(branch.segment):
        on = branch.segment == segment
        stress.plot(gamma[on], branch.stress[on, 2], color="k", lw=1)
    for event in branch.plastic:
        for ax in (stress, pairs, im):
            ax.axvline(event.gamma, color="k", ls="--", lw=0.8)
    stress.set_ylabel("sigma_xy [force / length]")
    for c in branch.collisions:
        stress.axvline(c.p, color="tab:red" if str(c.kind) == "birth" else "tab:blue", lw=0.3,
                       alpha=0.5)
    pairs.step(gamma, branch.n_complex, where="post", color="k", lw=1)
    pairs.set_ylabel("complex pairs")
    lam = branch.eigenvalues
    g, values = np.broadcast_to(gamma[:, None], lam.shape), lam.imag
    shown = values > 1e-12 * np.nanmax(np.abs(lam))  # nan: a window column not tracked there
    im.plot(g[shown], values[shown], ".", ms=1.5, color="tab:purple")
    im.set_ylabel(f"Im lambda of {branch.matrix} (raw)")
    im.set_xlabel("shear strain gamma")
    stress.set_title(f"{scene.name}: N = {scene.N}, P = {scene.pressure:g}, mu = {scene.mu:g}; "
                     f"{len(branch.collisions)} collisions (red: birth, blue: death), "
                     f"{len(branch.plastic)} plastic events (dashed)", fontsize=9)
    fig.tight_layout()
    save_figure(fig, path)


def plot_packing_run(t: np.ndarray, d: np.ndarray, sigma: float, measured: float,
                     scene: PackingScene, gamma: float, path: Path) -> None:
    """The mass-weighted distance from the equilibrium against time (log), with e^(sigma t) of
    the spectrum's fastest complex pair and the measured slope."""
    fig, ax = new_figure(figsize=(7, 4))
    ax.semilogy(t, np.maximum(d, 1e-300), color="k", lw=0.6, label="|q - q_eq| (mass-weighted)")
    if sigma > 0:
        ax.semilogy(t, d[0] * np.exp(sigma * t), "--", color="tab:red", lw=1,
                    label=f"spectrum: sigma = {sigma:.4g}")
    if np.isfinite(measured):
        ax.plot([], [], " ", label=f"measured: sigma = {measured:.4g}")
    ax.set_ylim(max(d.min(), 1e-16) / 2, d.max() * 5)
    ax.set_xlabel("t (raw time)")
    ax.set_ylabel("distance [length x mass^(1/2)]")
    ax.set_title(f"{scene.name}: N = {scene.N}, gamma = {gamma:.4g}", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)


def plot_packing_snapshot(q: np.ndarray, radii: np.ndarray, L: float, gamma: float,
                          rows: np.ndarray, force: np.ndarray, mode: np.ndarray,
                          title: str, path: Path) -> None:
    """The packing at strain gamma in its sheared periodic box: disks as circles (positions
    wrapped into the box through the Lees-Edwards images), every contact row with a normal force
    as a line between the centres of width proportional to it, and the (x, y) part of `mode`
    (a displacement, e.g. an unstable eigenvector's real part) as arrows at the centres."""
    from matplotlib.collections import LineCollection, PatchCollection
    from matplotlib.patches import Circle, Polygon

    N = radii.size
    x, y = q[:N].copy(), q[N:2 * N].copy()
    k = np.floor(y / L)
    y, x = y - k * L, x - k * gamma * L
    x -= np.floor(x / L) * L
    fig, ax = new_figure(figsize=(6.5, 6.5))
    ax.add_collection(PatchCollection([Circle((a, b), r) for a, b, r in zip(x, y, radii)],
                                      facecolor="0.92", edgecolor="0.55", lw=0.5))
    i, j, cx, cy = rows.T
    carries = force > 0
    dx = q[i] - q[j] - cx * L - cy * gamma * L  # r_i - r_j of the row's image
    dy = q[N + i] - q[N + j] - cy * L
    segments = np.stack([np.stack([x[i], y[i]], 1), np.stack([x[i] - dx, y[i] - dy], 1)], 1)
    width = 4.0 * force / force.max() if carries.any() else force
    ax.add_collection(LineCollection(segments[carries], linewidths=width[carries],
                                     colors="tab:red"))
    xy = np.stack([mode[:N], mode[N:2 * N]], 1)
    scale = 0.8 * radii.min() / max(np.abs(xy).max(), 1e-300)
    ax.quiver(x, y, scale * xy[:, 0], scale * xy[:, 1], angles="xy", scale_units="xy", scale=1,
              color="tab:blue", width=0.003)
    ax.add_patch(Polygon([(0, 0), (L, 0), (L + gamma * L, L), (gamma * L, L)], closed=True,
                         fill=False, ls="--", lw=0.6, color="k"))
    ax.set_xlim(-radii.max(), L + gamma * L + radii.max())
    ax.set_ylim(-radii.max(), L + radii.max())
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    save_figure(fig, path)
