"""The report builder on a tiny scene: every section, the cache, recomputing only what changed,
bad input."""
from __future__ import annotations

import contextlib
import dataclasses
from pathlib import Path

import numpy as np
import pytest
from commandline import run_main

from diskfriction.reports.builder import build_report
from diskfriction.reports.cache import ResultCache, cache_key
from diskfriction.reports.sections import SECTIONS
from diskfriction.reports.settings import SettingError, Settings, with_setting
from diskfriction.scenes import Scene

TINY = Scene(N=3, name="tiny")
# Short runs and small grids: the whole report in well under a minute.
QUICK = Settings(inertias=(0.5,), eps_values=(0.0, 1e-4), accuracy_divisions=(30, 60),
                 accuracy_tol_p=(1e-8,), reference_divisions=120, jacobian_steps=(1e-4, 1e-6),
                 dt_fractions=(0.2, 0.1), reference_dt_fraction=0.05, dynamics_accuracy_t_end=20.0,
                 t_end=20.0, fig3_loads=(0.03, 0.083), fig4_disk=2, ensemble_loads=(0.087, 0.09),
                 realizations=2, ensemble_t_end=20.0, vcm_loads=(0.087, 0.09), vcm_realizations=1,
                 lammps_inertias=(0.4,))


def build(out: Path, cache: Path, settings: Settings = QUICK, only=None):
    lines = []
    log = build_report([TINY], out, only, settings, cache, echo=lambda text, end="\n": lines.append(text))
    return log, lines


@contextlib.contextmanager
def one_local_cluster():
    """The report's ensembles (fig5, fig7 and the LAMMPS section's two) on one local dask
    cluster instead of a new one each: every new cluster's workers import and load the kernels
    again (~2 s each). What an ensemble returns does not depend on its cluster (seeded runs);
    dask_client itself is tested where ensembles and maps are (test_ensemble, test_maps)."""
    from diskfriction.studies import cluster, ensemble

    with cluster.dask_client() as client:
        @contextlib.contextmanager
        def shared(scheduler=None, workers=None):
            assert scheduler is None and workers is None
            yield client

        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(ensemble, "dask_client", shared)
            yield


@pytest.fixture(scope="module")
def first(tmp_path_factory):
    """The whole report of TINY built once (QUICK): the tests that read it are the slow tier's
    (README, Tests); the others check parts, in-process."""
    root = tmp_path_factory.mktemp("report")
    with one_local_cluster():
        log, lines = build(root / "out", root / "cache")
    return root, log, lines


@pytest.mark.slow
def test_builder_writes_every_figure_and_the_table(first):
    root, log, _ = first
    report = (root / "out" / "report.md").read_text()
    for section in SECTIONS:
        assert f"## {section.title}" in report
    for name in ("fig2", "condition", "fig3", "fig4", "fig5", "fig6", "fig7", "readings", "lammps",
                 "accuracy"):
        png = root / "out" / "tiny" / f"{name}.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
        assert f"(tiny/{name}.png)" in report
    assert "| claim | paper | ours | deviation / holds | reading |" in report
    assert not [e for e in log if "failed" in e.status]


@pytest.mark.slow
def test_progress_line_per_computation_and_shared_ones_computed_once(first):
    _, log, lines = first
    computed = [e for e in log if e.status == "computed"]
    assert len({e.key for e in computed}) == len(computed)  # each distinct key ran once
    assert any(line.startswith("computing fig2/branch[J] ... ") for line in lines)
    assert any(line.startswith("cached    paper/branch[J]") for line in lines)


@pytest.mark.slow
def test_second_run_hits_the_cache_and_recomputes_nothing(first):
    root, log, _ = first
    again, lines = build(root / "out2", root / "cache")
    assert [e.status for e in again] == ["cached"] * len(again)
    assert {e.key for e in again} == {e.key for e in log}
    assert all(line.startswith(("cached", "skipped")) for line in lines)


