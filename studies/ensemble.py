"""Ensembles of runs on dask.distributed: realizations x loads, resumable, front speeds.

Layout of an ensemble directory (raw units everywhere):
    runs/F_x=<F>/r<k>-<key>.json   one summary per finished realization (dynamics.simulate's
                                   summarize), written atomically the moment it arrives;
    ensemble.json                  its parameters (scene, t_end, amplitude, perturbation kind,
                                   loads, seeds, code version) and the aggregates below.
A realization's key hashes everything it depends on (scene, F_x, seed, t_end, perturbation,
code version), so a rerun of the same command skips what is on disk, and an interrupt loses
nothing already finished. More realizations, other loads or seeds extend a directory (the
aggregates then cover what the last run asked for). Another scene, t_end, amplitude,
perturbation kind or code version is refused (EnsembleMismatch): the runs on disk would not be
comparable, and ensemble.json would silently describe other runs.

Realizations differ in the seed of a random-velocity perturbation of the same equilibrium
(the branch point at F_x, reached from rest). Front speeds (paper eq. 9 and Fig. 5):
    V1: forward front of first Coulomb breaches at the substrate: per realization the slope of
        x(tau) against tau over the disks that breached (x the disk's position at its breach);
    V2: backward front of sliding onsets: per realization |slope| of x* against tau*.
Each is averaged over realizations (and for V2 over all loads, as in the paper), with the
standard error of the mean. V_cm(F_x): mean centre-of-mass velocity of the realizations that
slid, fitted by V = a + b F_x (least squares, standard errors from the fit covariance).
Only accurate realizations (summary["accurate"]: the energy budget closes, dynamics/trajectory.py)
enter the aggregates; the others are kept on disk and counted apart.
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from diskfriction.studies.cluster import as_finished, code_version, dask_client, task_key
from diskfriction.errors import OneLineError
from diskfriction.files import save_json
from diskfriction.scenes import Scene

MIN_FRONT_POINTS = 3
MUST_MATCH = ("scene", "t_end", "amplitude", "kind", "code")
"""Parameters an ensemble directory is bound to (module docstring)."""


class EnsembleMismatch(OneLineError):
    """The output directory holds an ensemble with other run parameters; str() is one line."""

    exit_code = 2


@dataclass(frozen=True)
class RunSpec:
    """What one realization needs besides the equilibrium: t_end [time], perturbation
    (kind, amplitude, seed)."""

    t_end: float
    amplitude: float = 1e-6
    kind: str = "random-velocity"
    seed: int = 0


@dataclass(frozen=True)
class Estimate:
    value: float
    error: float
    n: int

    def as_dict(self) -> dict:
        """JSON-ready: a missing value or error (nan) is None."""
        clean = lambda v: v if np.isfinite(v) else None
        return {"value": clean(self.value), "error": clean(self.error), "n": self.n}


@dataclass(frozen=True)
class Ensemble:
    """summaries: F_x -> summaries of the finished realizations; V1 per F_x; V2 pooled;
    V_cm per F_x; V_cm_fit: (intercept, slope) Estimates of V_cm = a + b F_x (None if < 2 loads)."""

    summaries: dict
    V1: dict
    V2: Estimate
    V_cm: dict
    V_cm_fit: Optional[tuple[Estimate, Estimate]]

    def as_dict(self) -> dict:
        fit = None if self.V_cm_fit is None else {"intercept": self.V_cm_fit[0].as_dict(),
                                                  "slope": self.V_cm_fit[1].as_dict()}
        return {"V1": {str(F): e.as_dict() for F, e in self.V1.items()},
                "V2": self.V2.as_dict(),
                "V_cm": {str(F): e.as_dict() for F, e in self.V_cm.items()},
                "V_cm_fit": fit,
                "realizations": {str(F): len(s) for F, s in self.summaries.items()}}


# ---- aggregation (pure) ---------------------------------------------------------------------

def front_slope(t, x) -> Optional[float]:
    """Least-squares slope dx/dt over the finite (t, x) pairs; None if fewer than 3."""
    t, x = np.asarray(t, dtype=float), np.asarray(x, dtype=float)
    ok = np.isfinite(t) & np.isfinite(x)
    if ok.sum() < MIN_FRONT_POINTS or np.ptp(t[ok]) == 0:
        return None
    return float(np.polyfit(t[ok], x[ok], 1)[0])


def mean_estimate(values) -> Estimate:
    """Mean and standard error of the mean (nan error for a single value)."""
    v = np.array([x for x in values if x is not None and np.isfinite(x)], dtype=float)
    if v.size == 0:
        return Estimate(float("nan"), float("nan"), 0)
    err = float(v.std(ddof=1) / np.sqrt(v.size)) if v.size > 1 else float("nan")
    return Estimate(float(v.mean()), err, int(v.size))


def _times(points: dict) -> list:
    return [np.nan if t is None else t for t in points["t"]]


def _positions(points: dict) -> list:
    return [np.nan if x is None else x for x in points["x"]]


def breach_speed(summary: dict) -> Optional[float]:
    """V1 of one realization: slope of the breach positions against the breach times."""
    return front_slope(_times(summary["first_breach"]), _positions(summary["first_breach"]))


def sliding_speed(summary: dict) -> Optional[float]:
    """V2 of one realization: |slope| of the sliding-onset positions against onset times."""
    slope = front_slope(_times(summary["onset"]), _positions(summary["onset"]))
    return None if slope is None else abs(slope)


def aggregate(summaries: dict) -> Ensemble:
    """Front speeds and centre-of-mass velocities of the finished accurate realizations (see
    module doc)."""
    loads = sorted(summaries)
    kept = {F: [s for s in summaries[F] if s["accurate"]] for F in loads}
    V1 = {F: mean_estimate(breach_speed(s) for s in kept[F]) for F in loads}
    V2 = mean_estimate(sliding_speed(s) for F in loads for s in kept[F])
    V_cm = {F: mean_estimate(s["V_cm"] for s in kept[F] if s["slid"]) for F in loads}
    usable = [F for F in loads if V_cm[F].n > 0]
    fit = None
    if len(usable) >= 2:
        F = np.array(usable)
        V = np.array([V_cm[f].value for f in usable])
        if len(usable) >= 3:
            (b, a), cov = np.polyfit(F, V, 1, cov=True)
            eb, ea = np.sqrt(np.diag(cov))
        else:
            (b, a), eb, ea = np.polyfit(F, V, 1), float("nan"), float("nan")
        fit = (Estimate(float(a), float(ea), len(usable)), Estimate(float(b), float(eb), len(usable)))
    return Ensemble(summaries, V1, V2, V_cm, fit)


# ---- running -------------------------------------------------------------------------------

def realization_key(scene: Scene, F_x: float, spec: RunSpec, version: str) -> str:
    return task_key(asdict(replace(scene, source="")), F_x, asdict(spec), version)


def run_path(out: Path, F_x: float, index: int, key: str) -> Path:
    return Path(out) / "runs" / f"F_x={F_x!r}" / f"r{index:03d}-{key}.json"


def parameters(scene: Scene, loads: list[float], realizations: int, spec: RunSpec,
               version: str) -> dict:
    """What ensemble.json records about the runs it aggregates (JSON values, raw units)."""
    return {"scene": scene.physics_fields(), "t_end": spec.t_end, "amplitude": spec.amplitude,
            "kind": spec.kind, "loads": [float(F) for F in loads], "realizations": realizations,
            "seeds": [spec.seed, spec.seed + realizations - 1], "code": version}


def check_directory(out: Path, wanted: dict) -> None:
    """Raise EnsembleMismatch if OUT/ensemble.json records other MUST_MATCH parameters."""
    path = Path(out) / "ensemble.json"
    if not path.exists():
        return
    try:
        recorded = json.loads(path.read_text()).get("parameters")
    except (OSError, ValueError, AttributeError):
        recorded = None
    if not isinstance(recorded, dict):
        raise EnsembleMismatch(f"{path} records no run parameters (not an ensemble of this "
                               f"version); choose another output directory or remove it")
    for key in MUST_MATCH:
        if recorded.get(key) != wanted[key]:
            shown = lambda v: json.dumps(v) if key != "scene" else "another scene"
            raise EnsembleMismatch(f"{path} holds an ensemble with {key} = {shown(recorded.get(key))}"
                                   f" (this run: {shown(wanted[key])}); choose another output "
                                   f"directory or remove it")


def run_realization(scene: Scene, F_x: float, q, xi, spec: RunSpec) -> dict:
    """One realization (runs in a dask worker): simulate and summarize."""
    from diskfriction.dynamics.simulate import simulate, summarize
    from diskfriction.dynamics.start import Perturbation
    from diskfriction.symbolic import System

    traj = simulate(System.from_scene(scene), q, xi, F_x, spec.t_end,
                    perturbation=Perturbation(spec.kind, spec.amplitude, spec.seed))
    return summarize(traj)


def run_ensemble(scene: Scene, F_values, realizations: int, t_end: float, out: Path,
                 seed: int = 0, amplitude: float = 1e-6, kind: str = "random-velocity",
                 scheduler: Optional[str] = None,
                 progress: Optional[Callable[[int, int], None]] = None) -> Ensemble:
    """Run `realizations` seeded realizations at every F_x (seeds seed, seed + 1, ...), on the
    dask scheduler at `scheduler` or on a LocalCluster of this machine's cores, skipping those
    already on disk. progress(done, total) after every finished realization."""
    out, version = Path(out), code_version()
    loads = [float(F) for F in F_values]
    if len(set(loads)) != len(loads):
        raise ValueError(f"duplicate loads in {loads}")
    record = parameters(scene, loads, realizations, RunSpec(t_end, amplitude, kind, seed), version)
    check_directory(out, json.loads(json.dumps(record)))
    todo, summaries = pending(scene, loads, realizations, RunSpec(t_end, amplitude, kind, seed), out)
    total, done = len(todo) + sum(map(len, summaries.values())), sum(map(len, summaries.values()))
    if progress is not None:
        progress(done, total)
    if todo:
        _run_tasks(scene, todo, summaries, scheduler,
                   lambda: progress(done_count(summaries), total) if progress else None)
    for runs in summaries.values():  # completion order must not change a single bit
        runs.sort(key=lambda summary: summary["perturbation"]["seed"])
    ensemble = aggregate(summaries)
    save_json(out / "ensemble.json", {"parameters": record, **ensemble.as_dict()})
    return ensemble


def pending(scene: Scene, loads: list[float], realizations: int, first: RunSpec,
            out: Path) -> tuple[list, dict]:
    """(the realizations not on disk in `out`: (F_x, RunSpec, path) each, the summaries of those
    that are, by load); the seeds are first.seed, first.seed + 1, ..."""
    version, todo, summaries = code_version(), [], {F: [] for F in loads}
    for F in summaries:
        for k in range(realizations):
            spec = replace(first, seed=first.seed + k)
            path = run_path(Path(out), F, k, realization_key(scene, F, spec, version))
            if path.exists():
                summaries[F].append(json.loads(path.read_text()))
            else:
                todo.append((F, spec, path))
    return todo, summaries


def done_count(summaries: dict) -> int:
    return sum(map(len, summaries.values()))


def _run_tasks(scene, todo, summaries, scheduler, tick) -> None:
    """Connect (a scheduler that cannot be reached fails before any sweep), get the equilibrium
    at every load of `todo`, submit the missing realizations, and write each one the moment it
    finishes (studies/cluster.py)."""
    from diskfriction.models.chain.equilibrium import equilibrium_at
    from diskfriction.symbolic import System

    with dask_client(scheduler) as client:
        system = System.from_scene(scene)
        states = {F: equilibrium_at(system, F) for F in dict.fromkeys(F for F, _, _ in todo)}
        tasks = {(F, path): (scene, F, states[F].q, states[F].xi, spec) for F, spec, path in todo}
        for (F, path), summary in as_finished(client, run_realization, tasks):
            save_json(path, summary)
            summaries[F].append(summary)
            tick()
