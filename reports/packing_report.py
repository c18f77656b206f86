"""The packing section of the report (issue 25, docs/packings.md#report): `diskfriction report
PACKING_SCENE` shears the scene's packing, runs the dynamics from two of its states and writes
report.md with four figures:

- stress.png: sigma_xy against gamma, the strains where the state carries complex pairs shaded,
  plastic events dashed;
- spectrum.png: the lowest eigenvalues of M^-1 J against gamma (real grey, complex red) and the
  fastest pair's growth rate sigma = |Im sqrt(lambda)|;
- snapshot.png: the packing at the state of fastest growth, contact forces as line widths and
  that pair's eigenvector as arrows;
- msd.png: the mean squared displacement of the network's disks (loose disks, free to drift,
  left out) in runs from that state and from a state with every eigenvalue real (the last on
  the branch; the same random velocities of amplitude AMPLITUDE on the network's disks), or the
  one run when no such state exists on the branch (said in the report).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from diskfriction.files import save_text
from diskfriction.packings.dynamics import (fastest_pair, mean_squared_displacement, simulate,
                                            time_step)
from diskfriction.packings.equilibria import PackingEquilibria
from diskfriction.packings.runs import fastest_mode
from diskfriction.packings.shear import PackingBranch, shear_scene
from diskfriction.reports.figures import new_figure, save_figure
from diskfriction.reports.packing_outputs import plot_packing_snapshot
from diskfriction.scenes.packing import PackingScene

AMPLITUDE = 1e-6
"""Random initial velocities of the MSD runs, per dof [length / time]: small against a contact's
overlap over a period, so that a run from a stable state stays near it."""

PERIODS = 400
"""The MSD runs last this many periods 2 pi / omega_min of the state's slowest mode."""

LOWEST = 24
"""Eigenvalues drawn in spectrum.png: the LOWEST of each state by real part."""


@dataclass(frozen=True)
class MsdRun:
    """One MSD run: the state's strain and index on the branch, its complex pairs and fastest
    growth rate, t and MSD(t), and the sliding updates (contacts that reached Coulomb)."""

    label: str
    k: int
    gamma: float
    pairs: int
    sigma: float
    t: np.ndarray
    msd: np.ndarray
    slid: int


def build_packing_report(scene: PackingScene, out: Path, plastic_events: int,
                         progress: Optional[Callable[[str], None]] = None) -> list[str]:
    """Shear, run, draw and write out/report.md; returns the files written."""
    say = progress or (lambda line: None)
    branch, network, mass = shear_scene(scene, plastic_events, say)
    sigma = np.array([fastest_pair(e)[1] for e in branch.eigenvalues])
    fast = int(np.argmax(sigma))
    real = np.flatnonzero(branch.n_complex == 0)
    runs = []
    for label, k in [("complex", fast)] + ([("real", int(real[-1]))] if real.size else []):
        say(f"dynamics from the {label} state at gamma = {branch.gamma[k]:.4g}")
        runs.append(msd_run(branch, k, label, network, mass, sigma[k], scene))
    plot_stress(branch, scene, out / "stress.png")
    plot_spectrum(branch, sigma, scene, out / "spectrum.png")
    mode = fastest_mode(branch, fast, network, mass, scene.matrix)
    force = network.normal_forces(branch.q[fast], branch.rows[fast], branch.gamma[fast])
    plot_packing_snapshot(branch.q[fast], network.radii, network.L, branch.gamma[fast],
                          branch.rows[fast], force, mode,
                          f"{scene.name} at gamma = {branch.gamma[fast]:.4g}: contact forces "
                          f"(red, width ~ F_n), the fastest pair's eigenvector (blue)",
                          out / "snapshot.png")
    plot_msd(runs, scene, out / "msd.png")
    save_text(out / "report.md", report_text(scene, branch, sigma, runs))
    return ["report.md", "stress.png", "spectrum.png", "snapshot.png", "msd.png"]


def msd_run(branch: PackingBranch, k: int, label: str, network, mass: np.ndarray,
            sigma: float, scene: PackingScene) -> MsdRun:
    """Random velocities (AMPLITUDE, seed 0) of the network's disks, their centre-of-mass
    velocity removed, from state k, run PERIODS slowest periods; the MSD over the network's
    disks (a loose disk would drift freely)."""
    lam = branch.eigenvalues[k]
    slowest = float(np.sqrt(np.min(np.abs(lam[lam != 0]))))
    loose = PackingEquilibria(network, branch.q[k], branch.xi[k], branch.rows[k],
                              branch.gamma[k], mass, scene.matrix).gauge.loose
    v = AMPLITUDE * np.random.default_rng(0).normal(size=branch.q[k].size)
    v[np.tile(loose, 3)] = 0.0
    N = network.N
    for axis in (slice(0, N), slice(N, 2 * N)):  # no centre-of-mass drift
        v[axis] -= np.where(loose, 0.0, np.sum(mass[axis] * v[axis]) / np.sum(mass[axis][~loose]))
    run = simulate(network, branch.q[k], v, branch.xi[k], branch.rows[k], branch.gamma[k],
                   mass, time_step(lam), PERIODS * 2 * np.pi / slowest, frames=400)
    return MsdRun(label, k, float(branch.gamma[k]), int(branch.n_complex[k]), float(sigma),
                  run.t, mean_squared_displacement(run, network.N, ~loose), int(run.capped[-1]))


