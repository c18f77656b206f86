"""Packing preparation benchmark: seconds to prepare the default packing scene's
packing at N disks with the generated kernels (models/packing/prepared.py), the FIRE steps and
relaxations it took, phi and z. One line per N, measured in this run; the kernels are compiled
(or loaded) before the clock starts.

Run: python benchmarks/prepare_packing.py [N ...]   (default: 64 256 1024)
"""
from __future__ import annotations

import sys
import time

from diskfriction.models.packing.prepared import contact_number, prepare_scene
from diskfriction.scenes.packing import PackingScene
from diskfriction.symbolic.kernels import load_packing_kernels


def main(sizes: list[int]) -> None:
    load_packing_kernels(PackingScene().resolved_effects)
    print(f"{'N':>6} {'seconds':>8} {'FIRE steps':>10} {'relaxations':>11} {'phi':>7} "
          f"{'P / target - 1':>14} {'z':>6} {'rattlers':>8}")
    for N in sizes:
        scene = PackingScene(N=N)
        start = time.perf_counter()
        packing = prepare_scene(scene)
        seconds = time.perf_counter() - start
        _, z = contact_number(packing)
        print(f"{N:>6} {seconds:>8.2f} {packing.steps:>10} {packing.relaxations:>11} "
              f"{packing.phi:>7.4f} {packing.pressure / scene.pressure - 1:>14.1e} {z:>6.3f} "
              f"{int(packing.rattlers.sum()):>8}")


if __name__ == "__main__":
    main([int(n) for n in sys.argv[1:]] or [64, 256, 1024])
