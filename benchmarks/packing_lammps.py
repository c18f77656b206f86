"""Our quasistatic shear of a packing against LAMMPS's damped shear of the same packing: the
seconds each takes to gamma = GAMMA_END, and the stress-strain curves of both in one figure.

For each N: the packing of the scene defaults with seed 1, mu = 10, pressure 0.1 is prepared
(not timed), then sheared in this one run
- by us: models/packing/shear.shear with the scene's spectra (default "none": the equilibria,
  contact and plastic events and the stress, no spectrum), up to PLASTIC_EVENTS plastic events
  passed; its wall time, accepted points, contact events and plastic events;
- by LAMMPS at each rate R: the deck of `diskfriction export lammps` (peers/packing_deck.py: the
  same disks and contact constants, a tilted periodic box under fix deform remap v, a drag of
  `damping` omega_0 relative to the flow), one MPI process, one OpenMP thread; its own "Loop
  time" (the steps only) and the wall time of the lmp process (its start, reading the data, the
  first neighbour list).
The scene's tangential law is the default "mindlin-smooth" unless --law says otherwise; LAMMPS
always has the linear law with a sharp cap (peers/packing_deck.law_note). The figure (--figure,
for the first N) shows sigma_xy(gamma) of our branch (its `stress` column, index 2), of our
branch with the linear law (--law-too, untimed), and of LAMMPS at each rate.

The load average is printed before and after each measurement: the machine is shared.

Run: python benchmarks/packing_lammps.py [--sizes 64 256 1024] [--rates 1e-5 1e-6]
     [--gamma 0.01] [--spectra none] [--law mindlin-smooth] [--law-too LAW]
     [--figure packing_lammps.png] [--keep DIR]
"""
from __future__ import annotations

import argparse
import os
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

PLASTIC_EVENTS = 1000
"""As bifurcate: plastic events passed before the shear stops."""


def load() -> str:
    return f"{os.getloadavg()[0]:.2f}"


def scene_of(N: int, gamma: float, spectra: str, law: str):
    from diskfriction.scenes import Effects
    from diskfriction.scenes.packing import PackingScene

    return PackingScene(N=N, seed=1, mu=10.0, pressure=0.1, gamma_range=(0.0, gamma),
                        spectra=spectra, effects=Effects(law, wall_friction=False),
                        name=f"packing{N}", source="benchmarks/packing_lammps.py")


def ours(scene, packing) -> dict:
    """One timed shear: seconds, points, contact events, plastic events, sigma_xy(gamma)."""
    from diskfriction.models.packing.shear import shear

    t0 = time.perf_counter()
    branch = shear(scene, packing, plastic_events=PLASTIC_EVENTS)
    seconds = time.perf_counter() - t0
    return {"seconds": seconds, "points": len(branch), "events": branch.events,
            "plastic": len(branch.plastic), "gamma_end": float(branch.gamma[-1]),
            "gamma": np.asarray(branch.gamma), "sigma_xy": np.asarray(branch.stress)[:, 2]}


def theirs(lammps, scene, packing, rate: float, workdir: Path) -> dict:
    """One LAMMPS run of the exported deck: loop and wall seconds, steps, sigma_xy(gamma)."""
    from diskfriction.peers.lammps_run import loop_seconds
    from diskfriction.peers.packing_deck import STRESS_FILE, read_stress, shear_deck

    deck = shear_deck(scene, packing, rate)
    deck.save(workdir)
    t0 = time.perf_counter()
    log = lammps.run(workdir, {})
    wall = time.perf_counter() - t0
    curve = read_stress(workdir / STRESS_FILE)
    return {"loop": loop_seconds(log), "wall": wall, "steps": deck.steps,
            "gamma": curve.gamma, "sigma_xy": curve.sigma_xy}


def busy() -> str:
    """The other processes using a CPU now (ps), one line."""
    try:
        ps = subprocess.run(["ps", "-eo", "pid,ppid,pcpu,args", "--sort=-pcpu"], capture_output=True,
                            text=True).stdout.splitlines()[1:]
    except OSError:
        return "ps not available"
    me = str(os.getpid())
    rows = [line.split(None, 3) for line in ps]
    rows = [f"{cpu} % {args[:80]}" for pid, parent, cpu, args in rows
            if float(cpu) >= 20 and me not in (pid, parent)]
    return "; ".join(rows[:5]) or "nothing else above 20 % of a core"


