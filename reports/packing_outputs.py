"""A packing's shear branch as files and a figure (docs/packings.md#shear):
packing.npz, branch.npz, collisions.json, plastic.json and diagram.png of `diskfriction
bifurcate PACKING_SCENE`, and with `--damping` damped.json and precursors.csv (its damped
stability, docs/packings.md#damped-stability), written as one set (save_packing_outputs),
every file naming the scene it belongs to (scene_record, scene_arrays; other_scene finds a
directory's files of another scene)."""
from __future__ import annotations

import json
import os
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

from diskfriction.continuation.branch import Branch
from diskfriction.continuation.records import collisions_json, save_branch
from diskfriction.continuation.spectra.window import SpectralWindow
from diskfriction.files import json_values, save_json, save_text
from diskfriction.matrices import Matrix
from diskfriction.models.packing.contact_damping import ContactDamping
from diskfriction.models.packing.contact_onsets import clear_signs, contact_growth, contact_hopfs
from diskfriction.models.packing.damped import DampedHopf, damped_rates
from diskfriction.models.packing.equilibria import mass_diagonal
from diskfriction.models.packing.prepare import Packing, save_packing
from diskfriction.models.packing.precursors import EVENT_COLUMNS, drag_study, event_rows
from diskfriction.models.packing.shear import network_of
from diskfriction.models.packing.strain_statistics import state_weights, strain_mean, strain_statistics
from diskfriction.reports.figures import new_figure, save_figure
from diskfriction.reports.maps import csv_table
from diskfriction.scenes.packing import PackingScene

OUTPUTS = ("packing.npz", "branch.npz", "collisions.json", "plastic.json", "diagram.png")
"""The files of a packing's shear, written together (save_packing_outputs)."""

DAMPED_OUTPUTS = ("damped.json", "precursors.csv")
"""The files `bifurcate --damping` adds to OUTPUTS, in the same set (save_packing_outputs with
a DampedShear); a set written without one removes an earlier run's."""

RUN_SCENE = Path("segments") / "scene.json"
"""{"scene": scene_record} of a shear under way in DIR (models/packing/commands.py), beside its
segments."""

RECORDED = ("packing.npz", "packing.json", "branch.npz", "collisions.json", "plastic.json",
            "damped.json", RUN_SCENE, "summary.json", "run.npz", "verify.json")
"""The files of a packing scene in a directory that name their scene: bifurcate's (with
--damping's damped.json), prepare's (packing.npz, packing.json), a shear under way's,
simulate's and verify's."""


