"""The packing section of the report (docs/packings.md#report): `diskfriction report
PACKING_SCENE` shears the scene's packing, runs the dynamics from two of its states and writes
report.md with four figures:

- stress.png: sigma_xy against gamma, the strains where the state carries complex pairs shaded,
  plastic events dashed, the two states of the MSD runs marked;
- spectrum.png: the lowest eigenvalues of the branch's matrix against gamma (real grey, complex
  red) and the fastest pair's |Im sqrt(lambda)| (of M^-1 J: the growth rate sigma), plastic
  events dashed, the two states marked;
- snapshot.png: the packing at the complex state, contact forces as line widths and the right
  eigenvector V of that state's fastest pair of M^-1 J as arrows, Re V and Im V (at the real
  state with the forces alone when no state carries a complex pair);
- msd.png: the mean squared displacement of the network's disks (loose disks, free to drift,
  left out) in runs from the complex state and from the real state (the same random velocities
  of amplitude AMPLITUDE on the network's disks), sampled from t = 0 (sampled_msd), on log
  axes.

The two states (quiet_state): the state with complex pairs, and the state with every eigenvalue
real, farthest in strain from the ends of its interval (the collisions where such states begin
and end, a plastic event, the start or end of the shear) and from every contact event inside
it (Branch.event: where a step of the shear was cut at one). Near a fold the saddle-node's
eigenvalue, going to zero, mixes into the dynamics, and at a contact event a contact sits at delta = 0, where its Hertz stiffness
vanishes; neither is the instability of the complex pair. A branch without one kind of state
has no run of that kind, and report.md says so.
"""
from __future__ import annotations

import dataclasses

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from diskfriction.continuation.branch import Branch
from diskfriction.files import save_text
from diskfriction.matrices import Matrix
from diskfriction.models.packing.dynamics import (fastest_pair, mean_squared_displacement, simulate,
                                            time_step)
from diskfriction.models.packing.runs import linearized
from diskfriction.models.packing.shear import shear_scene
from diskfriction.reports.figures import new_figure, save_figure
from diskfriction.reports.packing_outputs import (PLASTIC_STYLE, eigenvalue_unit,
                                                  plot_packing_snapshot, strain_lines)
from diskfriction.scenes.packing import PackingScene

AMPLITUDE = 1e-6
"""Random initial velocities of the MSD runs, per dof [length / time]: small against a contact's
overlap over a period, so that a run from a stable state stays near it."""

PERIODS = 400
"""The MSD runs last this many periods 2 pi / omega_min of the state's slowest mode."""

FRAMES = 400
"""Frames of each of the runs an MSD is sampled from (sampled_msd), evenly spaced in its time."""

LOWEST = 24
"""Eigenvalues drawn in spectrum.png: the LOWEST of each state by real part."""

COLORS = {"complex": "tab:red", "real": "tab:blue"}
"""The colour of each MSD run and of its state's marks."""


@dataclass(frozen=True)
class MsdRun:
    """One MSD run: the state's kind ("complex" or "real"), index on the branch and strain, its
    strain clearance (quiet_state), its complex pairs of M^-1 J and fastest growth rate sigma
    [1 / time], t [time] and MSD(t) [length^2] from t = 0, and the sliding updates (contacts
    that reached their Coulomb limit)."""

    label: str
    k: int
    gamma: float
    clearance: float
    pairs: int
    sigma: float
    t: np.ndarray
    msd: np.ndarray
    slid: int


