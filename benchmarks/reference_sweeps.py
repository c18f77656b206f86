"""The reference sweeps a restructuring must leave unchanged: run, save, compare.

Run: python benchmarks/reference_sweeps.py --save FILE   (before a change)
     python benchmarks/reference_sweeps.py --compare FILE (after it)
Each case is the installed `diskfriction bifurcate` as a user runs it (so that moving modules
does not move the harness), with scans inline (--workers 0: bit-for-bit reproducible): nine
sweeps of chains, two problems of the gallery and two packing shears (32 disks with every
eigenvalue through 3 plastic events; 64 disks with a spectral window). Saved per case: every
collision (p, kind, lambda) and the branch's parameter (F_x, gamma or p), n_complex and
eigenvalue arrays. --compare prints, per case, whether the counts are equal and the largest differences of
the collision locations and of the eigenvalues relative to max|lambda| (by label, and as each
point's set: which real eigenvalue continues which label after a collision may rest on
rounding), then a verdict: bit for bit, within 1e-12 (as sets: the labels that differ are
counted), or changed (exit 1).
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.optimize import linear_sum_assignment

ROOT = Path(__file__).resolve().parents[1]
COMMAND = Path(sys.executable).with_name("diskfriction")
TOLERANCE = 1e-12
SCENES = {"N20-eps1e-4": "[disks]\nN = 20\neps = 1e-4\n",
          "N100": "[disks]\nN = 100\n",
          "N100-eps1e-4": "[disks]\nN = 100\neps = 1e-4\n",
          "packing-32": 'geometry = "packing"\n[packing]\nN = 32\n[shear]\ngamma = [0.0, 0.01]\n',
          "packing-64": 'geometry = "packing"\n[packing]\nN = 64\nseed = 2\n[shear]\ngamma = [0.0, 0.004]\n'}
CASES = {
    "paper J": ["scenes/paper.toml"],
    "paper M^-1J": ["scenes/paper.toml", "--matrix", "M^-1J"],
    "paper unloading 0.06:0.03": ["scenes/paper.toml", "--fx", "0.06:0.03"],
    "paper window 0.05:0.08": ["scenes/paper.toml", "--window", "0.05:0.08"],
    "paper exhaustive": ["scenes/paper.toml", "--detection", "exhaustive"],
    "N = 20, eps = 1e-4": ["@N20-eps1e-4"],
    "N = 20, eps = 1e-4, window 0.05:0.08": ["@N20-eps1e-4", "--window", "0.05:0.08"],
    "N = 100, eps = 0": ["@N100"],
    "N = 100, eps = 1e-4": ["@N100-eps1e-4"],
    "Ziegler": ["--problem", "examples/ziegler.py"],
    "Beck": ["--problem", "examples/beck.py"],
    "packing 32 to gamma 0.01": ["@packing-32"],
    "packing 64 to gamma 0.004, window -3:8": ["@packing-64", "--window=-3:8"],
}


def run_case(args: list[str], scenes: Path, out: Path) -> dict:
    """One bifurcate run; its collisions and branch arrays as plain lists."""
    argv = [str(scenes / f"{a[1:]}.toml") if a.startswith("@") else a for a in args]
    workers = [] if "--problem" in argv else ["--workers", "0"]
    subprocess.run([str(COMMAND), "bifurcate", *argv, *workers, "--out", str(out)], cwd=ROOT,
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    found = json.loads((out / "collisions.json").read_text())  # continuation/records.py
    with np.load(out / "branch.npz") as branch:
        p, lam = branch[str(branch["parameter"])], branch["eigenvalues"]  # F_x, or a problem's own
        # [p, kind, lambda, Im lambda]: a collision's double eigenvalue is real
        collisions = [[c["p"], c["kind"], c["lambda"], 0.0] for c in found["collisions"]]
        return {"collisions": collisions, "p": p.tolist(), "n_complex": branch["n_complex"].tolist(),
                "re": np.nan_to_num(lam.real, nan=0.0).tolist(), "im": np.nan_to_num(lam.imag, nan=0.0).tolist()}


def compare(old: dict, new: dict) -> tuple[str, bool]:
    """One line for a case, and whether it is within TOLERANCE."""
    if len(old["collisions"]) != len(new["collisions"]) or old["n_complex"] != new["n_complex"] \
            or len(old["p"]) != len(new["p"]):
        return (f"counts differ: {len(old['collisions'])} -> {len(new['collisions'])} collisions, "
                f"{len(old['p'])} -> {len(new['p'])} points"), False
    kinds = [c[1] for c in old["collisions"]] == [c[1] for c in new["collisions"]]
    dp = max((abs(a[0] - b[0]) for a, b in zip(old["collisions"], new["collisions"])), default=0.0)
    lam_old = np.array(old["re"]) + 1j * np.array(old["im"])
    lam_new = np.array(new["re"]) + 1j * np.array(new["im"])
    scale = max(np.abs(lam_old).max(), 1e-300)
    dlam = float(np.abs(lam_new - lam_old).max() / scale) if lam_old.shape == lam_new.shape else np.inf
    dset = as_sets(lam_old, lam_new) / scale
    dpts = float(np.abs(np.subtract(old["p"], new["p"])).max())
    same = old == new
    ok = kinds and dp <= TOLERANCE and dset <= TOLERANCE and dpts <= TOLERANCE
    moved = relabelled(lam_old, lam_new, scale)
    labels = "" if dlam <= TOLERANCE or not ok else f" (labels differ at {moved} points)"
    verdict = "bit for bit" if same else ("within 1e-12" + labels if ok else "CHANGED")
    return (f"{len(new['collisions'])} collisions, {verdict}: max |d location| {dp:.2g}, "
            f"max |d lambda| / max|lambda| {dlam:.2g} by label, {dset:.2g} as sets, "
            f"max |d point| {dpts:.2g}"), ok


def as_sets(old: np.ndarray, new: np.ndarray) -> float:
    """The largest difference of the points' eigenvalues as sets (the stored ones, not a
    window's empty columns; matched by least total distance, as a conjugate pair's members may
    swap): after a collision, which real eigenvalue continues which label may rest on
    rounding; inf where a point's count differs."""
    if len(old) != len(new):
        return np.inf
    worst = 0.0
    for a, b in zip(old, new):
        a, b = a[a != 0], b[b != 0]
        if a.size != b.size:
            return np.inf
        distance = np.abs(a[:, None] - b[None, :])
        rows, cols = linear_sum_assignment(distance)
        worst = max(worst, float(distance[rows, cols].max(initial=0.0)))
    return worst


def relabelled(old: np.ndarray, new: np.ndarray, scale: float) -> int:
    """How many points hold an eigenvalue under another label."""
    if old.shape != new.shape:
        return len(new)
    return int(np.sum(np.abs(new - old).max(axis=1) > TOLERANCE * scale))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--save", type=Path)
    group.add_argument("--compare", type=Path)
    args = parser.parse_args()
    results, ok = {}, True
    reference = json.loads(args.compare.read_text()) if args.compare else None
    with tempfile.TemporaryDirectory() as tmp:
        scenes = Path(tmp)
        for name, text in SCENES.items():
            (scenes / f"{name}.toml").write_text(text)
        for k, (name, case) in enumerate(CASES.items()):
            t0 = time.perf_counter()
            results[name] = run_case(case, scenes, scenes / f"out{k}")
            line = f"{time.perf_counter() - t0:5.1f} s"
            if reference is not None:
                text, good = compare(reference[name], results[name])
                ok &= good
                line += f"  {text}"
            print(f"{name:40s} {line}", flush=True)
    if args.save:
        args.save.write_text(json.dumps(results))
        print(f"saved {args.save}")
    else:
        print("all within 1e-12" if ok else "CHANGED: see above")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
