"""Parameter maps (issue 11): the grid, one cell against bifurcate, bit-identical tables on 1
and 2 workers, an interrupted map resumed, failed cells shown with their reason, and bad
--vary specifications refused with one line."""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import pytest
from commandline import error_line, run_cli, run_main

from diskfriction.studies.maps import (COLUMNS, Axis, MapParams, SlideParams, grid_values,
                                        map_cell, map_cells, run_map, sliding_load)
from diskfriction.reports.maps import csv_text, save_map, table_rows
from diskfriction.scenes import Scene
from diskfriction.scenes.load import SceneError

TINY = Scene(N=3, F_x_range=(0.0, 0.05), name="tiny")
"""Three disks to F_x = 0.05: 4 collisions of J, five windows, about a second a cell."""
AXES = [Axis("contacts.mu", grid_values(2.0, 10.0, 2)), Axis("disks.inertia", grid_values(0.5, 2.0, 2))]
PARAMS = MapParams(0.0, 0.05, "J", SlideParams(t_end=100.0))
"""A 2 x 2 map with slide runs short enough for a test; at mu = 2, c = 0.5 a window slides."""


def results(text: str) -> list[str]:
    """The lines of a map.csv without the last column, wall_time: everything that must not
    depend on which worker ran a cell, or when."""
    return [line.rsplit(",", 1)[0] for line in text.splitlines()]


def write_table(out: Path, records: list[dict]) -> str:
    cells = map_cells(TINY, AXES, "tiny")
    save_map(out, TINY, AXES, PARAMS, "test", cells, records)
    return (out / "map.csv").read_text()


@pytest.fixture(scope="module")
def one_worker(tmp_path_factory):
    """The 2 x 2 map on a local cluster of one worker: (out, map.csv text)."""
    out = tmp_path_factory.mktemp("one-worker")
    records = run_map(map_cells(TINY, AXES, "tiny"), PARAMS, out, workers=1)
    return out, write_table(out, records)


# ---- the grid ---------------------------------------------------------------------------------

def test_grid_values_are_even_in_value_or_in_log_and_include_both_ends():
    assert grid_values(4, 40, 10) == tuple(float(n) for n in range(4, 41, 4))
    log = grid_values(0.1, 10.0, 3, log=True)
    assert log[0] == 0.1 and log[-1] == 10.0 and log[1] == pytest.approx(1.0, rel=1e-15)
    assert grid_values(3.0, 3.0, 1) == (3.0,)


@pytest.mark.parametrize("lo, hi, count, log, says", [
    (1.0, 2.0, 0, False, "COUNT must be an integer >= 1"),
    (2.0, 1.0, 3, True, "LO must be below HI"),
    (2.0, 1.0, 3, False, "LO must be below HI"),
    (0.0, 1.0, 3, True, "log spacing needs LO > 0"),
    (1.0, 2.0, 1, False, "one value (COUNT = 1) needs LO = HI"),
    (1.0, float("inf"), 3, False, "finite"),
])
def test_grid_values_refuse_what_is_no_grid(lo, hi, count, log, says):
    with pytest.raises(ValueError, match=says.replace("(", r"\(").replace(")", r"\)")):
        grid_values(lo, hi, count, log)


def test_cells_run_through_the_grid_first_key_slowest_each_a_checked_scene():
    cells = map_cells(TINY, [Axis("disks.N", grid_values(4, 6, 2)), Axis("load.F_y", (0.1, 0.2))],
                      "tiny")
    assert [c.index for c in cells] == [(0, 0), (0, 1), (1, 0), (1, 1)]
    assert [(c.scene.N, c.scene.F_y) for c in cells] == [(4, 0.1), (4, 0.2), (6, 0.1), (6, 0.2)]
    assert all(type(c.scene.N) is int and dict(c.values)["disks.N"] == c.scene.N for c in cells)
    with pytest.raises(SceneError) as raised:  # 4, 4.5, 5 disks
        map_cells(TINY, [Axis("disks.N", grid_values(4, 5, 3))], "tiny")
    assert (raised.value.key, raised.value.value) == ("disks.N", 4.5)
    with pytest.raises(SceneError, match=r"disks.eps: must be in \[0, 0.1\) \(got 0.15\)"):
        map_cells(TINY, [Axis("disks.eps", grid_values(0.05, 0.15, 2))], "tiny")


def test_the_sliding_load_is_the_lowest_that_slid_above_the_highest_that_stuck_below_it():
    run = lambda F, slid: {"F_x": F, "slid": slid}
    runs = [run(0.1, False), run(0.2, None), run(0.3, False), run(0.4, True), run(0.5, False),
            run(0.6, True)]
    assert sliding_load(runs) == (0.4, 0.3)
    assert sliding_load([run(0.1, True), run(0.2, False)]) == (0.1, None)
    assert sliding_load([run(0.1, False), run(0.2, None)]) == (None, None)


