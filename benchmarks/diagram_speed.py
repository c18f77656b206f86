"""The paper scene's diagram.png alone, as the first README command draws it once per process.

Run: python benchmarks/diagram_speed.py [--repeat 5]. Each repeat is a fresh interpreter that
sweeps the paper scene (kernels from the cache), then times importing matplotlib's figure and
Agg canvas, and the first reports.bifurcation.plot_diagram call (drawing and writing the PNG,
every cache of matplotlib's still cold in that process). Prints medians over the repeats,
measured in this run.
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys

CHILD = """
import json, time, tempfile
from pathlib import Path
from diskfriction.models.chain.sweep import SweepParams, sweep
from diskfriction.matrices import Matrix
from diskfriction.scenes.load import default_scene_path, load_scene
from diskfriction.symbolic import System
scene = load_scene(default_scene_path())
branch = sweep(System.from_scene(scene), 0.0, 0.12, Matrix(scene.matrix), SweepParams())
start = time.perf_counter()
import matplotlib.backends.backend_agg, matplotlib.figure
imported = time.perf_counter()
from diskfriction.reports.bifurcation import plot_diagram
with tempfile.TemporaryDirectory() as tmp:
    drawn_from = time.perf_counter()
    plot_diagram(branch, scene, Path(tmp) / "diagram.png")
    drawn = time.perf_counter()
print(json.dumps({"import": imported - start, "diagram": drawn - drawn_from}))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5, help="fresh processes (default 5)")
    args = parser.parse_args()
    runs = [json.loads(subprocess.run([sys.executable, "-c", CHILD], check=True,
                                      capture_output=True, text=True).stdout)
            for _ in range(args.repeat)]
    median = {key: statistics.median(run[key] for run in runs) for key in runs[0]}
    print(f"diagram.png of the paper scene: medians of {args.repeat} fresh processes")
    print(f"  importing matplotlib's figure and Agg canvas: {median['import']:.3f} s")
    print(f"  plot_diagram, first call (draw + write): {median['diagram']:.3f} s")


if __name__ == "__main__":
    main()
