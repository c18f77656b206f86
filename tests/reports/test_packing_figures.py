"""What a reader of the packing figures sees (issue 60): diagram.png with a window draws only
the window's eigenvalues and names it, plastic events over the collisions; snapshot.png has axis
labels, an arrow key and both parts of a complex mode; run.png's legend entries all draw lines;
map.png's counts on readable linear axes; the report's states lie away from folds and contact
events, its MSD sampled from t = 0, and a branch without complex pairs has no "complex" run."""
from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from diskfriction.reports import packing_maps, packing_outputs, packing_report
from diskfriction.scenes.packing import PackingScene


@pytest.fixture
def figures(monkeypatch):
    """The figures the packing plots save, kept open (save_figure replaced in their modules)."""
    kept = []
    for module in (packing_outputs, packing_report, packing_maps):
        monkeypatch.setattr(module, "save_figure", lambda fig, path: kept.append(fig))
    return kept


def shear_branch(window=None, collisions=300):
    """A branch as the diagram reads it: 40 states in two segments (a plastic event at gamma =
    0.5), complex eigenvalues with Re from 0 to 30, many collisions."""
    gamma = np.linspace(0, 1, 40)
    rng = np.random.default_rng(1)
    lam = rng.uniform(0, 30, (40, 12)) + 1j * rng.uniform(0.1, 2, (40, 12))
    lam[:, 6:] = np.conj(lam[:, :6])
    lam[::5, 0] = np.nan  # a window column not tracked at those states
    return SimpleNamespace(
        gamma=gamma, stress=np.column_stack([gamma] * 4), segment=(gamma > 0.5).astype(int),
        n_complex=np.full(40, 3), eigenvalues=lam, matrix="M^-1 J", window=window,
        collisions=[SimpleNamespace(p=p, kind=("birth", "death")[n % 2])
                    for n, p in enumerate(rng.uniform(0, 1, collisions))],
        plastic=[SimpleNamespace(gamma=0.5)], labelled={})


def test_the_diagram_with_a_window_draws_only_its_eigenvalues_and_names_it(figures):
    """Guard-band eigenvalues (Re outside the window) are tracked, not shown: the Im panel holds
    exactly the eigenvalues with Im > 0 and Re in [5, 20], and the title names the window."""
    branch = shear_branch(window=(5.0, 20.0))
    packing_outputs.plot_packing_diagram(branch, PackingScene(), Path("diagram.png"))
    stress, pairs, im = figures[-1].axes[:3]
    drawn = np.sort(np.concatenate([line.get_ydata() for line in im.lines]))
    lam = branch.eigenvalues
    inside = np.isfinite(lam) & (lam.imag > 0) & (lam.real >= 5) & (lam.real <= 20)
    assert (~inside & np.isfinite(lam) & (lam.imag > 0)).any()  # there is something to leave out
    assert np.array_equal(drawn, np.sort(lam.imag[inside]))
    assert "window 5 <= Re lambda <= 20" in stress.get_title()


def test_the_diagrams_plastic_events_lie_over_its_many_collisions(figures):
    """With 300 collisions the plastic event's dashed line is drawn in every panel, in the
    stress panel above the collisions and the stress curve (zorder) and wider than them."""
    packing_outputs.plot_packing_diagram(shear_branch(), PackingScene(), Path("diagram.png"))
    stress, pairs, im = figures[-1].axes[:3]
    for ax in (stress, pairs, im):
        assert plastic_line(ax).get_linestyle()[0][1] is not None  # dashed
    collisions = max(stress.collections, key=lambda c: len(c.get_segments()))
    curve = next(c for c in stress.collections
                 if c is not collisions and len(c.get_segments()) == 2)  # two segments
    assert len(collisions.get_segments()) == 300
    plastic = plastic_line(stress)
    assert plastic.get_zorder() > max(collisions.get_zorder(), curve.get_zorder())
    assert plastic.get_linewidth()[0] > collisions.get_linewidth()[0]


def test_a_real_spectrum_draws_its_softest_mode_and_lays_out(figures):
    """A frictionless branch (every eigenvalue real, exact zeros for its gauge modes) with no
    plastic event: the lower panel draws the lowest positive eigenvalue at every state (the
    Im panel was empty) and says why, and the layout applies (an empty marker line in axis
    coordinates made tight_layout give up with a warning)."""
    import warnings

    branch = shear_branch(collisions=0)
    lam = np.abs(branch.eigenvalues.real) + 1.0
    lam[:, :3] = 0.0  # the gauge rows' zeros
    branch.eigenvalues, branch.n_complex, branch.plastic = lam + 0j, np.zeros(40, int), []
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        packing_outputs.plot_packing_diagram(branch, PackingScene(), Path("diagram.png"))
    im = figures[-1].axes[2]
    (line,) = im.lines
    assert np.array_equal(line.get_ydata(), lam[:, 3:].min(axis=1))
    assert "lowest Re" in im.get_ylabel() and "no complex eigenvalue" in im.texts[0].get_text()


