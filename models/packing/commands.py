"""The packing's front: what each command does with a packing scene (models/__init__.py):
prepare, bifurcate (shear), simulate, verify, report and map. cli/ parses the arguments and
calls these; they check at the door (check_packing: memory, what the preparation can make, run
length, with a rough wall-time estimate), run the packing's physics and studies, write through
reports/ and print. Values on the command line and in files are raw units (docs/packings.md).

bifurcate keeps what a long shear finished (studies/kept_shear.py: a rerun resumes after it)
and writes its outputs together at the end, each naming its scene
(reports/packing_outputs.py); DIR/segments/scene.json names the scene of the shear under way,
and a DIR holding another scene's files is refused."""
from __future__ import annotations

import argparse
import dataclasses
import shutil
import sys
import time
from pathlib import Path

from diskfriction.cli.bifurcate_cmd import parse_drags, parse_window
from diskfriction.cli.common import (EXIT_FAILED, CommandError, check_memory, check_window_covered,
                                     matrix_from_args, number, output_dir, run_length)
from diskfriction.cli.map_cmd import MapPlan
from diskfriction.cli.progress import Progress
from diskfriction.files import json_text
from diskfriction.matrices import Matrix
from diskfriction.models.packing.commands_checks import (check_packing, check_packing_bifurcate,
                                                         check_packing_simulate, spectra_from_args,
                                                         spectra_line)
from diskfriction.scenes.packing import PackingScene
from diskfriction.words import count

CHAIN_ONLY = {"fx": "a packing's load is its strain: [shear] gamma in the scene",
              "p": "only with --problem FILE.py; a packing's load is its strain, [shear] gamma in "
                   "the scene", "ds_max": "a packing's step follows its strain"}
"""bifurcate's options a packing scene does not take, and why."""


PLASTIC_EVENTS = 1000
"""The plastic events a command passes (models/packing/plastic.py) before it stops at the next."""


