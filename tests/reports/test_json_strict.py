"""Every JSON the tool writes is strict JSON (docs/outputs.md: a value that is not finite is
null): commands that write JSON run on tiny inputs, chains (3 disks) and packings (16 disks),
and every .json under their output directories, and what --json prints, is read by a parser
that refuses NaN and Infinity (tests/reports/test_outputs.py does the same for the chain's simulate,
ensemble, verify and map). diskfriction.files.save_json and json_text are where they all go
through."""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from extras import needs_lammps

from diskfriction.cli.main import main
from diskfriction.files import json_text, save_json

pytestmark = pytest.mark.slow  # whole runs of commands or examples: the slow tier (README, Tests)

REPO = Path(__file__).resolve().parents[2]
CHAIN = 'name = "tiny"\n[disks]\nN = 3\n[load]\nF_x = [0.0, 0.05]\n'
PACKING = ('geometry = "packing"\nname = "p16"\n[packing]\nN = 16\nseed = 1\n'
           '[shear]\ngamma = [0.0, 0.001]\n')


def strict(text: str):
    """json.loads that refuses NaN, Infinity and -Infinity."""
    def refuse(name):
        raise ValueError(f"{name} is not JSON")
    return json.loads(text, parse_constant=refuse)


def nulls(value) -> int:
    """The nulls in a JSON value."""
    if isinstance(value, dict):
        return sum(nulls(v) for v in value.values())
    if isinstance(value, list):
        return sum(nulls(v) for v in value)
    return value is None


def test_save_json_writes_what_is_not_finite_as_null(tmp_path):
    """nan and inf, as Python floats, numpy scalars and inside numpy arrays and tuples, at any
    depth: null; numpy integers and booleans their JSON numbers and booleans."""
    data = {"nan": float("nan"), "inf": np.float32(np.inf), "rows": [{"x": -np.inf}],
            "array": np.array([1.5, np.nan]), "pair": (2, np.nan), "n": np.int64(3),
            "flag": np.bool_(True), "fine": 0.25}
    save_json(tmp_path / "a.json", data)
    assert strict((tmp_path / "a.json").read_text()) == {
        "nan": None, "inf": None, "rows": [{"x": None}], "array": [1.5, None],
        "pair": [2, None], "n": 3, "flag": True, "fine": 0.25}
    assert strict(json_text([np.nan], indent=None)) == [None]


def scenes(tmp_path: Path) -> dict[str, str]:
    (tmp_path / "tiny.toml").write_text(CHAIN, encoding="utf-8")
    (tmp_path / "p16.toml").write_text(PACKING, encoding="utf-8")
    return {"CHAIN": str(tmp_path / "tiny.toml"), "PACKING": str(tmp_path / "p16.toml"),
            "PROBLEM": str(REPO / "examples" / "fitzhugh_nagumo.py")}


COMMANDS = {
    "bifurcate": ["bifurcate", "CHAIN", "--json"],
    "bifurcate-problem": ["bifurcate", "--problem", "PROBLEM", "--json"],
    "prepare-packing": ["prepare", "PACKING"],
    "bifurcate-packing": ["bifurcate", "PACKING", "--json"],
    "simulate-packing-real": ["simulate", "PACKING", "--gamma", "0", "--t-end", "5"],
    "simulate-packing-unmeasured": ["simulate", "PACKING", "--gamma", "0.001", "--t-end", "5",
                                    "--amplitude", "1e-6"],
    "verify-packing": ["verify", "PACKING", "--t-end", "5"],
}
"""The commands that write JSON, on tiny inputs, but those whose every JSON tests/reports/test_outputs.py
already reads strictly (a chain's simulate, ensemble, verify and map) and map on a packing
(half a minute for one cell, its local cluster's start: its files, map.json and cells/*.json,
are written by save_json as a chain's map's are). The packing's simulate and verify include
runs without a growth rate (every eigenvalue real; the start beyond the linear range), whose
rate is null."""
MAY_HOLD_NULL = {"simulate-packing-real", "simulate-packing-unmeasured", "verify-packing"}


@pytest.mark.parametrize("name", COMMANDS)
def test_every_json_a_command_writes_is_strict(tmp_path, capsys, name):
    paths = scenes(tmp_path)
    out = tmp_path / "out"
    argv = [paths.get(word, word) for word in COMMANDS[name]] + ["--out", str(out)]
    assert main(argv) == 0, argv
    printed = capsys.readouterr().out
    written = sorted(out.rglob("*.json"))
    assert written or "--json" in argv, name
    found = [strict(path.read_text(encoding="utf-8")) for path in written]
    if "--json" in argv:
        found.append(strict(printed))
    if name in MAY_HOLD_NULL:
        assert sum(nulls(value) for value in found) > 0  # a rate that is not there is null


@needs_lammps
def test_crosschecks_json_is_strict(tmp_path):
    from diskfriction.scenes import Effects, Scene
    from diskfriction.scenes.load import format_scene

    scene = tmp_path / "linear.toml"
    scene.write_text(format_scene(dataclasses.replace(
        Scene(effects=Effects("mindlin-linear", conventions="lammps")), name="linear")))
    out = tmp_path / "out"
    assert main(["crosscheck", "lammps", str(scene), "--fx", "0.03", "--t-end", "0.2",
                 "--out", str(out)]) == 0
    assert [strict(p.read_text(encoding="utf-8")) for p in out.rglob("*.json")]