def build_packing_report(scene: PackingScene, out: Path, plastic_events: int,
                         progress: Optional[Callable[[str], None]] = None) -> list[str]:
    """Shear, run, draw and write out/report.md; returns the files written."""
    say = progress or (lambda line: None)
    # every state's spectrum and every collision: the report's figures and runs are drawn from them
    branch, network, mass = shear_scene(dataclasses.replace(scene, spectra="full"), plastic_events, say)
    sigma = np.array([fastest_pair(e)[1] for e in branch.eigenvalues])
    events = np.array([e.p for e in branch.event] + [e.gamma for e in branch.plastic])
    bounds = [c.p for c in branch.collisions]
    runs, linear = [], {}
    for label, chosen in (("complex", branch.n_complex > 0), ("real", branch.n_complex == 0)):
        state = quiet_state(branch.gamma, chosen, branch.segment, bounds, events)
        if state is None:
            continue
        k, clearance = state
        linear[label] = linearized(branch, k, network, mass)
        say(f"dynamics from the {label} state at gamma = {branch.gamma[k]:.4g}")
        runs.append(msd_run(branch, k, label, clearance, network, mass, linear[label], scene))
    plot_stress(branch, runs, scene, out / "stress.png")
    plot_spectrum(branch, sigma, runs, scene, out / "spectrum.png")
    shown = runs[0]  # the complex state's, where there is one
    q, rows, gamma = branch.q[shown.k], branch.rows[shown.k], shown.gamma
    mode = linear[shown.label].mode
    if mode is None:
        arrows, what = np.zeros(q.size), "every eigenvalue is real at every state: no mode drawn"
    else:
        arrows = mode.right
        what = (f"the fastest pair of M^-1 J, lambda = {mode.lam.real:.4g} +- "
                f"{abs(mode.lam.imag):.3g} i [1/time^2], sigma = |Im sqrt(lambda)| = "
                f"{mode.sigma:.3g} [1/time]: its right eigenvector V as arrows, Re V (blue) and "
                f"Im V (orange), a quarter period apart (phase of the largest excursion)")
    plot_packing_snapshot(q, network.radii, network.L, gamma, rows,
                          network.normal_forces(q, rows, gamma), arrows,
                          f"{scene.name} at gamma = {gamma:.4g} ({shown.label} state): contact "
                          f"forces (red); {what}", out / "snapshot.png",
                          unit=r"($|\mathrm{Re}\,V|_M$ = 1)")
    plot_msd(runs, scene, out / "msd.png")
    save_text(out / "report.md", report_text(scene, branch, sigma, runs))
    return ["report.md", "stress.png", "spectrum.png", "snapshot.png", "msd.png"]


def quiet_state(gamma: np.ndarray, chosen: np.ndarray, segment: np.ndarray, bounds,
                events) -> Optional[tuple[int, float]]:
    """(k, clearance): of the states `chosen` (bool (m,)), the one farthest in strain from the
    nearest of the ends of its interval and the `events` (strains) inside it, and that distance
    [strain]. Its interval: the run of consecutive chosen states of one segment it belongs to,
    from the nearest of `bounds` (the collisions where its kind of state begins and ends) after
    the state before the run, or the run's first state where none lies between them or it is its
    segment's first (the start of the shear, or the relaxed state after a plastic event), to the
    nearest one before the state after the run, or the run's last state (the end of the strain
    range, or a fold). Where every state lies at an end or an event, the state nearest the
    middle of the longest interval, with clearance 0. None when no state is chosen."""
    bounds, events = np.asarray(bounds, dtype=float), np.asarray(events, dtype=float)
    best, longest, k, m = None, None, 0, gamma.size
    while k < m:
        if not chosen[k]:
            k += 1
            continue
        last = k
        while last + 1 < m and chosen[last + 1] and segment[last + 1] == segment[k]:
            last += 1
        lo, hi = gamma[k], gamma[last]
        if k > 0 and segment[k - 1] == segment[k]:
            lo = np.max(bounds[(bounds > gamma[k - 1]) & (bounds <= gamma[k])], initial=lo)
        if last + 1 < m and segment[last + 1] == segment[k]:
            hi = np.min(bounds[(bounds >= gamma[last]) & (bounds < gamma[last + 1])], initial=hi)
        states = np.arange(k, last + 1)
        g = gamma[states]
        near = events[(events >= lo) & (events <= hi)]
        clearance = np.minimum(g - lo, hi - g)
        if near.size:
            clearance = np.minimum(clearance, np.min(np.abs(g[:, None] - near[None, :]), axis=1))
        i = int(np.argmax(clearance))
        if best is None or clearance[i] > best[1]:
            best = (int(states[i]), float(clearance[i]))
        if longest is None or hi - lo > longest[1]:
            longest = (int(states[np.argmin(np.abs(g - 0.5 * (lo + hi)))]), hi - lo)
        k = last + 1
    if best is None:
        return None
    return best if best[1] > 0 else (longest[0], 0.0)


