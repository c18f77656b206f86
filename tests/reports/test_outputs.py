"""docs/outputs.md lists exactly the keys each output file has: every file is produced here
with a tiny scene (N = 3, short runs) and its keys compared with the page's tables."""
from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

from diskfriction.cli.main import main

pytestmark = pytest.mark.slow  # whole runs of commands or examples: the slow tier (README, Tests)

REPO = Path(__file__).resolve().parents[2]
TINY = 'name = "tiny"\n[disks]\nN = 3\n[load]\nF_x = [0.0, 0.05]\n'
OPAQUE = {"scene"}
"""Objects not descended into: a scene's physics fields are the scene schema's (docs/chain.md,
Scenes)."""


def documented() -> dict[str, tuple[set[str], set[str]]]:
    """Section heading of docs/outputs.md -> (keys, optional keys) of its table: the first
    cell's backticked name; optional where the meaning says 'only when'."""
    sections, heading = {}, None
    for line in (REPO / "docs" / "outputs.md").read_text(encoding="utf-8").splitlines():
        if line.startswith("## "):
            heading = line[3:].strip()
            sections[heading] = (set(), set())
        elif heading and (match := re.match(r"\| `([^`]+)` \|", line)):
            sections[heading][1 if "only when" in line else 0].add(match.group(1))
    return sections


DYNAMIC = {"V1": "<F_x>", "V_cm": "<F_x>", "realizations": "<F_x>", "status": "<status>"}
"""Objects keyed by data (a load, a status), with the placeholder the page writes for a key."""


def placeholder(key: str, parent: str, parameter: str) -> str:
    """A key as the page writes it: a load as <F_x>, a cell status as <status>, the problem's
    parameter as <parameter> (in a labelled point's key too: fold_<parameter>)."""
    if key == parameter:
        return "<parameter>"
    if parameter and key.endswith("_" + parameter):
        return key[:-len(parameter)] + "<parameter>"
    return DYNAMIC.get(parent, key)


def paths(value, prefix: str = "", parameter: str = "") -> set[str]:
    """Every key path of a JSON value: 'a', 'a.b' for objects, 'a[].b' for arrays of objects."""
    found = set()
    if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
        for item in value:
            found |= paths(item, prefix + "[]" if prefix else "", parameter)
    elif isinstance(value, dict):
        for key, item in value.items():
            name = placeholder(key, prefix, parameter)
            path = f"{prefix}.{name}" if prefix else name
            found.add(path)
            if path.rpartition(".")[2] not in OPAQUE:
                found |= paths(item, path, parameter)
    return found


@pytest.fixture(scope="module")
def outputs(tmp_path_factory) -> Path:
    """A folder with every command's outputs for the tiny scene."""
    root = tmp_path_factory.mktemp("outputs")
    scene = root / "tiny.toml"
    scene.write_text(TINY, encoding="utf-8")
    runs = [
        ["bifurcate", str(scene), "--out", str(root / "bifurcate")],
        ["bifurcate", "--problem", str(REPO / "examples" / "fitzhugh_nagumo.py"),
         "--out", str(root / "problem")],
        ["simulate", str(scene), "--fx", "0.03", "--t-end", "5", "--out", str(root / "simulate")],
        ["simulate", str(scene), "--fx", "0.03,0.04", "--realizations", "1", "--t-end", "5",
         "--out", str(root / "ensemble")],
        ["verify", str(scene), "--t-end", "5", "--out", str(root / "verify")],
        ["map", str(scene), "--vary", "contacts.mu=5:10:2", "--workers", "1",
         "--out", str(root / "map")],
    ]
    for argv in runs:
        assert main(argv) == 0, argv
    return root


def assert_documented(section: str, actual: set[str]) -> None:
    keys, optional = documented()[section]
    assert actual - keys - optional == set(), f"{section}: keys the page does not list"
    assert keys - actual == set(), f"{section}: keys the page lists that the file lacks"


@pytest.mark.parametrize(("section", "file", "parameter"), [
    ("branch.npz (bifurcate)", "bifurcate/branch.npz", ""),
    ("branch.npz (bifurcate --problem)", "problem/branch.npz", "I"),
    ("trajectory.npz (simulate)", "simulate/trajectory.npz", ""),
])
def test_npz_keys_are_documented(outputs, section, file, parameter):
    with np.load(outputs / file, allow_pickle=False) as arrays:
        assert_documented(section, {placeholder(k, "", parameter) for k in arrays.files})


