"""Build a report: for each scene and section, compute (or load) what it needs, then render.

    log = build_report([scene], Path("out/report"), settings=Settings())

Writes OUT/report.md and the figures OUT/<scene label>/<name>.png. Each distinct computation
(same cache key) runs at most once per build; a progress line per Need says whether it was
computed (and how long it took), loaded from the cache, or failed.
"""
from __future__ import annotations

import inspect
import re
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional

from diskfriction.reports.cache import ResultCache, cache_key, default_cache_dir
from diskfriction.files import save_text
from diskfriction.reports.figures import save_figure
from diskfriction.reports.compute import COMPUTATIONS
from diskfriction.reports.registry import ComputationFailed, Need, Section
from diskfriction.reports.sections import SECTIONS
from diskfriction.reports.settings import Settings
from diskfriction.reports.units import PaperUnits
from diskfriction.scenes import Scene

ERROR = "__error__"


def _echo(text: str, end: str = "\n") -> None:
    print(text, end=end, flush=True)


@dataclass
class LogEntry:
    scene: str
    section: str
    label: str
    computation: str
    key: str
    status: str  # computed | cached | failed
    seconds: float
    message: str = ""


@dataclass
class SectionContext:
    """What a section's render sees: its scene, settings, the results of its Needs by label,
    and where to put figures (`figure` saves one and returns its Markdown)."""

    scene: Scene
    settings: Settings
    results: dict
    errors: dict
    figure_dir: Path
    link_prefix: str
    units: PaperUnits = field(init=False)

    def __post_init__(self):
        self.units = PaperUnits.of(self.scene)

    def get(self, label: str) -> Optional[dict]:
        return self.results.get(label)

    def figure(self, fig, name: str, caption: str) -> str:
        """Save a matplotlib figure as FIGURE_DIR/name.png; the Markdown that shows it."""
        save_figure(fig, self.figure_dir / f"{name}.png")
        return f"![{caption}]({self.link_prefix}{name}.png)\n\n*{caption}*\n"


def sections_named(only: Optional[tuple[str, ...]]) -> list[Section]:
    """The sections in report order, restricted to `only` (keys); ValueError on an unknown key."""
    if not only:
        return list(SECTIONS)
    keys = [s.key for s in SECTIONS]
    unknown = [k for k in only if k not in keys]
    if unknown:
        raise ValueError(f"unknown section {unknown[0]!r}; one of {', '.join(keys)}")
    return [s for s in SECTIONS if s.key in only]


def scene_labels(scenes: list[Scene]) -> list[str]:
    """A distinct, path-safe label per scene (its name; -2, -3 for repeats)."""
    labels, seen = [], {}
    for scene in scenes:
        base = re.sub(r"[^A-Za-z0-9_.-]+", "_", scene.name).strip("._") or "scene"
        seen[base] = seen.get(base, 0) + 1
        labels.append(base if seen[base] == 1 else f"{base}-{seen[base]}")
    return labels


class _Runner:
    """Computes Needs, each distinct key once per build, through the on-disk cache."""

    def __init__(self, cache: ResultCache, echo: Callable[..., None]) -> None:
        self.cache, self.echo = cache, echo
        self.memory: dict[str, dict] = {}
        self.log: list[LogEntry] = []

    def run(self, scene_label: str, section: str, need: Need) -> dict:
        comp = COMPUTATIONS[need.computation]
        key = cache_key(comp.name, need.scene, need.params, comp.code)
        where = f"{scene_label}: " if scene_label else ""
        name = f"{section}/{need.label}"
        t0 = time.perf_counter()
        result = self.memory.get(key)
        status = "cached"
        if result is None:
            result = self.cache.load(comp.name, key)
        if result is None:
            self.echo(f"{where}computing {name} ... ", end="")
            result, cacheable = self._compute(comp, need, key)
            if cacheable:
                self.cache.store(comp.name, key, result)
            status = "computed"
        self.memory[key] = result
        seconds = time.perf_counter() - t0
        failed = result.get(ERROR)
        if failed:
            status = "failed" if status == "computed" else "cached (failed)"
        self.log.append(LogEntry(scene_label, section, need.label, comp.name, key, status,
                                 seconds, failed or ""))
        note = f": {failed}" if failed else ""
        if status.startswith("cached"):
            self.echo(f"{where}{status:9s} {name}{note}")
        else:
            self.echo(f"{seconds:.1f} s" + (f" FAILED{note}" if failed else ""))
        return result

    def _compute(self, comp, need: Need, key: str) -> tuple[dict, bool]:
        """Run it; a function with a `workdir` parameter gets a directory of its own beside
        the cache (not part of the key: it is derived from it). ComputationFailed and
        NoEquilibrium (a load beyond the branch from rest) are physics failures, cached."""
        from diskfriction.models.chain.equilibrium import NoEquilibrium

        params = dict(need.params)
        if "workdir" in inspect.signature(comp.function).parameters:
            params["workdir"] = str(self.cache.directory / "work" / comp.name / key[:16])
        try:
            return comp.function(need.scene, **params), True
        except ComputationFailed as error:
            return {ERROR: str(error)}, error.cache
        except NoEquilibrium as error:
            return {ERROR: str(error)}, True
        except Exception as error:  # a bug: shown in the report, never cached
            last = traceback.extract_tb(error.__traceback__)[-1]
            return {ERROR: f"{type(error).__name__}: {error} ({Path(last.filename).name}:{last.lineno})"}, False