def bifurcate(args: argparse.Namespace, scene: PackingScene,
                window: tuple[float, float] | None) -> int:
    """bifurcate on a packing scene: prepare, shear (with `window`, --window as bifurcate
    parsed and checked it), write packing.npz, branch.npz, collisions.json, plastic.json and
    diagram.png, with --damping damped.json and precursors.csv (the damped stability at each
    drag, damping_from_args; with --dashpots contact dashpots of those rates), together
    (reports/packing_outputs.save_packing_outputs); exit 1 with one line when the branch ends
    short of the scene's strain (a plastic event, a fold in gamma), after writing what it
    reached. An --out holding another scene's files is refused
    (exit 2)."""
    for option, why in CHAIN_ONLY.items():
        if getattr(args, option) is not None:
            flag = "--" + option.replace("_", "-")
            raise CommandError(f"bifurcate error: {flag}: {why} (got {getattr(args, option)!r})")
    if args.workers is not None and args.workers < 0:
        raise CommandError(f"bifurcate error: --workers: must be >= 0 (got {args.workers})")
    spectra = spectra_from_args(args, scene, window)
    if args.json and spectra != "full":
        raise CommandError(f"bifurcate error: --json: prints the collisions located, and spectra "
                           f"{spectra} locate none; give --spectra full")

    matrix = matrix_from_args("bifurcate", args, scene)
    drags = damping_from_args(args, scene, spectra, matrix)
    out = output_dir("bifurcate", args.out, Path("out") / "bifurcate" / scene.name)
    scene = dataclasses.replace(scene, matrix=str(matrix), spectra=spectra)
    refuse_other_scene("bifurcate", out, scene)
    check_packing_bifurcate(args, scene, window)

    from diskfriction.continuation.stepping.arclength import ContinuationError
    from diskfriction.continuation.stepping.segment import SegmentSolveError
    from diskfriction.continuation.linalg.solves import SingularMatrix
    from diskfriction.continuation.branch import StopCode
    from diskfriction.continuation.detection.collisions import DetectionParams
    from diskfriction.continuation.spectra.window import WindowCrowded
    from diskfriction.files import save_json
    from diskfriction.models.packing.equilibria import MissedContact, NotJammed
    from diskfriction.models.packing.plastic import RelaxationFailed
    from diskfriction.models.packing.prepared import prepare_scene
    from diskfriction.continuation.records import brief, collision_records
    from diskfriction.models.packing.sampled import SampleFailed
    from diskfriction.models.packing.shear import ShearParams, shear
    from diskfriction.studies.kept_shear import kept_segments
    from diskfriction.reports.packing_outputs import (DAMPED_OUTPUTS, OUTPUTS, RUN_SCENE,
                                                      damped_shear, save_packing_outputs,
                                                      scene_record)

    g0, g1 = scene.gamma_range
    save_json(out / RUN_SCENE, {"scene": scene_record(scene)})  # the shear under way's scene
    progress = Progress("bifurcate")
    kept = None
    try:
        progress.stage(f"prepare {scene.N} disks to pressure {scene.pressure:g}")
        packing = prepare_scene(scene, progress.part("relax"))
        kept = kept_segments(out / "segments", scene, window, args.detection, PLASTIC_EVENTS)
        progress.stage(f"shear gamma 0 -> {g1:g}{kept.resumed()}")
        params = ShearParams(detection=DetectionParams(mode=args.detection), workers=args.workers)
        try:
            branch = shear(scene, packing, params,
                           lambda gamma: progress(gamma / g1, f"gamma = {gamma:.3e}"),
                           plastic_events=PLASTIC_EVENTS, window=window, done=kept.done,
                           on_segment=kept.save)
        except (ContinuationError, MissedContact, NotJammed, RelaxationFailed, SampleFailed,
                WindowCrowded) as error:
            kept_line = (f" (the segments finished before it are kept in {kept.directory}: a "
                         "rerun resumes after them)" if kept.finished() else "")
            raise CommandError(f"bifurcate error: {scene.source}: {error}{kept_line}",
                               EXIT_FAILED) from None
        if window is not None and scene.resolved_spectra == "full":
            check_window_covered(branch, args.window, matrix, 1.0)
        damped = None
        if drags is not None:
            progress.stage(f"damped stability at {count(len(drags), 'drag')}")
            try:
                damped = damped_shear(scene, packing, branch, drags, args.dashpots)
            except (SegmentSolveError, SingularMatrix) as error:
                raise CommandError(f"bifurcate error: --damping: {scene.source}: a damped onset "
                                   f"not located: {error}", EXIT_FAILED) from None
        progress.stage(f"writing {out}/{', '.join(OUTPUTS + (DAMPED_OUTPUTS if damped else ()))}")
        written = save_packing_outputs(out, kept.directory / "writing", branch, scene, packing,
                                       damped)
        kept.release(keep=False)
    except BaseException:
        directory = out / "segments"
        finished = kept is not None and kept.finished()
        if kept is None or not finished:  # nothing to resume from: the shear's claim on DIR goes too
            shutil.rmtree(directory, ignore_errors=True)
        args.keeps = ("segments", directory if finished else None)  # what Ctrl-C says (cli.common)
        raise
    finally:
        progress.close()
    records = collision_records(branch)
    if args.json:
        print(json_text(brief(records)))
    else:
        print(f"{count(len(branch), 'equilibrium', 'equilibria')} from gamma = 0 to "
              f"{branch.gamma[-1]:.6g}, max residual {branch.residual.max():.1e}, "
              f"{branch.events} contact events split; {branch.contacts[0]} -> "
              f"{branch.contacts[-1]} contacts, {branch.loose[-1]} loose disks")
        print(f"{count(len(branch.plastic), 'plastic event')} passed (branch lost, relaxed "
              f"{'with' if scene.resolved_effects.pair_friction else 'without'} friction)"
              f"{':' if branch.plastic else ''}")
        for e in branch.plastic:
            print(f"  gamma = {e.gamma:.9f} ({e.kind}): sigma_xy {e.stress_before:.6g} -> "
                  f"{e.stress_after:.6g}")
        print(spectra_line(branch, scene, records, window))
        for line in damped_lines(damped):
            print(line)
        print(f"wrote {out}/{', '.join(written)}")
    if not branch.status.reached:
        why = ("a plastic event: the quasistatic branch folds back in gamma (a saddle-node)"
               if branch.status.code is StopCode.FOLD else branch.status.sentence(len(branch)))
        raise CommandError(f"bifurcate error: {scene.source}: the branch ended at gamma = "
                           f"{branch.gamma[-1]:.9g}, short of {g1:g}: {why}; what it reached "
                           f"is written", EXIT_FAILED)
    return 0


