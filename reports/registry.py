"""What a report is made of: computations (cached physics) and sections (figures, tables).

A Computation is a function (scene, **params) -> dict of numpy arrays and JSON values, with the
modules its result depends on. A Section (one figure or table) declares the computations it
needs for a scene as a list of Needs, and renders Markdown from their results; it never computes
physics itself. The builder (reports/builder.py) computes each distinct Need once, from the
cache when the key (reports/cache.py) matches.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable

from diskfriction.files import source_digest
from diskfriction.scenes import Scene

SWEEP_DEPS = ("diskfriction", "diskfriction.scenes", "diskfriction.symbolic",
              "diskfriction.continuation", "diskfriction.dynamics", "diskfriction.models")
DYNAMICS_DEPS = SWEEP_DEPS + ("diskfriction.studies",)
"""The folders a computation's result depends on (tests/test_layers.py checks them against the
imports): a folder left out would let a cached result outlive an edit there."""


class ComputationFailed(Exception):
    """A computation that ran but has no result for a reason the report shows (no
    equilibrium, a module missing, ...); cached like a result when `cache` is True."""

    def __init__(self, message: str, cache: bool = True) -> None:
        super().__init__(message)
        self.cache = cache


@dataclass(frozen=True, eq=False)
class Computation:
    """name: unique, used in cache keys and paths; function(scene, **params) -> dict;
    depends: modules (packages or single modules) whose sources enter the code version,
    besides the computations' own package (reports/compute/: they call one another) and the
    registry and cache."""

    name: str
    function: Callable[..., dict]
    depends: tuple[str, ...]

    @cached_property
    def code(self) -> str:
        return source_digest(("diskfriction.reports.compute", "diskfriction.reports.registry",
                              "diskfriction.reports.cache") + self.depends)


def computation(name: str, depends: tuple[str, ...] = SWEEP_DEPS):
    """Decorator marking `function` as the computation `name` (its `computation` attribute);
    the report's table of them is built from the modules that define them (collect), not by
    the side effect of importing them."""

    def mark(function: Callable[..., dict]) -> Callable[..., dict]:
        function.computation = Computation(name, function, tuple(depends))
        return function

    return mark


def collect(*modules) -> dict[str, Computation]:
    """{name: Computation} of the functions the modules mark (computation); ValueError for a
    name marked twice."""
    found: dict[str, Computation] = {}
    for module in modules:
        for value in vars(module).values():
            each = getattr(value, "computation", None)
            if isinstance(each, Computation) and each.function is value:
                if each.name in found:
                    raise ValueError(f"computation {each.name!r} defined twice")
                found[each.name] = each
    return found


@dataclass(frozen=True)
class Need:
    """One computation a section needs: label (unique within the section, shown in progress
    lines), the registered computation, the scene it runs on and its parameters (JSON values)."""

    label: str
    computation: str
    scene: Scene
    params: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Section:
    """key: what --only names (fig2, paper, ...); title: the report heading;
    needs(scene, settings) -> [Need]; render(ctx) -> Markdown (reports/builder.SectionContext).
    unavailable() -> None, or the line the report prints instead (a module that is missing)."""

    key: str
    title: str
    needs: Callable
    render: Callable
    unavailable: Callable[[], str | None] = lambda: None