def plastic_line(ax):
    """The collection of the single vertical line at gamma = 0.5 in `ax`."""
    found = [c for c in ax.collections if hasattr(c, "get_segments")
             and len(c.get_segments()) == 1 and np.isclose(c.get_segments()[0][0, 0], 0.5)]
    assert len(found) == 1, ax.get_ylabel()
    return found[0]


def test_the_snapshot_labels_its_axes_and_keys_both_parts_of_a_complex_mode(figures):
    """Three disks in contact: x and y labelled with their unit, a key arrow for each of Re V
    and Im V (two sets of arrows), the contact forces named in the legend."""
    from matplotlib.quiver import Quiver, QuiverKey

    L, radii = 3.0, np.array([0.5, 0.5, 0.7])
    q = np.array([0.5, 1.45, 1.0, 0.5, 0.5, 1.5, 0, 0, 0])
    rows = np.array([[0, 1, 0, 0], [0, 2, 0, 0], [1, 2, 0, 0]])
    mode = np.arange(9) * (1 + 0.3j) / 10
    packing_outputs.plot_packing_snapshot(q, radii, L, 0.01, rows, np.array([1.0, 0.5, 0.0]),
                                          mode, "title", Path("snapshot.png"), unit="length")
    ax = figures[-1].axes[0]
    assert "length" in ax.get_xlabel() and "length" in ax.get_ylabel()
    keys = [a for a in ax.get_children() if isinstance(a, QuiverKey)]
    assert len(keys) == 2 and [k.text.get_text().split(":")[0] for k in keys] == ["Re V", "Im V"]
    assert all("length" in k.text.get_text() for k in keys)
    assert sum(isinstance(c, Quiver) for c in ax.collections) == 2
    assert "[force]" in ax.get_legend().get_texts()[0].get_text()


def test_every_entry_of_the_runs_legend_draws_a_line(figures):
    """run.png: the distance, the spectrum's e^(sigma t) and the measured growth all drawn, each
    legend handle a line with a style (no empty "measured" entry)."""
    t = np.linspace(0, 100, 500)
    d = 1e-10 * np.exp(0.1 * t) * (1.5 + np.sin(3 * t))
    packing_outputs.plot_packing_run(t, d, 0.1, 0.098, PackingScene(), 0.002, Path("run.png"))
    ax = figures[-1].axes[0]
    handles = ax.get_legend().legend_handles
    assert len(handles) == 3
    assert all(h.get_linestyle() not in ("None", " ", "") and h.get_linewidth() > 0
               for h in handles)
    assert "time" in ax.get_xlabel()


def test_the_map_counts_collisions_and_plastic_events_on_readable_axes(figures):
    """About 60 collisions per 1e-3 of strain: linear axes from 0 with ticks between 10 and the
    largest value (a symlog axis showed 0, 1 and 10 only)."""
    from diskfriction.studies.maps import Axis, Cell

    axis = Axis("contacts.mu", (0.3, 1.7, 10.0), log=True)
    cells = [Cell((n,), (("contacts.mu", mu),), None) for n, mu in enumerate(axis.values)]
    records = [{"summary": {"status": "ok", "reason": "", "gamma_end": 0.005,
                            "complex_fraction": 0.9, "pairs_mean": 10.0, "sigma_median": 0.5,
                            "sigma_max": 1.0, "omega_c": 10.5, "collisions": n,
                            "plastic_events": p}}
               for n, p in ((196, 0), (209, 0), (302, 1))]
    packing_maps.plot_packing_bands(axis, cells, records, Path("map.png"), "title")
    counts, events = figures[-1].axes[2], figures[-1].axes[-1]
    for ax, top in ((counts, 60.4), (events, 0.2)):
        assert ax.get_yscale() == "linear"
        ticks = [v for v in ax.get_yticks() if ax.get_ylim()[0] <= v <= ax.get_ylim()[1]]
        assert sum(0.15 * top < v <= top * 1.05 for v in ticks) >= 3, (ax.get_ylabel(), ticks)