def damping_from_args(args: argparse.Namespace, scene: PackingScene, spectra: str,
                      matrix: Matrix) -> tuple[float, ...] | None:
    """The drags of --damping [omega_0] (cli/bifurcate_cmd.parse_drags), None without it; a
    one-line CommandError (exit 2) where the drag's shear has nothing to analyse: the matrix J
    (the drag's damped modes are those of M^-1 J) or spectra none. With --dashpots any matrix
    and spectra (their modes are solved at the accepted states, which every shear keeps), each
    rate > 0: dashpots of rate 0 damp nothing, and the undamped analysis locates its onsets at
    the collisions (the drag 0), where a state's growth rate rises from zero, not from below."""
    if args.damping is None:
        return None
    drags = parse_drags(args.damping)
    if args.dashpots:
        if 0.0 in drags:
            raise CommandError(f"bifurcate error: --dashpots: each rate > 0: dashpots of rate 0 "
                               f"damp nothing, and the undamped analysis is the drag 0, --damping "
                               f"0 without --dashpots (got {args.damping!r})")
        return drags
    if matrix != Matrix.M_INV_J:
        raise CommandError(f"bifurcate error: --damping: the damped modes of M q'' + eta M q' + "
                           f"J q = 0 come from the eigenvalues of M^-1 J; the shear's matrix is "
                           f"{matrix}: give --matrix M^-1J (got {args.damping!r})")
    if spectra == "none":
        auto = f" (auto for {scene.N} disks)" if (args.spectra or scene.spectra) == "auto" else ""
        raise CommandError(f"bifurcate error: --damping: the shear's spectra are none{auto}: "
                           f"nothing to analyse; give --spectra full or sample:DGAMMA (got "
                           f"{args.damping!r})")
    return drags


def damped_lines(damped) -> list[str]:
    """What bifurcate prints of a reports/packing_outputs.DampedShear, one line per drag (or
    dashpots' rate): the onsets and ends of damped instability located (spectra full) and the
    fraction of the strain with a damped-unstable mode; none without one."""
    if damped is None:
        return []
    sampled = damped.hopfs is None
    lines = []
    for i, (drag, eta) in enumerate(zip(damped.drags, damped.eta)):
        if sampled:
            located = "no onset located (spectra sampled)"
        else:
            kinds = [h.kind for h in damped.hopfs[i]]
            located = (f"{count(kinds.count('onset'), 'onset')} and "
                       f"{count(kinds.count('end'), 'end')} of damped instability located")
        what = "contact dashpots" if damped.damping == "dashpots" else "drag"
        lines.append(f"{what} {drag:g} omega_0 (eta = {eta:.4g} / time): {located}; damped-unstable "
                     f"over {100 * damped.unstable_fraction[i]:.0f} % of the strain")
    return lines


def refuse_other_scene(command: str, out: Path, scene: PackingScene) -> None:
    """A CommandError (one line, exit 2) when `out` holds files of a scene other than `scene`
    (reports/packing_outputs.other_scene: finished outputs, or a shear under way), naming the
    file, both scenes and how they differ."""
    from diskfriction.reports.packing_outputs import other_scene

    found = other_scene(out, scene)
    if found is not None:
        path, record, differ = found
        raise CommandError(f"{command} error: --out: {path.relative_to(out)} there belongs to "
                           f"scene '{record['name']}' ({record['file']}), not to '{scene.name}' "
                           f"({scene.source}): {'; '.join(differ)}; give another --out or "
                           f"remove that scene's files (got {str(out)!r})")


