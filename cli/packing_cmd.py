"""``diskfriction bifurcate PACKING_SCENE [--matrix J|M^-1J] [--workers K] [--out DIR]
[--json]``: prepare the scene's packing, shear it quasistatically with friction and locate
every birth and death of a complex pair (issue 25, docs/packings.md#shear)."""
from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

from diskfriction.cli.common import EXIT_FAILED, CommandError, matrix_from_args, output_dir
from diskfriction.cli.progress import Progress
from diskfriction.scenes.packing import PackingScene
from diskfriction.words import count

CHAIN_ONLY = {"fx": "a packing's load is its strain: [shear] gamma in the scene",
              "window": "spectral windows are not yet offered for packings",
              "p": "only with --problem FILE.py", "ds_max": "a packing's step follows its strain"}
"""bifurcate's options a packing scene does not take, and why."""


def run_packing(args: argparse.Namespace, scene: PackingScene) -> int:
    """bifurcate on a packing scene: prepare, shear, write branch.npz, collisions.json,
    diagram.png and packing.npz; exit 1 with one line when the branch ends short of the scene's
    strain (a plastic event, a fold in gamma), after writing what it reached."""
    for option, why in CHAIN_ONLY.items():
        if getattr(args, option) is not None:
            flag = "--" + option.replace("_", "-")
            raise CommandError(f"bifurcate error: {flag}: {why} (got {getattr(args, option)!r})")
    if args.workers is not None and args.workers < 0:
        raise CommandError(f"bifurcate error: --workers: must be >= 0 (got {args.workers})")
    matrix = matrix_from_args("bifurcate", args, scene)
    out = output_dir("bifurcate", args.out, Path("out") / "bifurcate" / scene.name)

    from diskfriction.continuation.arclength import ContinuationError
    from diskfriction.continuation.branch import StopCode
    from diskfriction.continuation.collisions import DetectionParams
    from diskfriction.packings.equilibria import MissedContact
    from diskfriction.packings.prepare import save_packing
    from diskfriction.packings.prepared import prepare_scene
    from diskfriction.packings.shear import ShearParams, shear
    from diskfriction.reports.packing_outputs import (collision_records, plot_packing_diagram,
                                                      save_packing_branch)

    scene = dataclasses.replace(scene, matrix=str(matrix))
    g0, g1 = scene.gamma_range
    progress = Progress("bifurcate")
    try:
        progress.stage(f"prepare {scene.N} disks to pressure {scene.pressure:g}")
        packing = prepare_scene(scene, progress.part("relax"))
        save_packing(out / "packing.npz", packing)
        progress.stage(f"shear gamma 0 -> {g1:g}")
        params = ShearParams(detection=DetectionParams(mode=args.detection), workers=args.workers)
        try:
            branch = shear(scene, packing, params,
                           lambda gamma: progress(gamma / g1, f"gamma = {gamma:.3e}"))
        except (ContinuationError, MissedContact) as error:
            raise CommandError(f"bifurcate error: {scene.source}: {error}", EXIT_FAILED) from None
        progress.stage(f"writing {out}/branch.npz, collisions.json")
        save_packing_branch(out, branch, scene)
        progress.stage(f"plotting {out}/diagram.png")
        plot_packing_diagram(branch, scene, out / "diagram.png")
    finally:
        progress.close()
    records = collision_records(branch)
    if args.json:
        print(json.dumps(records, indent=1))
    else:
        print(f"{count(len(branch), 'equilibrium', 'equilibria')} from gamma = 0 to "
              f"{branch.gamma[-1]:.6g}, max residual {branch.residual.max():.1e}, "
              f"{branch.events} contact events split; {branch.contacts[0]} -> "
              f"{branch.contacts[-1]} contacts, {branch.loose[-1]} loose disks")
        print(f"{count(len(records), 'collision')} ({matrix}) with gamma >= {g0:g}; complex "
              f"pairs at {100 * (branch.n_complex > 0).mean():.0f} % of the equilibria, at most "
              f"{branch.n_complex.max()}")
        print(f"wrote {out}/branch.npz, collisions.json, diagram.png, packing.npz")
    if not branch.status.reached:
        why = ("a plastic event: the quasistatic branch folds back in gamma (a saddle-node)"
               if branch.status.code is StopCode.FOLD else branch.status.sentence(len(branch)))
        raise CommandError(f"bifurcate error: {scene.source}: the branch ended at gamma = "
                           f"{branch.gamma[-1]:.9g}, short of {g1:g}: {why}; what it reached "
                           f"is written", EXIT_FAILED)
    return 0
