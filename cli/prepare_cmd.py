"""``diskfriction prepare [FILE] --out DIR``: prepare a packing scene's packing (issue 25,
docs/packings.md): packing.npz (every field of packings.prepare.Packing, loads back bit for
bit) and packing.json (what it is: N, L, phi, the pressure reached, contacts, rattlers), both
naming the scene (reports/packing_outputs.scene_record); a DIR holding another scene's files is
refused."""
from __future__ import annotations

import argparse
import time
from importlib import resources
from pathlib import Path

from diskfriction.cli.common import CommandError, check_packing, output_dir, scene_from_args
from diskfriction.cli.packing_cmd import refuse_other_scene
from diskfriction.cli.progress import Progress
from diskfriction.scenes.packing import PackingScene

PACKING_SCENE = resources.files("diskfriction.scenes") / "packing.toml"
"""prepare's scene without FILE: the packaged packing scene."""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``prepare`` subcommand."""
    parser = subparsers.add_parser(
        "prepare", help="prepare a packing scene's frictionless packing",
        description="Place a packing scene's disks at random from its seed and relax them "
                    "without friction (FIRE) to its target pressure; write packing.npz and "
                    "packing.json. The same scene gives the same packing bit for bit.")
    parser.add_argument("scene", nargs="?", metavar="FILE", default=str(PACKING_SCENE),
                        help="packing scene TOML file, geometry = \"packing\" (default: the "
                             "packaged packing scene, scenes/packing.toml: 256 disks)")
    parser.add_argument("--out", metavar="DIR",
                        help="output directory (default: out/prepare/SCENE); one holding another "
                             "scene's packing is refused")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    scene = scene_from_args(args)
    if not isinstance(scene, PackingScene):
        raise CommandError(f"prepare error: {scene.source}: a chain scene: prepare takes a "
                           f"packing scene (geometry = \"packing\", docs/packings.md)")
    out = output_dir("prepare", args.out, Path("out") / "prepare" / scene.name)
    refuse_other_scene("prepare", out, scene)
    check_packing("prepare", scene)
    from diskfriction.files import save_json
    from diskfriction.models.packing.prepare import save_packing
    from diskfriction.models.packing.prepared import contact_number, prepare_scene
    from diskfriction.reports.packing_outputs import scene_arrays, scene_record

    progress = Progress("prepare")
    try:
        progress.stage(f"{scene.N} disks to pressure {scene.pressure:g}")
        start = time.perf_counter()
        packing = prepare_scene(scene, progress.part("relax"))
        seconds = time.perf_counter() - start
    finally:
        progress.close()
    n_contacts, z = contact_number(packing)
    rattling = packing.rattlers
    save_packing(out / "packing.npz", packing, scene_arrays(scene))
    summary = {"scene": scene_record(scene), "N": scene.N, "L": packing.L, "phi": packing.phi,
               "pressure": packing.pressure, "target_pressure": scene.pressure,
               "max_force": packing.max_force, "contacts": n_contacts,
               "rattlers": int(rattling.sum()), "z": z, "fire_steps": packing.steps,
               "relaxations": packing.relaxations, "seconds": seconds}
    save_json(out / "packing.json", summary)
    print(f"{scene.N} disks: phi = {packing.phi:.4f}, P = {packing.pressure:.6g} (target "
          f"{scene.pressure:g}), {n_contacts} contacts, z = {z:.3f} without the "
          f"{int(rattling.sum())} rattlers, max |F| = {packing.max_force:.1e}; "
          f"{seconds:.1f} s -> {out}")
    return 0