def msd_run(branch: Branch, k: int, label: str, clearance: float, network,
            mass: np.ndarray, linear, scene: PackingScene) -> MsdRun:
    """Random velocities (AMPLITUDE, seed 0) of the network's disks, their centre-of-mass
    velocity removed, from state k (`linear`: runs.linearized there), run PERIODS periods of
    the slowest mode of M^-1 J; the MSD over the network's disks (a loose disk would drift
    freely), sampled from t = 0 (sampled_msd)."""
    lam = linear.eigenvalues
    slowest = float(np.sqrt(np.min(np.abs(lam[lam != 0]))))
    loose = linear.problem.gauge.loose
    v = AMPLITUDE * np.random.default_rng(0).normal(size=branch.q[k].size)
    v[np.tile(loose, 3)] = 0.0
    N = network.N
    for axis in (slice(0, N), slice(N, 2 * N)):  # no centre-of-mass drift
        v[axis] -= np.where(loose, 0.0, np.sum(mass[axis] * v[axis]) / np.sum(mass[axis][~loose]))
    t, msd, slid = sampled_msd(network, branch.q[k], v, branch.xi[k], branch.rows[k],
                               float(branch.gamma[k]), mass, time_step(lam),
                               PERIODS * 2 * np.pi / slowest, ~loose)
    return MsdRun(label, k, float(branch.gamma[k]), clearance, linear.pairs,
                  0.0 if linear.mode is None else linear.mode.sigma, t, msd, slid)


def sampled_msd(network, q: np.ndarray, v: np.ndarray, xi: np.ndarray, rows: np.ndarray,
                gamma: float, mass: np.ndarray, dt: float, t_end: float, disks: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, int]:
    """(t, MSD(t) of `disks`, sliding updates) of a run from (q, v, xi, rows) to t_end,
    sampled from t = 0 on: runs from the same start over t_end, t_end / 10, t_end / 100, ...,
    down to one no longer than FRAMES steps of dt (every step a frame), each run's frames kept
    after the end of the next shorter one: every step at first (at least the first FRAMES / 10),
    then frames at most 10 / FRAMES of their time apart, for about 11 % more run than t_end."""
    spans = [t_end]
    while spans[-1] > FRAMES * dt:
        spans.append(spans[-1] / 10)
    t, msd, slid = np.zeros(1), np.zeros(1), 0
    for span in reversed(spans):
        run = simulate(network, q, v, xi, rows, gamma, mass, dt, span, frames=FRAMES)
        later = run.t > t[-1]
        t = np.concatenate([t, run.t[later]])
        msd = np.concatenate([msd, mean_squared_displacement(run, network.N, disks)[later]])
        slid = int(run.capped[-1])
    return t, msd, slid


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


def state_marks(ax, runs: list[MsdRun]) -> list:
    """A dotted vertical line at each MSD run's state; their legend handles."""
    from matplotlib.lines import Line2D

    for run in runs:
        ax.axvline(run.gamma, color=COLORS[run.label], ls=":", lw=1.2, zorder=4)
    return [Line2D([], [], color=COLORS[r.label], ls=":", lw=1.2,
                   label=f"{r.label} state of the MSD run") for r in runs]


def plastic_key(branch: Branch) -> list:
    """The legend handle of PLASTIC_STYLE's lines, where the branch passed plastic events."""
    from matplotlib.lines import Line2D

    return [Line2D([], [], color="k", ls=(0, (4, 2)), lw=1.3, label="plastic event")
            ][:len(branch.plastic)]