def simulate(args: argparse.Namespace, scene: PackingScene) -> int:
    """simulate on a packing scene: prepare, shear to --gamma (exit 1 with one line if the
    branch ends before it), perturb the equilibrium there (default: along the eigenvector of its
    fastest-growing complex pair, else random velocities), integrate, and compare the measured
    growth rate with the spectrum's. Writes run.npz, summary.json, run.png and snapshot.png
    (the packing at G, its contact forces and the perturbation)."""
    for option, why in {"fx": "a packing's load is its strain: --gamma G",
                        "realizations": "ensembles are not yet offered for packings",
                        "scheduler": "ensembles are not yet offered for packings"}.items():
        if getattr(args, option) is not None:
            raise CommandError(f"simulate error: --{option}: {why} (got {getattr(args, option)!r})")
    if args.gamma is None:
        raise CommandError("simulate error: --gamma: a packing scene needs the strain to start "
                           "from (got nothing)")
    number("simulate", "gamma", args.gamma, zero=True)
    run_length("simulate", args.t_end, args.dt)
    number("simulate", "seed", args.seed, zero=True, integer=True)
    amplitude = 1e-10 if args.amplitude is None else number("simulate", "amplitude", args.amplitude,
                                                            zero=True)
    out = output_dir("simulate", args.out, Path("out") / "simulate" / scene.name)
    refuse_other_scene("simulate", out, scene)
    check_packing_simulate(args, scene)
    given = scene  # what the outputs name (the shear below stops at --gamma)

    import numpy as np

    from diskfriction.files import save_json, save_npz
    from diskfriction.models.packing.dynamics import run_steps, time_step
    from diskfriction.models.packing.runs import FRAMES, NoComplexPair, linearized, run_from_state
    from diskfriction.reports.packing_outputs import (plot_packing_run, plot_packing_snapshot,
                                                      scene_arrays, scene_record)

    # a packing's strain range is positive: --gamma 0 shears one short step and runs from the
    # branch's first state, at gamma = 0 exactly
    # no spectrum along the way: the run's start takes its own (runs.linearized)
    scene = dataclasses.replace(scene, gamma_range=(0.0, args.gamma) if args.gamma > 0 else (0.0, 1e-12),
                                spectra="none")
    progress = Progress("simulate")
    try:
        branch, network, mass = sheared(scene, progress, args.gamma)
        if not branch.status.reached:
            raise CommandError(f"simulate error: {scene.source}: no equilibrium beyond gamma = "
                               f"{branch.gamma[-1]:.9g} (asked for {args.gamma:g}): the branch "
                               f"ends there ({branch.status.sentence(len(branch))})", EXIT_FAILED)
        k = len(branch) - 1 if args.gamma > 0 else 0
        linear = linearized(branch, k, network, mass)
        limit = 2.0 / float(np.sqrt(np.abs(linear.eigenvalues).max()))
        if args.dt is not None and args.dt >= limit:
            raise CommandError(f"simulate error: --dt: not below velocity Verlet's stability "
                               f"limit 2 / omega_max = {limit:.4g} of the start (got {args.dt!r})")
        kind = args.perturbation or ("eigenvector" if linear.mode else "random-velocity")
        steps = run_steps(args.t_end, args.dt or time_step(linear.eigenvalues), FRAMES)[0]
        progress.stage(f"run to t = {args.t_end:g} ({steps} steps)")
        try:
            done = run_from_state(branch, k, network, mass, kind, amplitude, args.t_end,
                                  scene.delta_0, args.dt, args.seed, linear)
        except NoComplexPair as error:
            raise CommandError(f"simulate error: --perturbation: {error}") from None
        run, gamma, sigma, fit = done.run, done.gamma, done.sigma_predicted, done.fit
        summary = {"scene": scene_record(given), "gamma": gamma, "perturbation": kind,
                   "amplitude": amplitude, "dt": run.dt, "t_end": float(run.t[-1]),
                   "sigma_predicted": sigma, "sigma_measured": fit.as_dict()["sigma"],
                   "fit": fit.as_dict(), "budget_drift": done.drift,
                   "kinetic_max": float(run.kinetic.max()),
                   "sliding_updates": int(run.capped[-1]), "complex_pairs": done.pairs}
        save_npz(out / "run.npz", t=run.t, q=run.q, distance=done.distance,
                 amplitude=done.mode_amplitude, budget=run.budget, kinetic=run.kinetic,
                 capped=run.capped, **scene_arrays(given))
        save_json(out / "summary.json", summary)
        plot_packing_run(run.t, done.distance, sigma, fit.sigma, scene, gamma, out / "run.png",
                         (fit.t_start, fit.t_end), done.mode_amplitude)
        q0, rows0 = done.q0, done.rows0
        plot_packing_snapshot(q0, network.radii, network.L, gamma, rows0,
                              network.normal_forces(q0, rows0, gamma), done.kick,
                              f"{scene.name} at gamma = {gamma:.4g}: contact forces (red, width "
                              f"~ F_n) and the perturbation ({kind}, blue)", out / "snapshot.png",
                              "length / time" if kind == "random-velocity" else "length")
    finally:
        progress.close()
    print(f"gamma = {gamma:g}: {count(done.pairs, 'complex pair')} of M^-1 J"
          + (f", the fastest growing at sigma = {sigma:.6g} (|Im sqrt(lambda)|)" if sigma > 0 else ""))
    measured = (f"measured sigma = {fit.sigma:.6g} over t = {fit.t_start:.4g} .. {fit.t_end:.4g} "
                f"({fit.frames} frames)" if fit.reason == "ok" else "no growth rate measured")
    print(f"run to t = {run.t[-1]:g} ({kind}, amplitude {amplitude:g}, dt {run.dt:.4g}): "
          f"{measured}; energy budget drift {done.drift:.2e} (max kinetic "
          f"{run.kinetic.max():.2e}); {int(run.capped[-1])} sliding updates")
    print(f"wrote {out}/run.npz, summary.json, run.png, snapshot.png")
    if fit.reason != "ok":
        print(f"simulate {'warning' if done.unmeasured else 'note'}: no growth rate measured: "
              f"{fit.reason}", file=sys.stderr)
    return 0


