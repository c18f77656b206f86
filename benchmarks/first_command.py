"""The README's first command as a newcomer runs it: `diskfriction bifurcate scenes/paper.toml`.

Run: python benchmarks/first_command.py [--repeat 3]. For each repeat a fresh, empty kernel
cache (a temporary $DISKFRICTION_CACHE) makes the cold run (kernel generation and numba
compilation included), and a second run on the same cache the warm one. Each run is the
installed `diskfriction` command in a new process, timed from start to exit; its stderr is a
pipe, so the command prints one line per stage, and the time between those lines splits the
run into start-up (interpreter and imports, until the first stage), kernels, sweep, writing
and plotting (the diagram, the printed summary and the interpreter's exit). Prints medians over
the repeats, measured in this run, of the wall time, of the command's CPU time (user + system:
on a machine others share it moves less than the wall time) and of each stage's wall time.
"""
from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COMMAND = Path(sys.executable).with_name("diskfriction")


def stage_name(line: str) -> str:
    """'bifurcate: kernels: compiling' -> 'kernels: compiling'; 'sweep F_x 0 -> 0.12' -> 'sweep'."""
    stage = line.split(": ", 1)[1].strip()
    return stage if stage.startswith("kernels") else stage.split()[0]


def child_cpu() -> float:
    """CPU seconds (user + system) of this process's children that have ended."""
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    return used.ru_utime + used.ru_stime


def timed_run(cache: str, out: str) -> tuple[float, float, dict[str, float]]:
    """(wall seconds, CPU seconds, wall seconds per stage) of one `diskfriction bifurcate` run."""
    env = {**os.environ, "DISKFRICTION_CACHE": cache}
    cpu = child_cpu()
    t0 = time.perf_counter()
    proc = subprocess.Popen([str(COMMAND), "bifurcate", str(ROOT / "scenes" / "paper.toml"),
                             "--out", out], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, env=env)
    stages, current, since = {}, "start-up", t0
    for line in proc.stderr:
        now = time.perf_counter()
        stages[current] = stages.get(current, 0.0) + now - since
        current, since = stage_name(line), now
    if proc.wait() != 0:
        raise SystemExit(f"diskfriction bifurcate failed (exit {proc.returncode})")
    end = time.perf_counter()
    stages[current] = stages.get(current, 0.0) + end - since
    return end - t0, child_cpu() - cpu, stages


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    if not COMMAND.exists():
        raise SystemExit(f"no {COMMAND}: install diskfriction into this environment first")
    runs = {"cold": [], "warm": []}
    for _ in range(args.repeat):
        with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as out:
            for kind in ("cold", "warm"):
                runs[kind].append(timed_run(cache, out))
    print(f"diskfriction bifurcate scenes/paper.toml: medians of {args.repeat} repeats "
          f"({os.cpu_count()} cores)")
    for kind, results in runs.items():
        wall = statistics.median(t for t, _, _ in results)
        cpu = statistics.median(c for _, c, _ in results)
        names = list(dict.fromkeys(name for _, _, stages in results for name in stages))
        parts = ", ".join(f"{name} {statistics.median(s.get(name, 0.0) for _, _, s in results):.2f}"
                          for name in names)
        print(f"  {kind}: {wall:.2f} s, CPU {cpu:.2f} s  ({parts})")


if __name__ == "__main__":
    main()