def plot_stress(branch: Branch, runs: list[MsdRun], scene: PackingScene,
                path: Path) -> None:
    """stress.png: sigma_xy [force / length] against gamma, one line per segment, the states
    with complex pairs shaded, plastic events dashed, the MSD runs' states dotted."""
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Patch

    fig, ax = new_figure(figsize=(7, 4.2))
    for a, b in complex_spans(branch.gamma, branch.n_complex):
        ax.axvspan(a, b, color="tab:red", alpha=0.12, lw=0)
    ax.add_collection(LineCollection(
        [np.column_stack([branch.gamma[on], branch.stress[on, 2]])
         for on in (branch.segment == s for s in np.unique(branch.segment))], colors="k", lw=1))
    ax.autoscale_view()
    strain_lines(ax, [e.gamma for e in branch.plastic], **PLASTIC_STYLE)
    handles = ([Patch(color="tab:red", alpha=0.12, label="states with complex pairs")]
               + plastic_key(branch) + state_marks(ax, runs))
    ax.set_xlabel(r"shear strain $\gamma$")
    ax.set_ylabel(r"$\sigma_{xy}$ [force / length]")
    ax.legend(handles=handles, fontsize=7, loc="upper left", framealpha=0.9)
    ax.set_title(f"{scene.name}: N = {scene.N}, P = {scene.pressure:g}, mu = {scene.mu:g}; "
                 f"complex pairs at {100 * np.mean(branch.n_complex > 0):.0f} % of the states, "
                 f"{len(branch.plastic)} plastic events", fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)


def plot_spectrum(branch: Branch, sigma: np.ndarray, runs: list[MsdRun],
                  scene: PackingScene, path: Path) -> None:
    """spectrum.png: the LOWEST eigenvalues by Re lambda of every state (grey real, red
    complex) and `sigma`, the fastest pair's |Im sqrt(lambda)| of every state; for M^-1 J in
    raw units [1 / time^2, 1 / time] and, on the right, in units of omega_0^2 and omega_0
    (PackingScene.omega_0), the complex MSD run's state circled. Plastic events dashed, the MSD
    runs' states dotted."""
    fig, (low, rate) = new_figure(2, 1, figsize=(7, 6.8), sharex=True)
    g, re, cx = [], [], []
    for gamma, lam in zip(branch.gamma, branch.eigenvalues):
        lam = lam[lam != 0]
        lam = lam[np.argsort(lam.real)][:LOWEST]
        g.append(np.full(lam.size, gamma))
        re.append(lam.real)
        cx.append(np.abs(lam.imag) > 1e-9 * np.abs(lam).max())
    g, re, cx = np.concatenate(g), np.concatenate(re), np.concatenate(cx)
    low.scatter(g[~cx], re[~cx], s=2, color="0.5", lw=0, label="real", zorder=6)
    low.scatter(g[cx], re[cx], s=5, color="tab:red", lw=0, label="complex pair", zorder=6)
    matrix, omega_0 = str(branch.matrix), scene.omega_0
    low.set_ylabel(rf"Re $\lambda$ of {matrix} {eigenvalue_unit(matrix)}")
    pairs = sigma > 0
    rate.plot(branch.gamma[~pairs], sigma[~pairs], ".", ms=3, color="0.5")
    rate.plot(branch.gamma[pairs], sigma[pairs], ".", ms=3, color="tab:red")
    if matrix == str(Matrix.M_INV_J):
        shown = [r for r in runs if r.label == "complex"]
        rate.plot([r.gamma for r in shown], [r.sigma for r in shown], "o", mfc="none", ms=8,
                  color="tab:red", zorder=5)
        w2 = omega_0 ** 2
        low.secondary_yaxis("right", functions=(lambda v: v / w2, lambda v: v * w2)).set_ylabel(
            r"Re $\lambda / \omega_0^2$")
        rate.set_ylabel(r"growth rate $\sigma = |\mathrm{Im}\sqrt{\lambda}|$ [time$^{-1}$]")
        rate.secondary_yaxis("right", functions=(lambda v: v / omega_0,
                                                 lambda v: v * omega_0)).set_ylabel(
            r"$\sigma / \omega_0$")
    else:
        rate.set_ylabel(r"largest |Im $\sqrt{\lambda}$| of J [raw units]")
    for ax in (low, rate):
        strain_lines(ax, [e.gamma for e in branch.plastic], **PLASTIC_STYLE)
        handles = state_marks(ax, runs)  # the same handles in both panels
    low.legend(handles=low.collections[:2] + plastic_key(branch) + handles, fontsize=7,
               loc="upper left", framealpha=0.9)
    low.set_title(f"{scene.name}: the lowest {LOWEST} eigenvalues by Re lambda at every state; "
                  f"omega_0 = {omega_0:.4g} [1/time]", fontsize=8)
    rate.set_xlabel(r"shear strain $\gamma$")
    fig.tight_layout()
    save_figure(fig, path)