def build_report(scenes: list[Scene], out: Path, only: Optional[tuple[str, ...]] = None,
                 settings: Settings = Settings(), cache_dir: Optional[Path] = None,
                 echo: Callable[..., None] = _echo) -> list[LogEntry]:
    """Compute what the chosen sections need for every scene and write OUT/report.md."""
    out = Path(out)
    sections = sections_named(only)
    runner = _Runner(ResultCache(cache_dir or default_cache_dir(out)), echo)
    labels = scene_labels(scenes)
    parts = []
    for scene, label in zip(scenes, labels):
        shown = label if len(scenes) > 1 else ""
        body = [_scene_header(scene, label, len(scenes) > 1)]
        for section in sections:
            body.append(f"## {section.title}\n")
            missing = section.unavailable()
            if missing:
                body.append(f"Not built: {missing}.\n")
                echo(f"{shown + ': ' if shown else ''}skipped   {section.key}: {missing}")
                continue
            results, errors = {}, {}
            for need in section.needs(scene, settings):
                result = runner.run(shown, section.key, need)
                if ERROR in result:
                    errors[need.label] = result[ERROR]
                else:
                    results[need.label] = result
            ctx = SectionContext(scene, settings, results, errors, out / label, f"{label}/")
            body.append(section.render(ctx))
        parts.append("\n".join(body))
    text = _title(scenes, sections) + "\n".join(parts) + _appendix(runner.log)
    save_text(out / "report.md", text)
    return runner.log


def _title(scenes: list[Scene], sections: list[Section]) -> str:
    return ("# diskfriction report\n\n"
            "Charan, Chattoraj, Pica Ciamarra, Procaccia, PRL 124, 030602 (2020), recomputed from "
            "the model in docs/model.md. Paper units on every axis: lengths in 2R, time in "
            "tau = sqrt(m / (k_n (2R)^(1/2))), velocities in 2R/tau, eigenvalues of J in "
            "k_n (2R)^(1/2) and of M^-1 J in 1/tau^2 (both lambda / k_n for the paper's scene), "
            "F_x in raw force units as the paper quotes it. How the report is built and what "
            "each part shows: docs/report.md.\n\n"
            f"Sections: {', '.join(s.key for s in sections)}. "
            f"Scenes: {', '.join(s.name for s in scenes)}.\n\n")


def _scene_header(scene: Scene, label: str, several: bool) -> str:
    e = scene.resolved_effects
    head = f"# Scene {scene.name}\n\n" if several else ""
    return (head + f"Scene `{scene.name}` ({Path(scene.source).name}): N = {scene.N}, R = {scene.R:g}, "
            f"m = {scene.m:g}, c = {scene.inertia:g} (I = c m R^2), eps = {scene.eps:g}, "
            f"k_n = {scene.k_n:g}, k_t = {scene.k_t:.6g}, mu = {scene.mu:g}, F_y = {scene.F_y:g}, "
            f"F_x = {scene.F_x_range[0]:g}..{scene.F_x_range[1]:g}; tangential law "
            f"{e.tangential}, pair friction {e.pair_friction}, substrate friction "
            f"{e.wall_friction}, rotation {e.rotation}, conventions {e.conventions}. "
            f"tau = {scene.tau:.5g} raw time units.\n")


def _appendix(log: list[LogEntry]) -> str:
    rows = ["\n## Computations of this build\n",
            "Each is cached under its key (sha256 of scene, parameters and code version; "
            "docs/report.md).\n",
            "| scene | section/need | computation | key | status | s |", "|---|---|---|---|---|---|"]
    for e in log:
        rows.append(f"| {e.scene or '-'} | {e.section}/{e.label} | {e.computation} | "
                    f"`{e.key[:12]}` | {e.status} | {e.seconds:.2f} |")
    return "\n".join(rows) + "\n"