def test_the_quiet_state_lies_away_from_folds_events_and_the_ends_of_its_interval():
    """States with complex pairs on 0..1e-3 (a fold at the last) and a contact event at 4e-4:
    the state chosen lies 3e-4 from the event and the fold, not next to either; bounded by
    collisions, the interval with the most room; without any room, the middle of the longest
    interval."""
    gamma = np.linspace(0, 1e-3, 101)
    chosen, segment = np.ones(101, bool), np.zeros(101)
    k, clearance = packing_report.quiet_state(gamma, chosen, segment, [], [4e-4, 1e-3])
    assert np.isclose(clearance, 3e-4) and np.isclose(gamma[k], 7e-4)
    chosen[40:60] = False  # two runs of states, the collisions at 3.95e-4 and 5.95e-4
    k, clearance = packing_report.quiet_state(gamma, chosen, segment, [3.95e-4, 5.95e-4], [])
    assert np.isclose(clearance, 2e-4) and np.isclose(gamma[k], 8e-4)
    k, clearance = packing_report.quiet_state(gamma, chosen, segment, [], gamma)
    assert clearance == 0 and k == 80
    assert packing_report.quiet_state(gamma, np.zeros(101, bool), segment, [], []) is None


def report_of(monkeypatch, tmp_path, text):
    """build_packing_report on the scene `text` with MSD runs of 40 slowest periods (not 400:
    seconds), its runs and branch kept from the plots."""
    from diskfriction.models.packing.commands import PLASTIC_EVENTS
    from diskfriction.scenes import load_scene

    seen = {}
    stress = packing_report.plot_stress

    def keep(branch, runs, scene, path):
        seen.update(branch=branch, runs=runs)
        stress(branch, runs, scene, path)

    monkeypatch.setattr(packing_report, "plot_stress", keep)
    monkeypatch.setattr(packing_report, "PERIODS", 40)
    path = tmp_path / "pack.toml"
    path.write_text('geometry = "packing"\n' + text, encoding="utf-8")
    packing_report.build_packing_report(load_scene(path), tmp_path, PLASTIC_EVENTS)
    return seen["branch"], seen["runs"], (tmp_path / "report.md").read_text()


@pytest.mark.slow
def test_the_reports_states_lie_away_from_folds_and_its_msd_starts_at_t_0(monkeypatch, tmp_path,
                                                                           figures):
    """16 disks to gamma = 0.002, a plastic event at 1.55e-3 on the way: the complex state lies
    its clearance (> 1e-5) from every fold, contact event and end of its interval; each MSD run
    starts at t = 0 with every step (the MSD far below 1e-9 there), then frames at most 2.5 %
    of their time apart over four decades and more; spectrum.png marks the plastic event in
    both panels."""
    branch, runs, text = report_of(monkeypatch, tmp_path,
                                   "[packing]\nN = 16\nseed = 1\n[shear]\ngamma = [0.0, 0.002]\n")
    assert branch.plastic
    complex_run = next(r for r in runs if r.label == "complex")
    assert complex_run.clearance > 1e-5 and complex_run.pairs > 0
    assert all(abs(complex_run.gamma - e.gamma) >= complex_run.clearance for e in branch.plastic)
    row = next(line for line in text.splitlines() if line.startswith("| complex |"))
    assert row.startswith(f"| complex | {complex_run.gamma:.6g} |")
    assert row.endswith(f"| {complex_run.clearance:.3g} |")
    for run in runs:
        assert run.t[0] == 0 and run.msd[0] == 0 and run.msd[1] < 1e-12
        first = run.t[run.t <= 40 * run.t[1]]
        assert np.allclose(np.diff(first), run.t[1])  # every step at first
        gap = np.diff(run.t)  # then frames no further apart than 2.5 % of their time
        assert np.all(np.isclose(gap, run.t[1]) | (gap <= 10 / packing_report.FRAMES * run.t[1:]))
        assert run.t[-1] > 1e4 * run.t[1]
    spectrum = figures[1]  # stress.png, spectrum.png, snapshot.png, msd.png in that order
    for ax in spectrum.axes[:2]:
        assert any(len(c.get_segments()) == 1 and np.isclose(c.get_segments()[0][0, 0],
                                                             branch.plastic[0].gamma)
                   for c in ax.collections if hasattr(c, "get_segments"))
    assert "time" in spectrum.axes[0].get_ylabel() and "time" in spectrum.axes[1].get_ylabel()


@pytest.mark.slow
def test_a_report_without_complex_pairs_runs_no_complex_state_and_says_so(monkeypatch, tmp_path,
                                                                          figures):
    """Frictionless disks (mu = 0): every eigenvalue real; one run, labelled real, and report.md
    says that there is no complex state."""
    _, runs, text = report_of(monkeypatch, tmp_path, "[packing]\nN = 16\nseed = 1\n[contacts]\n"
                                                     "mu = 0.0\n[shear]\ngamma = [0.0, 0.0005]\n")
    assert [r.label for r in runs] == ["real"]
    assert "\n| complex |" not in text and "No state of the branch carries a complex pair" in text
    msd = figures[-1].axes[0]
    assert [line.get_label().split()[0] for line in msd.lines] == ["real"]