# ---- one cell, failures ---------------------------------------------------------------------------

@pytest.mark.slow
def test_a_map_of_one_cell_equals_bifurcate_on_the_same_scene(tmp_path):
    scene = tmp_path / "four.toml"
    scene.write_text("[disks]\nN = 4\n[load]\nF_x = [0.0, 0.05]\n")
    bifurcate = run_cli("bifurcate", str(scene), "--matrix", "M^-1J", "--out", str(tmp_path / "b"))
    mapped = run_cli("map", str(scene), "--vary", "contacts.mu=10:10:1", "--matrix", "M^-1J",
                     "--workers", "1", "--out", str(tmp_path / "m"))
    assert bifurcate.returncode == 0 and mapped.returncode == 0, bifurcate.stderr + mapped.stderr
    assert "1 cell: bifurcate" in mapped.stderr and "on 1 worker (a rough estimate)" in mapped.stderr
    alone = json.loads((tmp_path / "b" / "collisions.json").read_text())["collisions"]
    (cell,) = (tmp_path / "m" / "cells").glob("*.json")
    cell = json.loads(cell.read_text())
    assert alone and len(cell["collisions"]) == len(alone)
    for a, b in zip(alone, cell["collisions"]):
        assert a["kind"] == b["kind"]
        assert abs(a["p"] - b["p"]) <= 1e-12 and abs(a["lambda"] - b["lambda"]) <= 1e-12 * abs(a["lambda"])
    import pandas

    table = pandas.read_csv(tmp_path / "m" / "map.csv")
    assert list(table.columns) == ["contacts.mu", *COLUMNS] and len(table) == 1
    assert table["collisions"][0] == len(alone) and table["status"][0] == "ok"
    assert (tmp_path / "m" / "map.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.slow
def test_cells_without_a_sticking_branch_are_shown_with_the_reason():
    """mu = 0.1: no equilibrium from the first load step; mu = 1 (N = 4): the branch turns back
    at F_x ~ 3e-5. Both rows are in the table, with their reason, and nothing beyond."""
    scene = Scene(N=4, F_x_range=(0.0, 0.05))
    cells = map_cells(scene, [Axis("contacts.mu", (0.1, 1.0))], "four")
    records = [map_cell(c.scene, MapParams(0.0, 0.05, "J", SlideParams(t_end=20.0))) for c in cells]
    failed, ended = (r["summary"] for r in records)
    assert failed["status"] == "failed" and "relaxation did not converge" in failed["reason"]
    assert failed["F_end"] is None and failed["collisions"] is None and failed["runs"] is None
    assert ended["status"] == "ended" and ended["reason"].startswith("branch ended at F_x = ")
    assert 0 < ended["F_end"] < 0.05 and all(r["F_x"] < ended["F_end"] for r in records[1]["runs"])
    import pandas

    table = pandas.read_csv(io.StringIO(csv_text([Axis("contacts.mu", (0.1, 1.0))],
                                                 table_rows(cells, records))))
    assert list(table["status"]) == ["failed", "ended"] and table["reason"].notna().all()
    assert table["F_slide"].isna().all() and table["mu_eff"].isna().all()


# ---- on dask: worker count, interrupts ------------------------------------------------------------

@pytest.mark.slow
def test_a_two_key_map_on_two_workers_gives_a_byte_identical_table(one_worker, tmp_path):
    out, table = one_worker
    records = run_map(map_cells(TINY, AXES, "tiny"), PARAMS, tmp_path, workers=2)
    assert results(write_table(tmp_path, records)) == results(table)
    assert (tmp_path / "map.json").read_bytes() == (out / "map.json").read_bytes()
    rows = list(csv.DictReader(io.StringIO(table)))
    assert len(rows) == 4 and any(row["F_slide"] for row in rows)  # the runs are compared too


@pytest.mark.slow
def test_an_interrupted_map_resumes_to_the_same_table_leaving_finished_cells_alone(one_worker,
                                                                                  tmp_path):
    """Ctrl-C arrives (as a KeyboardInterrupt) once the first cell is written."""
    _, table = one_worker
    cells = map_cells(TINY, AXES, "tiny")

    def interrupt(done: int, total: int) -> None:
        if done:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_map(cells, PARAMS, tmp_path, progress=interrupt)
    finished = {p: (p.stat().st_mtime_ns, p.read_bytes()) for p in (tmp_path / "cells").iterdir()}
    assert 1 <= len(finished) < len(cells)
    assert not list((tmp_path / "cells").glob(".*"))  # no temporary file left behind
    records = run_map(cells, PARAMS, tmp_path, workers=1)
    assert results(write_table(tmp_path, records)) == results(table)
    assert {p: (p.stat().st_mtime_ns, p.read_bytes()) for p in finished} == finished
    assert len(list((tmp_path / "cells").iterdir())) == len(cells)


# ---- bad input at the door ---------------------------------------------------------------------------

BAD = [
    (["--vary", "contacts.nu=1:2:2"], "contacts.nu is no scene key"),
    (["--vary", "effects.rotation=0:1:2"], "effects.rotation is not a numeric scene key"),
    (["--vary", "load.F_x=0:1:2"], "load.F_x is not a numeric scene key"),
    (["--vary", "contacts.mu=1:2:0"], "COUNT must be an integer >= 1"),
    (["--vary", "contacts.mu=1:2:2.5"], "an integer COUNT"),
    (["--vary", "contacts.mu=2:1:3:log"], "LO must be below HI"),
    (["--vary", "contacts.mu=0:1:3:log"], "log spacing needs LO > 0"),
    (["--vary", "contacts.mu=1:2:3:lin"], "expected KEY=LO:HI:COUNT[:log]"),
    (["--vary", "contacts.mu"], "expected KEY=LO:HI:COUNT[:log]"),
    (["--vary", "disks.N=4:5:3"], "cell disks.N = 4.5: expected an integer"),
    (["--vary", "disks.eps=0.05:0.15:2"], "cell disks.eps = 0.15: must be in [0, 0.1)"),
    (["--vary", "contacts.mu=1:2:2", "--vary", "contacts.mu=3:4:2"], "contacts.mu given twice"),
    (["--vary", "contacts.mu=1,2,1"], "a value listed twice"),
    (["--vary", "contacts.mu=1,2", "--damping", "0.1"], "--damping: the damped study is a packing's"),
    (["--vary", "contacts.mu=1,2", "--causality"], "--causality: the damped study is a packing's"),
    (["--vary", "contacts.mu=1,x"], "with numbers V1, V2"),
    (["--vary", "contacts.mu=1,inf"], "finite numbers"),
    (["--vary", "disks.N=4,5", "--vary", "contacts.mu=1,2", "--vary", "disks.N=6"], "disks.N given twice"),
    (["--vary", "contacts.mu=1:2:2", "--fx", "0.05:0.01"], "a map loads"),
    (["--vary", "contacts.mu=1:2:2", "--t-end", "10"], "add --slide"),
    (["--vary", "contacts.mu=1:2:2", "--workers", "0"], "--workers"),
    (["--vary", "contacts.mu=1:2:2", "--workers", "2", "--scheduler", "localhost:8786"],
     "--workers"),
]


@pytest.mark.parametrize("args, says", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_specifications_are_one_line_and_exit_2_before_anything_runs(tmp_path, args, says):
    result = run_main("map", *args, "--out", str(tmp_path / "out"))
    assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
    assert says in error_line(result, "map")
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_the_estimate_printed_first_grows_with_what_a_cell_does(tmp_path):
    """Issue 23: a map of 100 000 cells started silently. cell_seconds grows with N, with slide
    runs and their length; the CLI's estimate counts only the cells not yet on disk."""
    from diskfriction.cli.map_cmd import MapPlan, estimate
    from diskfriction.studies.maps import cell_seconds

    sweep, slide = MapParams(0.0, 0.12, "J"), MapParams(0.0, 0.12, "J", SlideParams())
    longer = MapParams(0.0, 0.12, "J", SlideParams(t_end=1e4))
    small, large = Scene(N=10, eps=1e-4), Scene(N=100, eps=1e-4)
    assert cell_seconds(small, sweep) < cell_seconds(small, slide) < cell_seconds(small, longer)
    assert cell_seconds(small, slide) < cell_seconds(large, slide)
    cells = map_cells(Scene(), [Axis("contacts.mu", grid_values(5.0, 10.0, 10_000))], "x")
    plan = MapPlan(slide, None, None, None, cell_seconds, (), None, None)
    assert estimate(cells, plan, tmp_path, 2, False).endswith("h on 2 workers (a rough estimate)")


def test_values_listed_keep_their_order_and_three_keys_make_every_combination():
    from diskfriction.cli.map_cmd import grid

    axes, cells = grid(Scene(), ["contacts.mu=10,0.3,1", "disks.N=4,5", "disks.eps=0,0.01"])
    assert [a.values for a in axes] == [(10.0, 0.3, 1.0), (4.0, 5.0), (0.0, 0.01)]
    assert len(cells) == 12 and cells[1].values == (("contacts.mu", 10.0), ("disks.N", 4), ("disks.eps", 0.01))
    assert cells[-1].scene.mu == 1.0 and cells[-1].scene.N == 5 and cells[-1].scene.eps == 0.01