def plot_msd(runs: list[MsdRun], scene: PackingScene, path: Path) -> None:
    """msd.png: each run's MSD [length^2] against t [time] (and omega_0 t on top), log-log from
    its first step."""
    fig, ax = new_figure(figsize=(7, 4.3))
    for run in runs:
        ax.loglog(run.t[1:], np.maximum(run.msd[1:], 1e-300), color=COLORS[run.label], lw=1,
                  label=f"{run.label} state, gamma = {run.gamma:.4g}, {run.pairs} pairs, "
                        f"sigma = {run.sigma:.3g}, {run.slid} sliding updates")
    ax.set_xlabel("t [time]")
    omega_0 = scene.omega_0
    ax.secondary_xaxis("top", functions=(lambda x: x * omega_0, lambda x: x / omega_0)
                       ).set_xlabel(r"$\omega_0 t$")
    ax.set_ylabel(r"MSD of the network's disks [length$^2$]")
    ax.set_title(f"{scene.name}: random velocities of amplitude {AMPLITUDE:g} [length/time] at "
                 f"t = 0", fontsize=8)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    save_figure(fig, path)


def report_text(scene: PackingScene, branch: Branch, sigma: np.ndarray,
                runs: list[MsdRun]) -> str:
    growth = (f"fastest growth rate {sigma.max():.4g} at gamma = "
              f"{branch.gamma[int(np.argmax(sigma))]:.6g}" if sigma.max() > 0
              else "every eigenvalue real at every state")
    lines = [f"# Packing report: {scene.name}", "",
             f"N = {scene.N}, P = {scene.pressure:g}, mu = {scene.mu:g}, seed {scene.seed}; "
             f"sheared to gamma = {branch.gamma[-1]:.6g} ({branch.status.sentence(len(branch))}); "
             f"{len(branch)} equilibria, {len(branch.collisions)} collisions, {len(branch.plastic)} plastic "
             f"events; complex pairs at {100 * np.mean(branch.n_complex > 0):.0f} % of the "
             f"states (at most {branch.n_complex.max()}); {growth}.", "",
             "The MSD runs start from the state of each kind (with complex pairs, with every "
             "eigenvalue real) farthest in strain from the ends of its interval (the collisions "
             "where such states begin and end, plastic events, the ends of the shear) and from "
             "the contact events inside it (its clearance below).", "",
             "![stress](stress.png)", "", "![spectrum](spectrum.png)", "",
             "![snapshot](snapshot.png)", "", "![msd](msd.png)", "",
             "| run | gamma | complex pairs | sigma | MSD at the end | sliding updates | "
             "clearance in strain |",
             "|---|---|---|---|---|---|---|"]
    lines += [f"| {r.label} | {r.gamma:.6g} | {r.pairs} | {r.sigma:.4g} | {r.msd[-1]:.3g} | "
              f"{r.slid} | {r.clearance:.3g} |" for r in runs]
    kinds = {r.label for r in runs}
    if "complex" not in kinds:
        lines += ["", "No state of the branch carries a complex pair: there is no complex state "
                      "to run from, and the snapshot shows the real state's contact forces only."]
    if "real" not in kinds:
        lines += ["", "No state of the branch has every eigenvalue real: there is no real "
                      "state to compare with."]
    return "\n".join(lines) + "\n"
