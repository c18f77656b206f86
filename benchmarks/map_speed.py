"""Parameter-map benchmark: the cost of a cell, and the speed-up from 1 to 2 workers.

Run: python benchmarks/map_speed.py [--cells 6] [--t-end 1000] [--matrix "M^-1 J"]
The map: the paper's scene (N = 10, eps = 0) with contacts.mu from 5 to 20 in --cells values,
every cell a full bifurcate of 0 .. 0.12 and one run per window to t_end (`diskfriction map
--slide`). It runs twice, each time from an empty directory on a fresh local cluster (start
included), with 1 and then 2 worker processes, after the kernels and the stepper are compiled
here (as the command does). Prints per map the wall time and per cell the median wall time a
worker spent on it, the speed-up, and the load average of the machine before and after: on a
shared machine other work takes cores from the workers, and the figures say so.
"""
from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time

from diskfriction.studies.maps import Axis, MapParams, SlideParams, grid_values, map_cells, run_map
from diskfriction.dynamics.stepper import load_stepper
from diskfriction.scenes import Scene
from diskfriction.symbolic import System


def timed_map(cells, params: MapParams, workers: int) -> tuple[float, list[float]]:
    """(wall time of the whole map [s], wall time of each cell in its worker [s])."""
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        records = run_map(cells, params, out, workers=workers)
        wall = time.perf_counter() - start
    return wall, [r["summary"]["wall_time"] for r in records]


def load() -> str:
    return "load average " + ", ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--cells", type=int, default=6)
    ap.add_argument("--t-end", type=float, default=1000.0)
    ap.add_argument("--matrix", default="M^-1 J", choices=("J", "M^-1 J"))
    args = ap.parse_args()
    scene = Scene()
    load_stepper(System.from_scene(scene).kernels)
    cells = map_cells(scene, [Axis("contacts.mu", grid_values(5.0, 20.0, args.cells))], "paper")
    params = MapParams(0.0, 0.12, args.matrix, SlideParams(t_end=args.t_end))
    print(f"{len(cells)} cells (paper scene, contacts.mu 5 .. 20), bifurcate 0 .. 0.12 "
          f"({args.matrix}) + one run per window to t = {args.t_end:g}; {os.cpu_count()} cores")
    walls = {}
    for workers in (1, 2):
        before = load()
        walls[workers], cell_times = timed_map(cells, params, workers)
        print(f"  {workers} worker(s): {walls[workers]:.1f} s wall, {walls[workers] / len(cells):.2f} s "
              f"per cell; a cell takes {statistics.median(cell_times):.2f} s in its worker "
              f"(median; {min(cell_times):.2f} .. {max(cell_times):.2f}) [{before} before, "
              f"{load()} after]")
    print(f"  speed-up 1 -> 2 workers: {walls[1] / walls[2]:.2f}")


if __name__ == "__main__":
    main()