VERIFY_STATES = (8, 2)
"""verify runs from at most this many states with complex pairs and with every eigenvalue real,
evenly spread over the branch's states of each kind."""


def spread(states, count: int) -> list[int]:
    """At most `count` of the indices `states`, evenly spread (first and last included)."""
    import numpy as np

    if len(states) <= count:
        return [int(k) for k in states]
    return [int(states[i]) for i in np.unique(np.linspace(0, len(states) - 1, count).round().astype(int))]


def verify(args: argparse.Namespace, scene: PackingScene) -> int:
    """verify on a packing scene: shear over the scene's strain, then run the dynamics from up to
    VERIFY_STATES states: along the fastest complex pair's eigenvector from states with complex
    pairs, random velocities from states with every eigenvalue real; tabulate the growth rate
    measured against the spectrum's and whether contacts slid. Writes verify.json, verify.md."""
    number("verify", "t-end", args.t_end)
    number("verify", "amplitude", args.amplitude, zero=True)
    if args.matrix is not None:
        raise CommandError(f"verify error: --matrix: a packing's growth rates are those of M^-1 J "
                           f"(got {args.matrix!r})")
    out = output_dir("verify", args.out, Path("out") / "verify" / scene.name)
    refuse_other_scene("verify", out, scene)
    check_packing("verify", dataclasses.replace(scene, spectra="full"), strain=scene.gamma_range[1],
                  runs=sum(VERIFY_STATES),
                  t_end=args.t_end)

    import numpy as np

    from diskfriction.files import save_json, save_text
    from diskfriction.models.packing.runs import linearized, run_from_state
    from diskfriction.models.packing.shear import ShearParams
    from diskfriction.reports.packing_outputs import scene_record
    from diskfriction.reports.verify import packing_verify_table

    progress = Progress("verify")
    try:  # every state's pairs: verify picks states with and without them
        branch, network, mass = sheared(dataclasses.replace(scene, spectra="full"), progress)
        chosen = sorted(spread(np.flatnonzero(branch.n_complex > 0), VERIFY_STATES[0])
                        + spread(np.flatnonzero(branch.n_complex == 0), VERIFY_STATES[1]))
        rows, unmeasured = [], []
        for n, k in enumerate(chosen):
            linear = linearized(branch, k, network, mass)
            kind = "eigenvector" if linear.mode else "random-velocity"
            progress.stage(f"run {n + 1}/{len(chosen)} from gamma = {branch.gamma[k]:.6g} ({kind})")
            done = run_from_state(branch, k, network, mass, kind, args.amplitude, args.t_end,
                                  scene.delta_0, linear=linear)
            rest = done.settled(network, ShearParams().newton_tol)
            fit = done.fit.as_dict()
            rows.append({"gamma": done.gamma, "complex_pairs": done.pairs, "perturbation": kind,
                         "sigma_predicted": done.sigma_predicted,
                         "sigma_measured": fit["sigma"], "fit": fit,
                         "distance_end": float(done.distance[-1]), "slid": done.slid,
                         "sliding_updates": int(done.run.capped[-1]), "budget_drift": done.drift,
                         "stress_change_at_rest": rest.stress_change, "moved_at_rest": rest.moved,
                         "contacts_opened_at_rest": rest.opened,
                         "contacts_formed_at_rest": rest.formed,
                         "outcome": rest.outcome})
            if done.unmeasured:
                unmeasured.append(f"verify warning: no growth rate measured from gamma = "
                                  f"{done.gamma:.6g}: {done.fit.reason}")
        table = packing_verify_table(rows)
        save_json(out / "verify.json", {"scene": scene_record(scene), "t_end": args.t_end,
                                        "amplitude": args.amplitude, "runs": rows})
        save_text(out / "verify.md", table)
    finally:
        progress.close()
    print(table, end="")
    for line in unmeasured:
        print(line, file=sys.stderr)
    print(f"wrote {out}/verify.json, verify.md")
    return 0


