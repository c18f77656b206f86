"""A packing's spectra as a choice of the run (scenes/rules.py SPECTRA): none takes the same
equilibria, contact and plastic events as full, bit for bit; sample:DGAMMA's pair counts at
the grid strains are those the full branch's collisions give there; the samples survive a
segment file; auto resolves by N."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from sheared_packing import SCENE

from diskfriction.continuation.spectra.window import SpectralWindow
from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.sampled import grid_strains
from diskfriction.models.packing.segments import load_segment, save_segment
from diskfriction.models.packing.shear import ShearParams, shear
from diskfriction.scenes.packing import SPECTRA_BY_N, PackingScene
from diskfriction.scenes.scene import SceneValueError


def sheared_with(scene: PackingScene, spectra: str, window=None, plastic_events: int = 1000):
    scene = dataclasses.replace(scene, spectra=spectra)
    return shear(scene, prepare_scene(scene), ShearParams(workers=0), plastic_events=plastic_events,
                 window=window)


def pairs_at(full, gamma: float) -> int:
    """The complex pairs at `gamma` from the full branch: those at the last state at or before
    it, plus its births less its deaths located in between."""
    k = int(np.searchsorted(full.gamma, gamma, side="right")) - 1
    born = sum(1 if str(c.kind) == "birth" else -1 for c in full.collisions
               if full.gamma[k] < c.p <= gamma)
    return int(full.n_complex[k]) + born


def assert_same_branch(none, full) -> None:
    """The equilibria, the steps cut at contact events and the plastic events bit for bit."""
    assert np.array_equal(none.gamma, full.gamma) and np.array_equal(none.q, full.q)
    assert [(e.p, e.row) for e in none.event] == [(e.p, e.row) for e in full.event]
    assert none.events == full.events
    assert [(e.gamma, e.stress_before, e.stress_after) for e in none.plastic] == \
        [(e.gamma, e.stress_before, e.stress_after) for e in full.plastic]
    assert np.array_equal(none.stress, full.stress)


def test_spectra_none_follows_the_same_branch_as_full(branch):
    none = sheared_with(SCENE, "none")
    assert_same_branch(none, branch)
    assert none.eigenvalues.shape == (len(none), 0) and not none.collisions
    assert (none.n_complex == -1).all()  # no pair counted, not zero pairs
    assert (branch.n_complex > 0).any()  # the full branch has pairs to miss


def test_sampled_pairs_are_the_full_branchs_at_the_grid_strains(branch):
    every = 2e-4
    sampled = sheared_with(SCENE, f"sample:{every!r}")
    assert_same_branch(sampled, branch)
    strains = [x.gamma for x in sampled.sample]
    assert np.allclose(strains, every * np.arange(len(strains)), rtol=0, atol=1e-15)
    assert strains[-1] == pytest.approx(SCENE.gamma_range[1])
    nearest = min(abs(c.p - g) for c in branch.collisions for g in strains)
    assert nearest > 1e-9  # no collision within the samples' Newton tolerance of a grid strain
    counts = [x.n_complex for x in sampled.sample]
    assert counts == [pairs_at(branch, g) for g in strains]
    assert len(set(counts)) > 2  # the counts change along the shear
    assert max(x.residual for x in sampled.sample) <= ShearParams().newton_tol


def test_sampled_window_counts_the_pairs_in_the_window(branch):
    """With a window the samples count the pairs with Re lambda in it, as the dense samples'
    eigenvalues there."""
    dense = sheared_with(SCENE, "sample:0.0005")
    complex_re = [e.real for x in dense.sample for e in x.eigenvalues if e.imag > 0]
    lo, hi = -3.0, 1.5 * min(complex_re)  # the softest complex pair of the samples in it
    windowed = sheared_with(SCENE, "sample:0.0005", window=(lo, hi))
    assert windowed.window == (lo, hi)
    for a, b in zip(dense.sample, windowed.sample):
        inside = a.eigenvalues[SpectralWindow(lo, hi).inside(a.eigenvalues) & (a.eigenvalues != 0)]
        assert b.n_complex == int(np.sum(inside.imag > 0))
        mine = np.sort_complex(b.eigenvalues[SpectralWindow(lo, hi).inside(b.eigenvalues)])
        theirs = np.sort_complex(inside)
        assert mine.size == theirs.size and np.allclose(mine, theirs, rtol=1e-9, atol=1e-9)
    assert any(x.n_complex for x in windowed.sample)


def test_a_segment_file_keeps_its_samples(tmp_path):
    scene = PackingScene(N=32, gamma_range=(0.0, 0.005), spectra="sample:0.0005")
    sheared = shear(scene, prepare_scene(scene), ShearParams(workers=0), plastic_events=1,
                    on_segment=lambda s: save_segment(tmp_path / "s.npz", s, "key"))
    assert sheared.plastic  # one plastic event passed: its segment was written
    back = load_segment(tmp_path / "s.npz", "key")
    first = [x for x in sheared.sample if x.gamma <= sheared.plastic[0].gamma]
    assert [(x.gamma, x.n_complex, x.residual) for x in back.sample] == \
        [(x.gamma, x.n_complex, x.residual) for x in first]
    assert all(np.array_equal(a.eigenvalues, b.eigenvalues) for a, b in zip(back.sample, first))


@pytest.mark.slow
def test_none_passes_the_same_plastic_events_as_full():
    """32 disks to gamma = 0.005 pass a plastic event at 0.0026: none follows full through it."""
    scene = PackingScene(N=32, gamma_range=(0.0, 0.005))
    full, none = sheared_with(scene, "full"), sheared_with(scene, "none")
    assert len(full.plastic) >= 1
    assert_same_branch(none, full)


def test_grid_strains_are_multiples_of_the_spacing():
    assert np.array_equal(grid_strains(0.0, 0.001, 0.00025), np.arange(5) * 0.00025)
    assert np.array_equal(grid_strains(0.0011, 0.0019, 0.0005), np.array([3]) * 0.0005)
    assert grid_strains(0.0011, 0.0014, 0.0005).size == 0
    assert grid_strains(0.003 * 0.1 / 0.1, 0.003, 0.001).size == 1  # an end on the grid counts


def test_auto_spectra_follow_N():
    for N in (16, 64, 65, 256, 257, 4096):
        chosen = PackingScene(N=N).resolved_spectra
        assert chosen == next(c for most, c in SPECTRA_BY_N if most is None or N <= most)
    assert PackingScene(N=16).resolved_spectra == "full"
    assert PackingScene(N=4096).resolved_spectra == "none"
    assert PackingScene(N=4096, spectra="full").resolved_spectra == "full"
    short = PackingScene(N=256, gamma_range=(0.0, 1e-4))  # shorter than auto's grid of 0.0005
    assert short.resolved_spectra == "sample:0.0001" and short.sample_spacing == 1e-4


@pytest.mark.parametrize("spectra, why", [
    ("sample:0", "needs DGAMMA a finite number > 0"), ("sample:nan", "finite number > 0"),
    ("sample", "must be one of auto | none | full | sample:DGAMMA"), ("dense", "must be one of"),
    ("sample:1", "wider than the strain range")])
def test_bad_spectra_are_refused(spectra, why):
    with pytest.raises(SceneValueError, match=why):
        PackingScene(spectra=spectra)


SMALL = 'geometry = "packing"\nname = "small"\n[packing]\nN = 16\nseed = 3\n[shear]\ngamma = [0.0, 0.004]\n'


def scene_path(tmp_path, extra: str = ""):
    path = tmp_path / "small.toml"
    path.write_text(SMALL + extra, encoding="utf-8")
    return path


@pytest.mark.parametrize(("args", "line"), [
    (["--spectra", "dense"], "bifurcate error: --spectra: must be one of auto | none | full | "
                             "sample:DGAMMA (got 'dense')"),
    (["--spectra", "sample:-1"], "bifurcate error: --spectra: sample:DGAMMA needs DGAMMA a finite "
                                 "number > 0, not '-1' (got 'sample:-1')"),
    (["--spectra", "sample:0.01"], "bifurcate error: --spectra: the sample grid's spacing is wider "
                                   "than the strain range: no two samples in it, [0, 0.004] (got "
                                   "'sample:0.01')"),
    (["--spectra", "none", "--window=-3:2"], "bifurcate error: --window: a window of the spectrum "
                                              "needs --spectra full or sample:DGAMMA; the shear's "
                                              "spectra are none (got '-3:2')"),
    (["--spectra", "sample:0.001", "--json"], "bifurcate error: --json: prints the collisions "
                                              "located, and spectra sample:0.001 locate none; give "
                                              "--spectra full"),
])
def test_bifurcate_refuses_spectra_it_cannot_take(tmp_path, capsys, args, line):
    from diskfriction.cli.main import main

    out = tmp_path / "out"
    assert main(["bifurcate", str(scene_path(tmp_path)), *args, "--out", str(out)]) == 2
    assert capsys.readouterr().err.splitlines() == [line]
    assert not out.exists() or not any(out.iterdir())


def test_a_scene_files_spectra_are_checked_naming_the_key(tmp_path, capsys):
    from diskfriction.cli.main import main

    path = scene_path(tmp_path, '[stability]\nspectra = "some"\n')
    assert main(["bifurcate", str(path), "--out", str(tmp_path / "out")]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"scene error: {path}: stability.spectra: must be one of auto | none")


def test_other_commands_and_a_chain_refuse_the_packings_spectra(tmp_path, capsys):
    from diskfriction.cli.main import main

    assert main(["bifurcate", "--spectra", "none", "--out", str(tmp_path / "o")]) == 2
    assert "a chain's sweep computes every spectrum" in capsys.readouterr().err


@pytest.mark.slow
def test_the_outputs_say_what_was_computed(tmp_path, capsys):
    """spectra none: collisions.json's collisions null (none looked for, not none found),
    branch.npz's spectra "none" and no eigenvalue; sample: the samples' strains, pairs and
    eigenvalues in branch.npz; plastic.json's pairs null in both."""
    import json

    from diskfriction.cli.main import main

    path = scene_path(tmp_path)
    for spectra in ("none", "sample:0.001"):
        out = tmp_path / spectra.replace(":", "_")
        assert main(["bifurcate", str(path), "--spectra", spectra, "--out", str(out)]) == 0
        printed = capsys.readouterr().out
        collisions = json.loads((out / "collisions.json").read_text(encoding="utf-8"))
        assert collisions["spectra"] == spectra and collisions["collisions"] is None
        plastic = json.loads((out / "plastic.json").read_text(encoding="utf-8"))["events"]
        assert plastic and all(e["complex_pairs"] is None for e in plastic)
        with np.load(out / "branch.npz") as data:
            assert str(data["spectra"]) == spectra and data["eigenvalues"].shape[1] == 0
            if spectra == "none":
                assert "sample_gamma" not in data.files
                assert "spectra none: no eigenvalue computed" in printed
            else:
                assert np.allclose(data["sample_gamma"], 0.001 * np.arange(5), atol=1e-15, rtol=0)
                n = data["sample_n_complex"]
                assert n.shape == (5,) and n.max() > 0
                lam = data["sample_eigenvalues"]
                assert [int(np.sum(row.imag > 0)) for row in lam] == list(n)
                assert "spectra sampled at 5 grid strains (every 0.001)" in printed