def complex_spans(gamma: np.ndarray, n_complex: np.ndarray) -> list[tuple[float, float]]:
    """The strain intervals [a, b] between accepted points over which the state carries complex
    pairs (a point with pairs extends its span to the next point)."""
    spans, start = [], None
    for k in range(gamma.size):
        if n_complex[k] > 0 and start is None:
            start = gamma[k]
        if start is not None and (n_complex[k] == 0 or k == gamma.size - 1):
            spans.append((float(start), float(gamma[k])))
            start = None
    return spans


def plot_stress(branch: PackingBranch, scene: PackingScene, path: Path) -> None:
    fig, ax = new_figure(figsize=(7, 4))
    for a, b in complex_spans(branch.gamma, branch.n_complex):
        ax.axvspan(a, b, color="tab:red", alpha=0.12, lw=0)
    for segment in np.unique(branch.segment):
        on = branch.segment == segment
        ax.plot(branch.gamma[on], branch.stress[on, 2], color="k", lw=1)
    for event in branch.plastic:
        ax.axvline(event.gamma, color="k", ls="--", lw=0.8)
    ax.set_xlabel("shear strain gamma")
    ax.set_ylabel("sigma_xy [force / length]")
    ax.set_title(f"{scene.name}: N = {scene.N}, P = {scene.pressure:g}, mu = {scene.mu:g}; "
                 f"shaded: complex pairs ({100 * np.mean(branch.n_complex > 0):.0f} % of the "
                 f"states); dashed: {len(branch.plastic)} plastic events", fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)


def plot_spectrum(branch: PackingBranch, sigma: np.ndarray, scene: PackingScene, path: Path) -> None:
    fig, (low, rate) = new_figure(2, 1, figsize=(7, 6.5), sharex=True)
    for g, lam in zip(branch.gamma, branch.eigenvalues):
        lam = lam[lam != 0]
        lam = lam[np.argsort(lam.real)][:LOWEST]
        cx = np.abs(lam.imag) > 1e-9 * np.abs(lam).max()
        low.plot(np.full((~cx).sum(), g), lam.real[~cx], ".", ms=1.5, color="0.5")
        low.plot(np.full(cx.sum(), g), lam.real[cx], ".", ms=2.5, color="tab:red")
    low.set_ylabel(f"Re lambda of {branch.matrix}, lowest {LOWEST} (raw)")
    low.set_title(f"{scene.name}: grey real, red complex", fontsize=8)
    rate.plot(branch.gamma, sigma, ".", ms=2, color="tab:red")
    rate.set_ylabel("fastest growth rate |Im sqrt(lambda)|")
    rate.set_xlabel("shear strain gamma")
    fig.tight_layout()
    save_figure(fig, path)


def plot_msd(runs: list[MsdRun], scene: PackingScene, path: Path) -> None:
    fig, ax = new_figure(figsize=(7, 4))
    for run, color in zip(runs, ("tab:red", "tab:blue")):
        ax.loglog(run.t[1:], np.maximum(run.msd[1:], 1e-300), color=color, lw=1,
                  label=f"{run.label} state, gamma = {run.gamma:.4g}, {run.pairs} pairs, "
                        f"sigma = {run.sigma:.3g}, {run.slid} sliding updates")
    ax.set_xlabel("t (raw time)")
    ax.set_ylabel("MSD [length^2]")
    ax.set_title(f"{scene.name}: random velocities of amplitude {AMPLITUDE:g}", fontsize=8)
    ax.legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, path)


def report_text(scene: PackingScene, branch: PackingBranch, sigma: np.ndarray,
                runs: list[MsdRun]) -> str:
    lines = [f"# Packing report: {scene.name}", "",
             f"N = {scene.N}, P = {scene.pressure:g}, mu = {scene.mu:g}, seed {scene.seed}; "
             f"sheared to gamma = {branch.gamma[-1]:.6g} ({branch.status.sentence(len(branch))}); "
             f"{len(branch)} equilibria, {len(branch.collisions)} collisions, {len(branch.plastic)} plastic "
             f"events; complex pairs at {100 * np.mean(branch.n_complex > 0):.0f} % of the "
             f"states (at most {branch.n_complex.max()}); fastest growth rate "
             f"{sigma.max():.4g} at gamma = {branch.gamma[int(np.argmax(sigma))]:.6g}.", "",
             "![stress](stress.png)", "", "![spectrum](spectrum.png)", "",
             "![snapshot](snapshot.png)", "", "![msd](msd.png)", "",
             "| run | gamma | complex pairs | sigma | MSD at the end | sliding updates |",
             "|---|---|---|---|---|---|"]
    lines += [f"| {r.label} | {r.gamma:.6g} | {r.pairs} | {r.sigma:.4g} | {r.msd[-1]:.3g} | "
              f"{r.slid} |" for r in runs]
    if len(runs) == 1:
        lines += ["", "No state of the branch has every eigenvalue real: there is no real "
                      "state to compare with."]
    return "\n".join(lines) + "\n"