def sheared(scene: PackingScene, progress: Progress, asked: float | None = None):
    """models/packing/shear.shear_scene with this command's progress lines; `asked`, the strain the
    user asked for, is the one the shear's line names (simulate --gamma 0 shears one step to
    take the branch's first state, at gamma = 0)."""
    from diskfriction.models.packing.shear import shear_scene

    g1 = scene.gamma_range[1]
    shown = g1 if asked is None else asked
    return shear_scene(scene, PLASTIC_EVENTS,
                       lambda line: progress.stage(f"shear gamma 0 -> {shown:g}"
                                                   if line.startswith("shear gamma") else line),
                       progress.part("relax"),
                       lambda g: progress(g / max(g1, 1e-300), f"gamma = {g:.3e}"))


def prepare(args: argparse.Namespace, scene: PackingScene) -> int:
    """prepare a packing scene: its frictionless packing at the target pressure, packing.npz."""
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


def report(args: argparse.Namespace, files: list, scenes: list) -> int:
    """report on one packing scene (reports/packing_report.py): shear, two dynamics runs, four
    figures and report.md; the chain's sections, settings and cache do not apply."""
    if len(scenes) > 1:
        raise CommandError(f"report error: {files[0]}: a packing scene is reported alone (got "
                           f"{len(scenes)} scenes)")
    for option, given in (("only", args.only), ("set", args.settings or None),
                          ("cache", args.cache)):
        if given is not None:
            raise CommandError(f"report error: --{option}: the packing report has no sections, "
                               f"settings or cache (got {given!r})")
    from diskfriction.reports.packing_report import build_packing_report

    scene = scenes[0]
    check_packing("report", dataclasses.replace(scene, spectra="full"), strain=scene.gamma_range[1])
    out = output_dir("report", args.out, Path("out/report") / scene.name)
    progress = Progress("report")
    try:
        written = build_packing_report(scene, out, PLASTIC_EVENTS, progress.stage)
    finally:
        progress.close()
    print(f"wrote {out / 'report.md'} and {', '.join(written[1:])}")
    return 0


NO_DYNAMICS = "a packing map runs no dynamics; `verify` runs them on one scene"


PACKING_REFUSES = {"fx": "a packing's load is its strain: [shear] gamma in the scene",
                   "slide": NO_DYNAMICS, "t_end": NO_DYNAMICS, "amplitude": NO_DYNAMICS}
"""map's options a packing scene does not take, and why."""


def packing_params(args: argparse.Namespace, scene):
    """A packing map's studies.packing_maps.PackingMapParams from --matrix, --window, --damping
    and --causality (checked: one line, exit 2); the chain's options are refused
    (PACKING_REFUSES)."""
    from diskfriction.studies.packing_maps import PackingMapParams

    for option, why in PACKING_REFUSES.items():
        if getattr(args, option) not in (None, False):
            flag = "--" + option.replace("_", "-")
            raise CommandError(f"map error: {flag}: {why} (got {getattr(args, option)!r})")
    window = parse_window(args.window, "map") if args.window is not None else None
    matrix = matrix_from_args("map", args, scene)
    drags = () if args.damping is None else parse_drags(args.damping, "map")
    if args.causality and not drags:
        raise CommandError("map error: --causality: runs the dynamics from the damped onsets; add "
                           "--damping D1,D2,... (got --causality alone)")
    if drags and matrix != Matrix.M_INV_J:
        raise CommandError(f"map error: --damping: the damped modes of M q'' + eta M q' + J q = 0 "
                           f"come from the eigenvalues of M^-1 J; the map's matrix is {matrix}: "
                           f"give --matrix M^-1J (got {args.damping!r})")
    return PackingMapParams(str(matrix), window, PLASTIC_EVENTS, drags, args.causality)