def plot(path: Path, N: int, curves: dict, gamma: float) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    for label, (g, s, style) in curves.items():
        ax.plot(g, s, style, label=label, lw=1.0)
    ax.set_xlim(0, gamma)
    ax.set_xlabel("shear strain gamma")
    ax.set_ylabel("sigma_xy [force / length]")
    ax.set_title(f"{N} disks (seed 1, P = 0.1, mu = 10): our branch, LAMMPS damped shear", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main() -> None:
    from diskfriction.models.packing.prepared import prepare_scene
    from diskfriction.peers.lammps_run import find_lammps

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[64, 256, 1024])
    ap.add_argument("--rates", type=float, nargs="+", default=[1e-5, 1e-6])
    ap.add_argument("--gamma", type=float, default=0.01)
    ap.add_argument("--spectra", default="none", help="our shear's spectra (default none)")
    ap.add_argument("--law", default="mindlin-smooth", help="the scene's tangential law")
    ap.add_argument("--law-too", default="",
                    help="a second law of ours in the figure, untimed (default: none)")
    ap.add_argument("--figure", type=Path, default=Path("packing_lammps.png"))
    ap.add_argument("--keep", type=Path, default=None,
                    help="keep LAMMPS's files and both codes' curves (N<N>_curves.npz) in DIR")
    args = ap.parse_args()

    lammps = find_lammps()
    print(f"LAMMPS {lammps.version} (1 process, OMP_NUM_THREADS=1); {os.cpu_count()} cores; "
          f"gamma 0 -> {args.gamma:g}; ours: spectra {args.spectra!r}, law {args.law!r}; "
          f"LAMMPS: the linear law with a sharp cap")
    rows = []
    with tempfile.TemporaryDirectory(prefix="packing-lammps-") as tmp:
        root = args.keep or Path(tmp)
        for index, N in enumerate(args.sizes):
            scene = scene_of(N, args.gamma, args.spectra, args.law)
            packing = prepare_scene(scene)
            print(f"\nN = {N}: L = {packing.L:.6g}; load {load()}; running: {busy()}", flush=True)
            mine = ours(scene, packing)
            print(f"  ours: {mine['seconds']:.1f} s, {mine['points']} points, {mine['events']} "
                  f"contact events, {mine['plastic']} plastic events, to gamma = "
                  f"{mine['gamma_end']:.6g}; load {load()}", flush=True)
            runs = {}
            for rate in args.rates:
                runs[rate] = theirs(lammps, scene, packing, rate, root / f"N{N}_rate{rate:g}")
                r = runs[rate]
                print(f"  LAMMPS rate {rate:g}: loop {r['loop']:.1f} s, wall {r['wall']:.1f} s, "
                      f"{r['steps']} steps; load {load()}", flush=True)
            rows.append((N, mine, runs))
            if args.keep:
                np.savez(root / f"N{N}_curves.npz", ours_gamma=mine["gamma"], ours_sigma_xy=mine["sigma_xy"],
                         **{f"lammps_{rate:g}_{key}": runs[rate][key] for rate in args.rates
                            for key in ("gamma", "sigma_xy")})
            if index == 0:
                curves = {f"ours, {args.law} (quasistatic)": (mine["gamma"], mine["sigma_xy"], "k-")}
                if args.law_too:
                    other = ours(scene_of(N, args.gamma, args.spectra, args.law_too), packing)
                    curves[f"ours, {args.law_too} (quasistatic)"] = (other["gamma"],
                                                                     other["sigma_xy"], "b-")
                for rate, style in zip(args.rates, ("r-", "m-", "g-", "c-")):
                    curves[f"LAMMPS rate {rate:g}"] = (runs[rate]["gamma"], runs[rate]["sigma_xy"], style)
                plot(args.figure, N, curves, args.gamma)
                print(f"  wrote {args.figure}", flush=True)
    head = "| N | diskfriction, spectra " + args.spectra + " | " + " | ".join(
        f"LAMMPS rate {rate:g}: loop (wall)" for rate in args.rates) + " |"
    print("\n" + head + "\n|" + "---|" * (2 + len(args.rates)))
    for N, mine, runs in rows:
        cells = [f"{mine['seconds']:.1f} s ({mine['points']} points, {mine['events']} contact "
                 f"events, {mine['plastic']} plastic events)"]
        cells += [f"{runs[rate]['loop']:.1f} s ({runs[rate]['wall']:.1f} s)" for rate in args.rates]
        print(f"| {N} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