def scene_record(scene: PackingScene) -> dict:
    """What every output of a packing scene says it belongs to (JSON values): the scene's name,
    its file, N, k_n [force / length^p], seed, and physics: every field that enters the
    physics (PackingScene.physics_fields: the matrix analysed included)."""
    return {"name": scene.name, "file": scene.source, "N": scene.N, "k_n": scene.k_n,
            "seed": scene.seed, "physics": json_values(scene.physics_fields())}


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
    its name and each physics field, the matrix and spectra left out (options of the analysis,
    bifurcate --matrix and --spectra, not of the packing)."""
    mine = scene_record(scene)
    there, here = ({"name": r["name"], **r["physics"]} for r in (record, mine))
    keys = ["name"] + sorted((set(there) | set(here)) - {"name", "matrix", "spectra"})
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


def plastic_records(branch: Branch) -> list[dict]:
    """One record per plastic event passed, in order: its strain gamma, kind (how the branch was
    lost: models/packing/shear.py PLASTIC), the shear stress sigma_xy before and after and the drop
    before - after [force / length], the displacement |q_after - q_before| [length] and the
    relaxation's steps; and the complex pairs at the last equilibrium before it (the fold, at
    gamma; in the window, with one): their count (n_complex there) and the fastest growth rate
    sigma = |Im sqrt(lambda)| among them [1 / time] (models/packing/dynamics.fastest_pair; of M^-1
    J only, None with J, and None without a pair); both None where the shear took no spectrum
    at its states (spectra none or sample)."""
    from diskfriction.models.packing.dynamics import fastest_pair

    records = []
    for k, event in enumerate(branch.plastic):
        last = int(np.flatnonzero(branch.segment == k)[-1])  # event k ends segment k
        pairs = int(branch.n_complex[last])
        if pairs < 0:  # no spectrum at the states (spectra none or sample)
            records.append(plastic_record(event, None, None))
            continue
        lam = branch.eigenvalues[last]
        lam = lam[np.isfinite(lam)]
        if branch.window is not None:
            lam = lam[SpectralWindow(*branch.window).inside(lam)]
        growth = (fastest_pair(lam)[1] if pairs and branch.matrix == Matrix.M_INV_J else None)
        records.append(plastic_record(event, pairs, growth))
    return records


def plastic_record(event, pairs: Optional[int], growth: Optional[float]) -> dict:
    """plastic.json's record of one plastic event (plastic_records), its complex pairs and
    fastest growth rate given."""
    return {"gamma": event.gamma, "kind": event.kind, "sigma_xy_before": event.stress_before,
            "sigma_xy_after": event.stress_after, "drop": event.stress_before - event.stress_after,
            "displacement": event.displacement, "relaxation_steps": event.steps,
            "complex_pairs": pairs, "growth_rate": growth}


def save_packing_branch(out: Path, branch: Branch, scene: PackingScene) -> None:
    """branch.npz (continuation/records.branch_arrays: every per-point array of the shear's
    branch, raw units, the contact rows and histories left out, the segments and window runs
    as labels, plastic_gamma; the scene's resolved spectra and, with sampled spectra, the
    samples' pairs and eigenvalues; and scene_arrays), collisions.json (records.collisions_json
    with the spectra; its collisions null where none were looked for) and plastic.json
    (plastic_records), each naming the scene (scene_record)."""
    spectral = spectral_points(branch)
    samples = ({} if spectra_of(branch) != "sample" else
               {"sample_n_complex": spectral[1], "sample_eigenvalues": spectral[2]})
    save_branch(out / "branch.npz", branch, **scene_arrays(scene), spectra=np.array(scene.resolved_spectra),
                **samples)
    record = scene_record(scene)
    collisions = collisions_json(branch, scene=record, spectra=scene.resolved_spectra)
    if spectra_of(branch) != "full":  # none looked for: not an empty list
        collisions["collisions"] = None
    save_json(out / "collisions.json", collisions)
    save_json(out / "plastic.json", {"scene": record, "matrix": str(branch.matrix),
                                     "events": plastic_records(branch)})


@dataclass(frozen=True)
class DampedShear:
    """A shear's damped stability at the drags of `bifurcate --damping`
    (docs/packings.md#damped-stability): the drags [omega_0], in the order given, and
    eta = drag omega_0 [1 / time]; damping, what eta is the rate of: "drag" (the viscous drag
    -eta M q') or "dashpots" (contact dashpots of rate eta, models/packing/contact_damping.py
    ContactDamping(eta)); gamma, the strains whose spectra the shear computed (every accepted
    state with spectra full, the grid strains with sample: spectral_points); growth (drags,
    strains), the fastest damped growth rate there [1 / time] (the drag's
    models/packing/damped.fastest_damped: over every mode but the translations' zeros; the
    dashpots' contact_onsets.contact_growth); hopfs, each drag's onsets and ends of damped
    instability (damped_hopfs, or the states' contact_hopfs with dashpots), None where none were
    looked for (spectra sample); events, the precursor table (models/packing/precursors.event_rows:
    one row per plastic event and drag); unstable_fraction, per drag the fraction of the strain
    with a damped-unstable mode (growth > 0; models/packing/strain_statistics.py: each state or
    sample weighted by the strain it stands for)."""

    drags: tuple[float, ...]
    eta: tuple[float, ...]
    damping: str
    gamma: np.ndarray
    growth: np.ndarray
    hopfs: Optional[tuple[tuple[DampedHopf, ...], ...]]
    events: list[dict]
    unstable_fraction: tuple[float, ...]


def damped_shear(scene: PackingScene, packing: Packing, branch: Branch,
                 drags: tuple[float, ...], dashpots: bool = False) -> DampedShear:
    """The DampedShear of the shear of `scene` from `packing` at `drags` [omega_0 =
    scene.omega_0]: the viscous drag (the branch: spectra full or sample, of M^-1 J; with
    sampled spectra no state's spectrum is known at a plastic event, so the precursor rows'
    unstable_at_event is None (not known) there, as their growth_at_event), or with `dashpots`
    contact dashpots (_dashpot_shear: any spectra, any matrix, as their modes are solved at the
    accepted states)."""
    network = network_of(scene, packing)
    mass = mass_diagonal(network, scene.m, scene.inertia)
    eta = tuple(drag * scene.omega_0 for drag in drags)
    if dashpots:
        return _dashpot_shear(network, mass, branch, drags, eta, scene.omega_0)
    gamma, _, lam, _ = spectral_points(branch)
    growth = np.array([damped_rates(lam, e) for e in eta]).reshape(len(drags), len(gamma))
    if spectra_of(branch) == "full":
        points, events, statistics = drag_study(network, mass, branch, scene.omega_0, drags,
                                                scene.gamma_range[0])
        hopfs = tuple(points[drag] for drag in drags)
    else:  # sampled: no onset looked for
        hopfs = None
        events = event_rows(network, mass, branch, scene.omega_0, dict.fromkeys(drags, ()))
        statistics = strain_statistics(branch, eta, sampled=True, counted_from=scene.gamma_range[0])
    return DampedShear(drags, eta, "drag", gamma, growth, hopfs, events,
                       statistics.unstable_fraction)


def _dashpot_shear(network, mass: np.ndarray, branch: Branch, drags: tuple[float, ...],
                   eta: tuple[float, ...], omega_0: float) -> DampedShear:
    """damped_shear with contact dashpots ContactDamping(eta) at every drag (each > 0): each
    accepted state's largest growth rate g (contact_growth: one quadratic eigenproblem per state
    and drag, from the state alone, whatever the shear computed of the spectrum), the onsets and
    ends where g changes sign (contact_hopfs on those g), the precursor rows' growth at the
    event g at the last state before it, and the fraction of the strain where g is clearly
    positive (contact_onsets.clear_signs, as the onsets read it; each state weighted by
    strain_statistics.state_weights)."""
    growths = [contact_growth(network, mass, branch, ContactDamping(e)) for e in eta]
    hopfs = tuple(contact_hopfs(network, mass, branch, ContactDamping(e), growth=g)
                  for e, g in zip(eta, growths))
    growth = np.array([g for g, _ in growths]).reshape(len(drags), len(branch))
    at = dict(zip(drags, growth))
    events = event_rows(network, mass, branch, omega_0, dict(zip(drags, hopfs)),
                        lambda drag, k: at[drag][k])
    weights = state_weights(branch)
    fractions = tuple(strain_mean(clear_signs(*g) > 0, weights) for g in growths)
    return DampedShear(drags, eta, "dashpots", branch.gamma, growth, hopfs, events, fractions)


def hopf_record(hopf: DampedHopf) -> dict:
    """damped.json's record of one onset or end (a DampedHopf): gamma, kind, eigenvalue
    [Re, Im] of M^-1 J [1 / time^2] (null with contact dashpots: no eigenvalue of M^-1 J maps to
    the marginal exponent), frequency w [1 / time], the branch step holding it, the strain
    bracket, and how it was found: "refined" (to the bracket), "event" (the spectrum's jump at
    the contact event ending the step) or "step" (not refined: the bracket is the step)."""
    how = "event" if hopf.jump else "refined" if hopf.resolved else "step"
    lam = hopf.eigenvalue
    return {"gamma": hopf.gamma, "kind": hopf.kind,
            "eigenvalue": None if lam is None else [lam.real, lam.imag],
            "frequency": hopf.frequency, "step": hopf.step, "bracket": list(hopf.bracket), "found": how}


def damped_json(damped: DampedShear, scene: PackingScene) -> dict:
    """damped.json's object (docs/outputs.md): the scene record, the spectra, omega_0
    [1 / time], damping ("drag" or "dashpots": DampedShear.damping), sample_gamma (the grid
    strains, sampled spectra only) and per drag its drag, eta, points (hopf_record of each onset
    and end; null where none were looked for: sampled spectra), unstable_fraction
    (DampedShear.unstable_fraction) and sample_growth (each grid strain's fastest damped growth
    rate; sampled spectra only)."""
    sampled = damped.hopfs is None
    drags = [{"drag": drag, "eta": eta,
              "points": None if sampled else [hopf_record(h) for h in damped.hopfs[i]],
              "unstable_fraction": float(damped.unstable_fraction[i]),
              "sample_growth": damped.growth[i].tolist() if sampled else None}
             for i, (drag, eta) in enumerate(zip(damped.drags, damped.eta))]
    return {"scene": scene_record(scene), "spectra": scene.resolved_spectra,
            "omega_0": scene.omega_0, "damping": damped.damping,
            "sample_gamma": damped.gamma.tolist() if sampled else None, "drags": drags}


def save_damped(out: Path, damped: DampedShear, scene: PackingScene) -> None:
    """DAMPED_OUTPUTS: damped.json (damped_json) and precursors.csv (EVENT_COLUMNS, one row
    per plastic event and drag, floats with repr, empty where None; the header alone without
    a plastic event)."""
    save_json(out / "damped.json", damped_json(damped, scene))
    save_text(out / "precursors.csv", csv_table(list(EVENT_COLUMNS), damped.events))


def save_packing_outputs(out: Path, staging: Path, branch: Branch, scene: PackingScene,
                         packing: Packing, damped: Optional[DampedShear] = None) -> tuple[str, ...]:
    """OUTPUTS, every one naming the scene: packing.npz (save_packing), save_packing_branch's
    and diagram.png, and with `damped` DAMPED_OUTPUTS (save_damped), written to `staging`
    first and then renamed into `out` one after another, so that they replace an earlier
    run's files together (an earlier run's DAMPED_OUTPUTS removed without `damped`: they
    described its branch). Returns the names written."""
    save_packing(staging / "packing.npz", packing, scene_arrays(scene))
    save_packing_branch(staging, branch, scene)
    plot_packing_diagram(branch, scene, staging / "diagram.png")
    if damped is not None:
        save_damped(staging, damped, scene)
    names = OUTPUTS + (DAMPED_OUTPUTS if damped is not None else ())
    for name in names:
        os.replace(staging / name, out / name)
    if damped is None:
        for name in DAMPED_OUTPUTS:
            (out / name).unlink(missing_ok=True)
    return names


PLASTIC_STYLE = dict(colors="k", linestyles=[(0, (4, 2))], linewidths=1.3, zorder=5)
"""Plastic events in every packing figure against the strain: black dashed lines drawn over
everything else (zorder), so that no number of collision lines hides them."""


def eigenvalue_unit(matrix) -> str:
    """The unit of the eigenvalues of `matrix` on an axis: those of M^-1 J are omega^2
    [1 / time^2]; J's mix the disks' translations and rotations (raw units)."""
    return r"[time$^{-2}$]" if str(matrix) == str(Matrix.M_INV_J) else "[raw units]"


def strain_lines(ax, strains, **style):
    """One LineCollection of vertical lines across `ax` (its full height) at `strains`."""
    from matplotlib.collections import LineCollection

    strains = np.asarray(strains, dtype=float)
    segments = np.zeros((strains.size, 2, 2))
    segments[:, :, 0], segments[:, 1, 1] = strains[:, None], 1.0
    return ax.add_collection(LineCollection(segments, transform=ax.get_xaxis_transform(), **style),
                             autolim=False)


def spectra_of(branch: Branch) -> str:
    """What a shear's branch holds of the spectrum: "sample" (labelled samples,
    models/packing/sampled.py), "none" (no state's pairs counted: n_complex -1) or "full"."""
    if "sample" in branch.labelled:
        return "sample"
    return "none" if branch.n_complex.size and (branch.n_complex < 0).all() else "full"


def spectral_points(branch: Branch):
    """(gamma, n_complex, eigenvalues, window) of what the shear computed of the spectrum: every
    accepted state's (spectra full: the branch's columns), the grid strains' (sample: the
    samples' eigenvalues, rows padded with nan), or None (none)."""
    computed = spectra_of(branch)
    if computed == "none":
        return None
    if computed == "full":
        return branch.gamma, branch.n_complex, branch.eigenvalues, branch.window
    samples = branch.sample
    lam = np.full((len(samples), max((x.eigenvalues.size for x in samples), default=0)), np.nan + 0j)
    for row, x in zip(lam, samples):
        row[:x.eigenvalues.size] = x.eigenvalues
    return (np.array([x.gamma for x in samples]), np.array([x.n_complex for x in samples], dtype=int),
            lam, branch.window)


def plot_packing_diagram(branch: Branch, scene: PackingScene, path: Path) -> None:
    """Three panels against the shear strain gamma: the shear stress sigma_xy [force / length]
    with every collision as a thin line (red: a complex pair born, blue: one dying), the number
    of complex pairs, and Im lambda > 0 of every complex eigenvalue of the branch's matrix
    (eigenvalue_unit; for M^-1 J also in units of omega_0^2, omega_0 = PackingScene.omega_0, on
    the right). With a spectral window only what lies in it, lo <= Re lambda <= hi: the guard
    bands' eigenvalues are tracked, not counted (the window is named in the title). Plastic
    events: black dashed lines over everything in every panel, a triangle above the stress.
    What the shear computed of the spectrum (spectra_of) decides the rest: with sampled
    spectra the pairs and eigenvalues at the grid strains (no collision lines); without
    spectra the stress panel alone."""
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D

    from diskfriction.words import count

    spectral = spectral_points(branch)
    if spectral is None:  # spectra none: the stress alone
        fig, stress = new_figure(figsize=(7, 3.6))
        panels = (stress,)
    else:
        fig, panels = new_figure(3, 1, figsize=(7, 8.4), sharex=True)
        stress, pairs, im = panels
    gamma, window = branch.gamma, branch.window
    strain = r"shear strain $\gamma$"
    stress.add_collection(LineCollection(
        [np.column_stack([gamma[on], branch.stress[on, 2]])
         for on in (branch.segment == s for s in np.unique(branch.segment))],
        colors="k", linewidths=1, zorder=3))
    stress.autoscale_view()
    colors = ["tab:red" if str(c.kind) == "birth" else "tab:blue" for c in branch.collisions]
    strain_lines(stress, [c.p for c in branch.collisions], colors=colors, linewidths=0.4,
                 alpha=0.45, zorder=1)
    folds = [e.gamma for e in branch.plastic]
    for ax in panels:
        strain_lines(ax, folds, **PLASTIC_STYLE)
    if folds:  # (an empty line in axis coordinates breaks tight_layout)
        stress.plot(folds, np.ones(len(folds)), "v", color="k", ms=6, zorder=6, clip_on=False,
                    transform=stress.get_xaxis_transform())
    stress.set_ylabel(r"$\sigma_{xy}$ [force / length]")
    located = [Line2D([], [], color="tab:red", lw=1, label="birth of a complex pair"),
               Line2D([], [], color="tab:blue", lw=1, label="death of a complex pair")]
    stress.legend(handles=[*(located if spectra_of(branch) == "full" else []),
                           Line2D([], [], color="k", ls=(0, (4, 2)), lw=1.3, marker="v",
                                  label="plastic event (fold)")],
                  fontsize=7, loc="upper left", framealpha=0.9).set_zorder(7)
    title = (f"{scene.name}: N = {scene.N}, P = {scene.pressure:g}, mu = {scene.mu:g}; "
             f"{count(len(branch.plastic), 'plastic event')}")
    if spectral is None:
        stress.set_xlabel(strain)
        stress.set_title(f"{title}\nspectra none: no eigenvalue computed", fontsize=9, pad=10)
        fig.tight_layout()
        save_figure(fig, path)
        return
    gamma, n_complex, lam, window = spectral
    sampled = spectra_of(branch) == "sample"
    if sampled:
        pairs.plot(gamma, n_complex, ".-", color="k", lw=0.6, ms=3)
    else:
        pairs.step(gamma, n_complex, where="post", color="k", lw=1)
    pairs.set_ylim(-0.05 * max(1, n_complex.max(initial=0)), 1.05 * max(1, n_complex.max(initial=0)))
    pairs.set_ylabel("complex pairs" + (" in the window" if window is not None else "")
                     + (" (grid strains)" if sampled else ""))
    tracked = np.isfinite(lam)
    if window is not None:  # nan: a window column not tracked at that state
        tracked &= SpectralWindow(*window).inside(np.nan_to_num(lam, nan=np.inf))
    shown = tracked & (lam.imag > 1e-12 * np.nanmax(np.abs(lam), initial=0.0))  # one per pair
    g = np.broadcast_to(gamma[:, None], lam.shape)
    unit = eigenvalue_unit(branch.matrix)
    inside = "" if window is None else r", Re $\lambda$ in the window"
    if shown.any():
        im.plot(g[shown], lam.imag[shown], ".", ms=1.5 if not sampled else 3, color="tab:purple", zorder=6)
        part = "Im"
    elif not tracked.any():  # a window that held nothing
        im.text(0.02, 0.92, "no eigenvalue in the window", transform=im.transAxes, fontsize=8, va="top")
        part = "Im"
    else:  # a real spectrum (a frictionless packing): its softest mode, which vanishes at a fold
        positive = np.where(tracked & (lam.real > 1e-12 * np.nanmax(np.abs(lam))), lam.real, np.inf)
        im.semilogy(gamma, positive.min(axis=1), color="tab:green", lw=1, zorder=6)
        im.text(0.02, 0.92, "no complex eigenvalue on this branch: the softest mode",
                transform=im.transAxes, fontsize=8, va="top")
        part = "lowest Re"
    im.set_ylabel(rf"{part} $\lambda$ of {branch.matrix}{inside} {unit}")
    if str(branch.matrix) == str(Matrix.M_INV_J):
        w2 = scene.omega_0 ** 2
        im.secondary_yaxis("right", functions=(lambda v: v / w2, lambda v: v * w2)).set_ylabel(
            rf"{part} $\lambda / \omega_0^2$")
    im.set_xlabel(strain)
    title += (f"\nspectra sampled at {count(gamma.size, 'grid strain')}, no collision located" if sampled
              else f"; {count(len(branch.collisions), 'collision')}")
    if window is not None:
        title += (f"\nwindow {window[0]:g} <= Re lambda <= {window[1]:g} {unit}: its complex "
                  f"pairs and collisions only")
    stress.set_title(title, fontsize=9, pad=10)
    fig.tight_layout()
    save_figure(fig, path)


def growth_line(t: np.ndarray, y: np.ndarray, rate: float, span: np.ndarray) -> np.ndarray:
    """y0 e^(rate t) through the frames `span` (bool) of y > 0 in the least-squares sense,
    log y0 = mean(log y - rate t) over them; through y[0] when `span` holds none."""
    if not span.any():
        return y[0] * np.exp(rate * t)
    return np.exp(np.mean(np.log(y[span]) - rate * t[span]) + rate * t)


def plot_packing_run(t: np.ndarray, d: np.ndarray, sigma: float, measured: float,
                     scene: PackingScene, gamma: float, path: Path,
                     window: Optional[tuple[float, float]] = None,
                     amplitude: Optional[np.ndarray] = None) -> None:
    """A run from the state at gamma against time t [time] (log scale): the mass-weighted
    distance d = sqrt(sum m (q - q_eq)^2) from the state [mass^(1/2) length], the fastest
    pair's amplitude |c| where given (the growth fitted), the measured growth e^(measured t)
    over the fitted `window` (t_start, t_end) and the spectrum's e^(sigma t) over the whole run,
    both through the fitted frames (growth_line), so that their slopes compare. Without a
    window the lines go through the growth between ten times the start and a tenth of the
    largest value. A second time axis counts omega_0 t (PackingScene.omega_0)."""
    fig, ax = new_figure(figsize=(7, 4.3))
    ax.semilogy(t, np.maximum(d, 1e-300), color="k", lw=0.6,
                label=r"distance from the state, $\sqrt{\sum m\,(q - q_\mathrm{eq})^2}$")
    fitted = d
    if amplitude is not None and np.isfinite(amplitude).any():
        fitted = amplitude
        ax.semilogy(t, amplitude, color="tab:purple", lw=0.8,
                    label="amplitude |c| of the fastest pair")
    if window is not None and np.all(np.isfinite(window)):
        span = (t >= window[0]) & (t <= window[1]) & (fitted > 0)
    else:
        first = np.flatnonzero(fitted > 10 * fitted[0])
        last = np.flatnonzero(fitted >= 0.1 * np.nanmax(fitted))
        span = np.zeros(t.size, bool)
        if first.size and last.size:
            span[first[0]:last[0]] = True
    if sigma > 0:
        ax.semilogy(t, growth_line(t, fitted, sigma, span), "--", color="tab:red", lw=1,
                    label=r"spectrum: $e^{\sigma t}$, $\sigma = |\mathrm{Im}\sqrt{\lambda}|$ = "
                          f"{sigma:.4g}")
    if np.isfinite(measured) and span.any():
        ax.semilogy(t[span], growth_line(t, fitted, measured, span)[span], color="tab:orange",
                    lw=2.2, alpha=0.8, label=rf"measured: $\sigma$ = {measured:.4g} (fit)")
    shown = np.concatenate([d[d > 0], fitted[np.isfinite(fitted) & (fitted > 0)]])
    ax.set_ylim(max(shown.min(), 1e-16) / 2, shown.max() * 5)
    ax.set_xlabel("t [time]")
    omega_0 = scene.omega_0
    ax.secondary_xaxis("top", functions=(lambda x: x * omega_0, lambda x: x / omega_0)
                       ).set_xlabel(r"$\omega_0 t$")
    ax.set_ylabel(("distance, |c|" if fitted is not d else "distance") + r" [mass$^{1/2}$ length]")
    ax.set_title(f"{scene.name}: N = {scene.N}, gamma = {gamma:.4g}", fontsize=9)
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    save_figure(fig, path)


def key_value(largest: float) -> float:
    """A round arrow length for a quiver key: 1, 2 or 5 times a power of ten, at most `largest`."""
    power = 10.0 ** np.floor(np.log10(largest))
    return float(max(f for f in (1.0, 2.0, 5.0) if f * power <= largest * (1 + 1e-12)) * power)


def plot_packing_snapshot(q: np.ndarray, radii: np.ndarray, L: float, gamma: float,
                          rows: np.ndarray, force: np.ndarray, mode: np.ndarray,
                          title: str, path: Path, unit: str = "") -> None:
    """The packing at strain gamma in its sheared periodic box (the dashed parallelogram of the
    Lees-Edwards images): every disk with its images that reach into the box, clipped to it;
    every contact row with a normal force as a red line between the centres of width
    proportional to F_n (the legend names the widths in force units); and the (x, y) part of
    `mode` as arrows at the centres (the rotations are not drawn), scaled so that the longest
    is 0.8 of the smallest radius, with a key arrow of a round length in `unit`. A complex
    `mode` (an eigenvector V) is drawn as Re V (blue) and Im V (orange), the displacements a
    quarter period apart of the oscillation it carries; a zero `mode` draws no arrows. Lengths
    in the raw unit: the small disks' radius is R."""
    import textwrap

    from matplotlib.collections import LineCollection, PatchCollection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Polygon

    N = radii.size
    x, y = q[:N], q[N:2 * N]
    k = np.floor(y / L)
    y, x = y - k * L, x - k * gamma * L
    x = x - np.floor((x - gamma * y) / L) * L  # the centre inside the parallelogram
    shifts = np.array([(a * L + b * gamma * L, b * L) for a in (-1, 0, 1) for b in (-1, 0, 1)])
    fig, ax = new_figure(figsize=(6.6, 7.4))
    box = ax.add_patch(Polygon([(0, 0), (L, 0), (L + gamma * L, L), (gamma * L, L)], closed=True,
                               fill=False, ls="--", lw=0.6, color="k", zorder=4))
    cx, cy = x[None, :] + shifts[:, :1], y[None, :] + shifts[:, 1:]
    reach = np.broadcast_to(radii, cx.shape)
    near = ((cy > -reach) & (cy < L + reach) & (cx - gamma * cy > -reach)
            & (cx - gamma * cy < L + reach))
    disks = PatchCollection([Circle((a, b), r) for a, b, r in zip(cx[near], cy[near], reach[near])],
                            facecolor="0.92", edgecolor="0.55", lw=0.5)
    ax.add_collection(disks)
    disks.set_clip_path(box)
    i, j, ix, iy = rows.T
    carries = force > 0
    handles = []
    if carries.any():
        i, j, ix, iy, f = i[carries], j[carries], ix[carries], iy[carries], force[carries]
        dx = q[i] - q[j] - ix * L - iy * gamma * L  # r_i - r_j of the row's image
        dy = q[N + i] - q[N + j] - iy * L
        start = np.stack([x[i], y[i]], 1)
        segments = np.stack([start, start - np.stack([dx, dy], 1)], 1)
        segments = (segments[None] + shifts[:, None, None, :]).reshape(-1, 2, 2)
        width = 4.0 * f / f.max()
        lines = ax.add_collection(LineCollection(segments, linewidths=np.tile(width, len(shifts)),
                                                 colors="tab:red", zorder=2))
        lines.set_clip_path(box)
        handles = [Line2D([], [], color="tab:red", lw=w, label=f"$F_n$ = {v:.3g} [force]")
                   for w, v in ((4.0, f.max()), (1.0, f.max() / 4))]
    parts = ([("Re V", mode.real, "tab:blue"), ("Im V", mode.imag, "tab:orange")]
             if np.iscomplexobj(mode) else [("", mode, "tab:blue")])
    largest = max(float(np.hypot(p[:N], p[N:2 * N]).max()) for _, p, _ in parts)
    if largest > 0:
        scale = 0.8 * radii.min() / largest
        value = key_value(largest)
        for n, (name, part, color) in enumerate(parts):
            arrows = ax.quiver(x, y, scale * part[:N], scale * part[N:2 * N], angles="xy",
                               scale_units="xy", scale=1, color=color, width=0.003, zorder=3)
            ax.quiverkey(arrows, 0.03 + 0.3 * n, -0.1, scale * value,
                         " ".join(filter(None, (name + ":" if name else "", f"{value:g}", unit))),
                         labelpos="E",
                         coordinates="axes", fontproperties={"size": 8})
    pad = radii.max()
    ax.set_xlim(-pad, L + gamma * L + pad)
    ax.set_ylim(-pad, L + pad)
    ax.set_aspect("equal")
    R = radii.min()
    ax.set_xlabel(f"x [length; small disks' radius R = {R:g}]")
    ax.set_ylabel(f"y [length; R = {R:g}]")
    if handles:
        ax.legend(handles=handles, fontsize=8, loc="upper right", bbox_to_anchor=(1.0, -0.07),
                  frameon=False, title="contact force (line width)", title_fontsize=8)
    ax.set_title("\n".join(textwrap.fill(line, 100) for line in title.split("\n")), fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)