def describe_packing(cell, s: dict) -> str:
    """One printed line per packing cell: its values, status, states, how many carry complex
    pairs, the fastest growth rate, collisions and plastic events, or why it failed or ended."""
    values = ", ".join(f"{key} = {value:g}" for key, value in cell.values)
    if s["status"] == "failed":
        return f"{values}: failed: {s['reason']}"
    fastest = ("" if s["sigma_max"] is None else
               f", sigma_max = {s['sigma_max']:.4g} ({s['sigma_max'] / s['omega_c']:.3g} omega_c)")
    line = (f"{values}: {s['status']} to gamma = {s['gamma_end']:.4g}, "
            f"{count(s['states'], 'state')}, complex pairs over {100 * s['complex_fraction']:.0f} % of the strain"
            f"{fastest}, {count(s['collisions'], 'collision')}, "
            f"{count(s['plastic_events'], 'plastic event')}")
    return line + (f"; {s['reason']}" if s["reason"] else "")


def map_plan(args: argparse.Namespace, scene: PackingScene) -> MapPlan:
    """A packing map (cli/map_cmd.py): every cell prepares its packing and shears it over the
    scene's strain (studies/packing_maps.py)."""
    from diskfriction.models.packing.limits import preparation_problem
    from diskfriction.reports.packing_maps import plot_packing_map
    from diskfriction.studies.packing_maps import (PACKING_COLUMNS, packing_cell,
                                                   packing_cell_seconds)

    params = packing_params(args, scene)

    def check_cell(cell, at_once: int) -> None:
        check_memory("map", cell.scene, at_once, dense=params.window is None)
        problem = preparation_problem(cell.scene)  # models/packing/limits.py: what FIRE cannot make
        if problem is not None:
            values = ", ".join(f"{key} = {value!r}" for key, value in cell.values)
            raise CommandError(f"map error: --vary: cell {values}: {problem[0]}: {problem[1]}")

    def plot(axes, cells, records, path: Path, title: str) -> None:
        plot_packing_map(axes, cells, records, path, f"{title}, gamma 0 -> {scene.gamma_range[1]:g}")

    def study(out: Path, axes, cells, records) -> list[str]:
        from diskfriction.reports.packing_study import save_study

        return save_study(out, axes, cells, records)

    return MapPlan(params, check_cell, map_kernels, packing_cell, packing_cell_seconds,
                   PACKING_COLUMNS, plot, describe_packing, study if params.damping else None)


def map_kernels(cells, params, progress: Progress) -> str:
    """Compile the kernels every cell needs (a cell's effects may differ with mu: mu = 0 has
    no tangential law), and say what each cell runs."""
    from diskfriction.symbolic.kernels import load_packing_kernels

    for effects in dict.fromkeys(c.scene.resolved_effects for c in cells):
        load_packing_kernels(effects, progress.part("kernels"))
    g1 = cells[0].scene.gamma_range[1]
    inside = "" if params.window is None else f", Re lambda in {params.window[0]:g}:{params.window[1]:g}"
    study = "" if not params.damping else f", the damped study at {count(len(params.damping), 'drag')}"
    study += ", damped runs from every onset" if params.causality else ""
    return f"prepare and shear gamma 0 -> {g1:g} ({params.matrix}{inside}){study}"


def export(args: argparse.Namespace, scene: PackingScene) -> int:
    """export lammps: the prepared packing and a deck shearing it by damped MD at --rate with
    the drag --damping to [shear] gamma (peers/packing_deck.py; cli/export_cmd.py checked both)."""
    from diskfriction.models.packing.prepared import prepare_scene
    from diskfriction.peers import packing_deck

    packing_deck.check_representable(scene)
    packing_deck.check_run(scene, args.rate)
    out = output_dir("export", args.out, Path("out") / "export" / scene.name)
    check_packing("export", scene)
    progress = Progress("export")
    try:
        progress.stage(f"prepare {scene.N} disks to pressure {scene.pressure:g}")
        deck = packing_deck.shear_deck(scene, prepare_scene(scene, progress.part("relax")),
                                       args.rate, args.damping)
        paths = deck.save(out)
    finally:
        progress.close()
    print("\n".join(packing_deck.summary(deck, paths)))
    return 0
