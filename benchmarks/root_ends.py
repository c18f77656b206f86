"""Square-root ends (continuation/detection/root_ends.py): a packing sheared from its preparation to
GAMMA (window LO:HI, as `bifurcate --window`, scans inline, every plastic event passed), once
with the steps that end where a contact opens or forms treated apart ("root ends", the code in
use) and once without ("plain": PackingEquilibria.root_events gives none). The continuation's
own path does not depend on it, so both follow the same equilibria; the scans differ. Prints
per variant the seconds, the points, the full spectra (window samples with a window) and partial samples
the whole run took, and the collisions; then how the two collision lists match (same kind
within 1e-9 in strain).

Run: python benchmarks/root_ends.py [N:SEED:GAMMA[:LO:HI]]   (default 256:1:0.003:-3:8)
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from diskfriction.continuation.linalg.solves import measured
from diskfriction.models.packing.equilibria import PackingEquilibria
from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.shear import ShearParams, shear
from diskfriction.scenes.packing import PackingScene
from diskfriction.scenes.scene import SceneValueError
from packing_cases import read_case

MATCH = 1e-9
"""Two collisions of the same kind this close in strain are the same one."""


def run(scene: PackingScene, window, roots: bool):
    """(seconds, branch, Work) of the shear with or without square-root ends."""
    packing = prepare_scene(scene)
    original = PackingEquilibria.root_events
    if not roots:
        PackingEquilibria.root_events = lambda self: None
    try:
        start = time.perf_counter()
        with measured() as spent:
            branch = shear(scene, packing, ShearParams(workers=0), plastic_events=10 ** 6, window=window)
        return time.perf_counter() - start, branch, spent
    finally:
        PackingEquilibria.root_events = original


def unmatched(these, others) -> list:
    """The collisions of `these` with no collision of `others` of the same kind within MATCH."""
    return [c for c in these if not any(o.kind == c.kind and abs(o.p - c.p) <= MATCH for o in others)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("case", nargs="?", default="256:1:0.003:-3:8")
    case = parser.parse_args().case
    N, seed, gamma, window = read_case(parser, case, "GAMMA", float)
    try:
        scene = PackingScene(N=N, seed=seed, gamma_range=(0.0, gamma), spectra="full")
    except SceneValueError as error:
        parser.error(str(error))
    print(f"{N} disks, seed {seed}, to gamma = {gamma:g}, window {window}, scans inline")
    results = {}
    for name, roots in (("root ends", True), ("plain", False)):
        seconds, branch, spent = run(scene, window, roots)
        results[name] = branch
        print(f"{name:>10}: {seconds:7.1f} s, {len(branch)} points, {spent.spectra} full spectra, "
              f"{spent.spectra_partial} partial samples, {len(branch.collisions)} collisions, "
              f"{len(branch.plastic)} plastic events", flush=True)
    ours, plain = results["root ends"].collisions, results["plain"].collisions
    only_ours, only_plain = unmatched(ours, plain), unmatched(plain, ours)
    same = [min(abs(o.p - c.p) for o in plain if o.kind == c.kind) for c in ours if c not in only_ours]
    print(f"matched within {MATCH:g}: {len(same)} (max |d gamma| {max(same, default=0.0):.2g}); "
          f"only with root ends: {len(only_ours)}, only plain: {len(only_plain)}")
    for label, extra in (("root ends", only_ours), ("plain", only_plain)):
        for c in extra:
            print(f"  only {label}: gamma = {c.p:.15g} {c.kind.value} lambda = {c.eigenvalue:.6g}")
    if not np.array_equal(results["root ends"].gamma, results["plain"].gamma):
        print("note: the two runs' equilibria differ")


if __name__ == "__main__":
    main()