@pytest.mark.slow
def test_changed_parameter_recomputes_only_what_depends_on_it(first):
    root, log, _ = first
    changed = dataclasses.replace(QUICK, mode_F_x=0.05)
    again, _ = build(root / "out3", root / "cache", changed)
    recomputed = {(e.section, e.label) for e in again if e.status == "computed"}
    assert recomputed == {("fig6", "shear_mode[F_x=0.05]")}  # the paper table shares it
    assert {e.computation for e in again if e.status == "computed"} == {"shear_mode"}


@pytest.mark.slow
def test_only_builds_one_section(first):
    root, _, _ = first
    log, _ = build(root / "only", root / "cache", only=("fig6",))
    assert {e.section for e in log} == {"fig6"}
    report = (root / "only" / "report.md").read_text()
    assert "## Fig. 6" in report and "## Fig. 2" not in report


def test_cache_key_covers_scene_parameters_and_code():
    base = cache_key("branch", TINY, {"matrix": "J"}, "code")
    assert cache_key("branch", dataclasses.replace(TINY, name="x", source="y"), {"matrix": "J"}, "code") == base
    assert cache_key("branch", dataclasses.replace(TINY, eps=1e-5), {"matrix": "J"}, "code") != base
    assert cache_key("branch", TINY, {"matrix": "M^-1 J"}, "code") != base
    assert cache_key("branch", TINY, {"matrix": "J"}, "code2") != base


def test_cache_round_trips_arrays_and_json_without_pickle(tmp_path):
    cache = ResultCache(tmp_path)
    result = {"a": np.arange(3.0), "z": np.array([1 + 2j]), "kinds": ["birth"], "n": 3, "none": None}
    cache.store("c", "k", result)
    back = cache.load("c", "k")
    assert np.array_equal(back["a"], result["a"]) and back["z"][0] == 1 + 2j
    assert back["kinds"] == ["birth"] and back["n"] == 3 and back["none"] is None
    cache.path("c", "k").write_bytes(b"garbage")
    assert cache.load("c", "k") is None  # unreadable: recomputed, never trusted


@pytest.mark.parametrize("assignment", ["foo=1", "t_end", "t_end=abc", "t_end=-1", "loads=",
                                        "realizations=0", "t_end=nan"])
def test_bad_setting_is_refused(assignment):
    with pytest.raises(SettingError):
        with_setting(Settings(), assignment)


def test_setting_parses_lists_and_numbers():
    s = with_setting(with_setting(Settings(), "loads=0.03, 0.05"), "realizations=3")
    assert s.loads == (0.03, 0.05) and s.realizations == 3


@pytest.mark.parametrize("args, says", [
    (["--only", "fig9"], "report error: --only: unknown section 'fig9'"),
    (["--set", "nothing=1"], "report error: --set: expected KEY=VALUE"),
    (["/no/such/scene.toml"], "scene error: /no/such/scene.toml"),
    (["--bogus"], "diskfriction: error: unrecognized arguments: --bogus"),
])
def test_bad_input_gets_one_line_and_exit_2(tmp_path, args, says):
    run = run_main("report", *args, "--out", str(tmp_path / "o"))
    assert run.returncode == 2
    assert run.stderr.count("\n") == 1 and run.stderr.startswith(says), run.stderr
    assert not (tmp_path / "o").exists()


def test_a_reading_moves_toward_the_paper_only_beyond_the_errors():
    from diskfriction.reports.analysis import movement

    est = lambda value, error=0.1: {"value": value, "error": error, "n": 5}  # noqa: E731
    assert movement(1.0, est(2.0), est(1.5)) == "toward"
    assert movement(1.0, est(2.0), est(2.5)) == "away"
    assert movement(1.0, est(2.0), est(2.1)) == "no change"  # within sqrt(0.1^2 + 0.1^2)
    assert movement(1.0, est(2.0, None), est(1.9, None)) == "toward"
    assert movement(1.0, None, est(1.5)) == movement(1.0, est(None), est(1.5)) == "n/a"
