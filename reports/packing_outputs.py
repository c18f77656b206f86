"""A packing's shear branch as files and a figure (issue 25, docs/packings.md#shear):
packing.npz, branch.npz, collisions.json, plastic.json and diagram.png of `diskfriction
bifurcate PACKING_SCENE`, written as one set (save_packing_outputs), every file naming the
scene it belongs to (scene_record, scene_arrays; other_scene finds a directory's files of
another scene)."""
from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path
from typing import Optional

import numpy as np

from diskfriction.continuation.spectral_window import Window
from diskfriction.files import save_json, save_npz
from diskfriction.matrices import Matrix
from diskfriction.packings.prepare import Packing, save_packing
from diskfriction.packings.shear import PackingBranch, collision_records
from diskfriction.reports.figures import new_figure, save_figure
from diskfriction.scenes.packing import PackingScene

OUTPUTS = ("packing.npz", "branch.npz", "collisions.json", "plastic.json", "diagram.png")
"""The files of a packing's shear, written together (save_packing_outputs)."""

RUN_SCENE = Path("segments") / "scene.json"
"""{"scene": scene_record} of a shear under way in DIR (cli/packing_cmd.py), beside its
segments."""

RECORDED = ("packing.npz", "packing.json", "branch.npz", "collisions.json", "plastic.json",
            RUN_SCENE)
"""The files of a packing scene in a directory that name their scene: bifurcate's, prepare's
(packing.npz, packing.json) and a shear under way's."""


def scene_record(scene: PackingScene) -> dict:
    """What every output of a packing scene says it belongs to (JSON values): the scene's name,
    its file, N, k_n [force / length^p], seed, and physics: every field that enters the
    physics (PackingScene.physics_fields: the matrix analysed included)."""
    return {"name": scene.name, "file": scene.source, "N": scene.N, "k_n": scene.k_n,
            "seed": scene.seed, "physics": json.loads(json.dumps(scene.physics_fields()))}


def scene_arrays(scene: PackingScene) -> dict[str, np.ndarray]:
    """scene_record as 0-d arrays of an .npz: scene (the name), scene_file, N, k_n, seed and
    scene_physics (the physics fields as a JSON string)."""
    record = scene_record(scene)
    return {"scene": np.array(record["name"]), "scene_file": np.array(record["file"]),
            "N": np.array(record["N"]), "k_n": np.array(float(record["k_n"])),
            "seed": np.array(record["seed"]),
            "scene_physics": np.array(json.dumps(record["physics"], sort_keys=True))}


def recorded_scene(path: Path) -> Optional[dict]:
    """{"name", "file", "physics"} of the scene an output file names (an .npz's scene_arrays,
    a JSON file's "scene" object), or None: no such file, unreadable, or naming no scene."""
    try:
        if path.suffix == ".npz":
            with np.load(path, allow_pickle=False) as data:
                if "scene_physics" not in data.files:
                    return None
                return {"name": str(data["scene"]), "file": str(data["scene_file"]),
                        "physics": json.loads(str(data["scene_physics"]))}
        record = json.loads(path.read_text(encoding="utf-8")).get("scene")
    except (OSError, ValueError, EOFError, KeyError, AttributeError, zipfile.BadZipFile):
        return None
    return record if isinstance(record, dict) and isinstance(record.get("physics"), dict) else None


def scene_differences(record: dict, scene: PackingScene) -> list[str]:
    """How the scene `record` names differs from `scene`: "KEY THERE there, HERE here" for
    its name and each physics field, the matrix left out (an option of the analysis,
    bifurcate --matrix, not of the scene)."""
    mine = scene_record(scene)
    there, here = ({"name": r["name"], **r["physics"]} for r in (record, mine))
    keys = ["name"] + sorted((set(there) | set(here)) - {"name", "matrix"})
    return [f"{key} {json.dumps(there.get(key))} there, {json.dumps(here.get(key))} here"
            for key in keys if there.get(key) != here.get(key)]


def other_scene(out: Path, scene: PackingScene) -> Optional[tuple[Path, dict, list[str]]]:
    """(file, its scene_record, scene_differences) of the first file in `out` (RECORDED) that
    names a scene other than `scene`; None if none does."""
    for name in RECORDED:
        record = recorded_scene(out / name)
        if record is not None and (differ := scene_differences(record, scene)):
            return out / name, record, differ
    return None


def plastic_records(branch: PackingBranch) -> list[dict]:
    """One record per plastic event passed, in order: its strain gamma, kind (how the branch was
    lost: packings/shear.py PLASTIC), the shear stress sigma_xy before and after and the drop
    before - after [force / length], the displacement |q_after - q_before| [length] and the
    relaxation's steps; and the complex pairs at the last equilibrium before it (the fold, at
    gamma; in the window, with one): their count (n_complex there) and the fastest growth rate
    sigma = |Im sqrt(lambda)| among them [1 / time] (packings/dynamics.fastest_pair; of M^-1
    J only, None with J, and None without a pair)."""
    from diskfriction.packings.dynamics import fastest_pair

    records = []
    for k, event in enumerate(branch.plastic):
        last = int(np.flatnonzero(branch.segment == k)[-1])  # event k ends segment k
        pairs = int(branch.n_complex[last])
        lam = branch.eigenvalues[last]
        lam = lam[np.isfinite(lam)]
        if branch.window is not None:
            lam = lam[Window(*branch.window).inside(lam)]
        growth = (fastest_pair(lam)[1] if pairs and branch.matrix == Matrix.M_INV_J else None)
        records.append({"gamma": event.gamma, "kind": event.kind,
                        "sigma_xy_before": event.stress_before,
                        "sigma_xy_after": event.stress_after,
                        "drop": event.stress_before - event.stress_after,
                        "displacement": event.displacement, "relaxation_steps": event.steps,
                        "complex_pairs": pairs, "growth_rate": growth})
    return records


def save_packing_branch(out: Path, branch: PackingBranch, scene: PackingScene) -> None:
    """branch.npz (every PackingBranch array, raw units, and scene_arrays), collisions.json
    and plastic.json (plastic_records), each naming the scene (scene_record)."""
    save_npz(out / "branch.npz", gamma=branch.gamma, q=branch.q, eigenvalues=branch.eigenvalues,
             condition=branch.condition,
             segment=branch.segment, plastic_gamma=np.array([e.gamma for e in branch.plastic]),
             n_complex=branch.n_complex, residual=branch.residual, contacts=branch.contacts,
             loose=branch.loose, stress=branch.stress, matrix=np.array(str(branch.matrix)),
             status=np.array(str(branch.status)), **scene_arrays(scene))
    record = scene_record(scene)
    save_json(out / "collisions.json", {"scene": record, "matrix": str(branch.matrix),
                                        "collisions": collision_records(branch)})
    save_json(out / "plastic.json", {"scene": record, "matrix": str(branch.matrix),
                                     "events": plastic_records(branch)})


def save_packing_outputs(out: Path, staging: Path, branch: PackingBranch, scene: PackingScene,
                         packing: Packing) -> None:
    """OUTPUTS, every one naming the scene: packing.npz (save_packing), save_packing_branch's
    and diagram.png, written to `staging` first and then renamed into `out` one after
    another, so that they replace an earlier run's files together."""
    save_packing(staging / "packing.npz", packing, scene_arrays(scene))
    save_packing_branch(staging, branch, scene)
    plot_packing_diagram(branch, scene, staging / "diagram.png")
    for name in OUTPUTS:
        os.replace(staging / name, out / name)


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
