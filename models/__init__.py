"""The geometries, by the scene file's top-level ``geometry``: the chain of disks on a
substrate (chain/, continued in F_x) and 2D frictional packings under Lees-Edwards shear
(packing/, continued in gamma). Every command and study asks this registry for a scene's
model; none asks what kind of scene it holds.

A geometry is one folder models/<geometry>/ with
- ``__init__.py`` defining ``MODEL``, a `Model`: what the studies call for its scenes;
- ``commands.py``, its front: a function per command that takes its scenes (``prepare``,
  ``bifurcate``, ``simulate``, ``verify``, ``report``, ``map``...), called by cli/ with the
  parsed arguments. The front sits on the command line's layer (tests/test_layers.py);
- the problem on the core, its preparation, runs and records, in modules of its own;
and its name in `GEOMETRIES` (and the scene schema's, scenes/rules.py).
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass

GEOMETRIES = {"chain": "diskfriction.models.chain", "packing": "diskfriction.models.packing"}
"""The package of each geometry's model, by the scenes' ``geometry``."""


@dataclass(frozen=True)
class Model:
    """A geometry as the commands and studies see it.

    geometry: its name in scene files; parameter: the continued parameter's name ("F_x",
    "gamma"), as collisions.json and the diagram name it; front: the module of its commands
    (a function per command it takes, named after the command; map's is ``map_plan``).
    """

    geometry: str
    parameter: str
    front: str


def model_for(scene) -> Model:
    """The Model of `scene` (its class's ``geometry``), imported on first use."""
    return importlib.import_module(GEOMETRIES[scene.geometry]).MODEL