@pytest.mark.parametrize(("section", "file", "parameter"), [
    ("collisions.json (bifurcate)", "bifurcate/collisions.json", ""),
    ("collisions.json (bifurcate --problem)", "problem/collisions.json", "I"),
    ("special_points.json (bifurcate --problem)", "problem/special_points.json", "I"),
    ("summary.json (simulate)", "simulate/summary.json", ""),
    ("ensemble.json (simulate with several loads or --realizations)", "ensemble/ensemble.json", ""),
    ("verify.json (verify)", "verify/verify.json", ""),
    ("map.json (map)", "map/map.json", ""),
])
def test_json_keys_are_documented(outputs, section, file, parameter):
    value = json.loads((outputs / file).read_text(encoding="utf-8"))
    assert value, f"{file} is empty: nothing to compare"
    assert_documented(section, paths(value, parameter=parameter))


def test_every_json_file_is_strict_json(outputs):
    """No NaN or Infinity in any JSON file written (docs/outputs.md: null instead)."""
    from test_json_strict import strict

    written = sorted(outputs.rglob("*.json"))
    assert {p.parent.name for p in written} >= {"bifurcate", "simulate", "ensemble", "verify",
                                                "map", "cells"}
    for path in written:
        strict(path.read_text(encoding="utf-8"))


PACKING = ('geometry = "packing"\nname = "tiny-packing"\n[packing]\nN = 16\nseed = 3\n'
           "[shear]\ngamma = [0.0, 0.002]\n")


@pytest.fixture(scope="module")
def packing_outputs(tmp_path_factory) -> Path:
    """A folder with the packing commands' outputs for a 16-disk packing sheared to 0.002 (one
    plastic event, complex pairs)."""
    root = tmp_path_factory.mktemp("packing_outputs")
    scene = root / "tiny.toml"
    scene.write_text(PACKING, encoding="utf-8")
    for argv in (["prepare", str(scene), "--out", str(root / "prepare")],
                 ["bifurcate", str(scene), "--out", str(root / "bifurcate")],
                 ["simulate", str(scene), "--gamma", "0.001", "--t-end", "20",
                  "--out", str(root / "simulate")],
                 ["verify", str(scene), "--t-end", "5", "--out", str(root / "verify")]):
        assert main(argv) == 0, argv
    return root


@pytest.mark.parametrize(("section", "file"), [
    ("branch.npz (bifurcate PACKING_SCENE)", "bifurcate/branch.npz"),
    ("packing.npz (prepare, bifurcate PACKING_SCENE)", "bifurcate/packing.npz"),
    ("packing.npz (prepare, bifurcate PACKING_SCENE)", "prepare/packing.npz"),
    ("run.npz (simulate PACKING_SCENE)", "simulate/run.npz"),
])
def test_packing_npz_keys_are_documented(packing_outputs, section, file):
    with np.load(packing_outputs / file, allow_pickle=False) as arrays:
        assert_documented(section, set(arrays.files))
        assert str(arrays["scene"]) == "tiny-packing" and int(arrays["N"]) == 16


@pytest.mark.parametrize(("section", "file", "items"), [
    ("packing.json (prepare)", "prepare/packing.json", None),
    ("summary.json (simulate PACKING_SCENE)", "simulate/summary.json", None),
    ("collisions.json (bifurcate PACKING_SCENE)", "bifurcate/collisions.json", "collisions"),
    ("plastic.json (bifurcate PACKING_SCENE)", "bifurcate/plastic.json", "events"),
    ("verify.json (verify PACKING_SCENE)", "verify/verify.json", "runs"),
])
def test_packing_json_keys_and_scene_record_are_documented(packing_outputs, section, file, items):
    """Each file's keys (of each object of its array `items`, where the page's table lists
    those) as the page lists them, and its scene record's keys as 'The scene record' lists."""
    from test_json_strict import strict

    value = strict((packing_outputs / file).read_text(encoding="utf-8"))
    listed = value if items is None else value[items]
    assert listed, f"{file}: nothing to compare"
    assert_documented(section, paths(listed))
    record = value["scene"]
    assert_documented("The scene record (every packing output)", set(record))
    assert record["name"] == "tiny-packing" and record["physics"]["N"] == 16


def test_ensemble_runs_are_summaries(outputs):
    run = next((outputs / "ensemble" / "runs").rglob("*.json"))
    assert_documented("summary.json (simulate)", paths(json.loads(run.read_text())))


def test_map_csv_columns_are_documented(outputs):
    with open(outputs / "map" / "map.csv", newline="") as fh:
        header = next(csv.reader(fh))
    assert header[0] == "contacts.mu"
    assert_documented("map.csv (map)", {"<key>"} | set(header[1:]))


def test_verify_table_columns_are_documented(outputs):
    text = (outputs / "verify" / "verify.md").read_text(encoding="utf-8")
    header = next(line for line in text.splitlines() if line.startswith("| window"))
    assert_documented("verify.md (verify)", {c.strip() for c in header.strip("|").split("|")})
