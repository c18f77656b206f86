"""Scene files: load and validate a TOML scene, write a resolved scene back as TOML.

A scene file has a top-level ``name``, an optional top-level ``geometry`` ("chain", the default,
or "packing") and the tables of its geometry's schema: for a chain [disks], [contacts], [load],
[effects], [stability] (schema and units: scenes/paper.toml); for a packing [packing], [disks],
[contacts], [shear], [effects], [stability] (PACKING_SCHEMA, scenes/packing.toml). Every key is
optional; a missing key takes the Scene() or PackingScene() default. Files are parsed with
tomllib only: nothing in a file is ever evaluated as code. Every problem raises one SceneError
whose str() is a single line naming the file and dotted key.
"""
from __future__ import annotations

import os
import tomllib
from dataclasses import replace
from importlib import resources
from pathlib import Path
from typing import Any, Callable, Iterator

from diskfriction.scenes.packing import PackingScene
from diskfriction.scenes.rules import GEOMETRIES, Invalid, expect, kind
from diskfriction.scenes.schema import (EFFECT_FIELDS, FIELDS, FRICTION_SWITCHES, KEYS,
                                        PACKING_EFFECTS, PACKING_FIELDS, PACKING_KEYS,
                                        PACKING_SCHEMA, SCHEMA, SCHEMAS, tables)
from diskfriction.scenes.scene import Effects, Scene, SceneValueError

FILE_KEY = "<file>"
COMMENT_COLUMN = 36


class SceneError(Exception):
    """One problem with a scene file: ``scene error: FILE: KEY: what is wrong (got VALUE)``.

    ``key`` is the dotted key (``disks.N``, ``load.F_x``) or ``<file>`` for whole-file problems.
    """

    def __init__(self, file: str, key: str, what: str, value: Any) -> None:
        self.file, self.key, self.what, self.value = file, key, what, value
        shown = file if file.isprintable() else repr(file)[1:-1]  # one line, whatever the path
        super().__init__(f"scene error: {shown}: {key}: {what} (got {_show(value)})")


# ---------------------------------------------------------------- writing values as TOML


def _toml_string(text: str) -> str:
    """A TOML basic string: quotes, backslashes and control characters escaped."""

    def escape(char: str) -> str:
        if char in '"\\':
            return "\\" + char
        if ord(char) < 0x20 or ord(char) == 0x7F:
            return f"\\u{ord(char):04x}"
        return char

    return '"' + "".join(map(escape, text)) + '"'


def _toml(value: Any, quote: Callable[[str], str] = _toml_string) -> str:
    """A parsed TOML value written back in TOML syntax, strings through ``quote``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return quote(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(item, quote) for item in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{key} = {_toml(item, quote)}" for key, item in value.items()) + "}"
    if isinstance(value, (int, float)):
        return repr(value)
    return value.isoformat()  # TOML dates and times


def _show(value: Any) -> str:
    """A value as an error message shows it: TOML syntax, strings via repr."""
    return _toml(value, quote=repr)


# ---------------------------------------------------------------- Scene <-> dotted values


def _effect_values(effects: Effects) -> dict[str, Any]:
    """The [effects] keys of ``effects``."""
    values = {key: getattr(effects, field) for field, key in EFFECT_FIELDS.items()}
    values["effects.friction"] = [each for each, switch in FRICTION_SWITCHES.items()
                                  if getattr(effects, switch)]
    return values


def _values(scene: Scene) -> dict[str, Any]:
    """Every dotted key of the schema with its value in ``scene``."""
    values = {key: getattr(scene, field) for field, key in FIELDS.items()}
    values |= _effect_values(scene.effects)
    return {key: values[key] for key in SCHEMA}


def _scene(values: dict[str, Any], given: dict[str, Any], origin: str, source: str) -> Scene:
    """The Scene holding the checked ``values`` of every dotted key, ``given`` those set by the
    file ``origin``. Values its derived quantities cannot be made of (R = 1e308: I = c m R^2
    overflows) raise SceneError naming the first of them that ``given`` sets."""
    friction = values["effects.friction"]
    try:
        effects = Effects(**{field: values[key] for field, key in EFFECT_FIELDS.items()},
                          **{switch: each in friction
                             for each, switch in FRICTION_SWITCHES.items()})
        return Scene(**{field: values[key] for field, key in FIELDS.items()}, effects=effects,
                     source=source)
    except SceneValueError as error:
        keys = [KEYS[field] for field in error.fields]
        key = next((each for each in given if each in keys), keys[0])
        made_of = ", ".join(f"{each} = {_show(values[each])}" for each in keys)
        what = error.what if len(keys) == 1 else f"{error.what}, from {made_of}"
        raise SceneError(origin, key, what, values[key]) from None


# ---------------------------------------------------------------- reading a file


def _read_document(file: str) -> dict[str, Any]:
    """The parsed TOML document in ``file``; a missing, unreadable or malformed file raises."""
    try:
        text = Path(file).read_bytes().decode("utf-8")
    except OSError as error:
        raise SceneError(file, FILE_KEY, "cannot read the scene file",
                         error.strerror or str(error)) from None
    except UnicodeDecodeError as error:
        raise SceneError(file, FILE_KEY, "not UTF-8 text",
                         f"byte 0x{error.object[error.start]:02x} at offset {error.start}") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise SceneError(file, FILE_KEY, "malformed TOML", str(error)) from None


def _unknown(file: str, table: str, name: str, value: Any, schema: dict = SCHEMA) -> SceneError:
    """The error for a key or table the schema does not know in ``table``, listing known ones."""
    siblings = [key.rpartition(".")[2] for key in schema if key.rpartition(".")[0] == table]
    known = siblings if table else ["geometry"] + siblings + [f"[{each}]" for each in tables(schema)]
    what = "unknown table" if isinstance(value, dict) else "unknown key"
    where = f" in [{table}]" if table else ""
    key = f"{table}.{name}" if table else name
    return SceneError(file, key, f"{what}{where}, expected one of {', '.join(known)}", value)


def _entry(file: str, table: str, name: str, value: Any, schema: dict = SCHEMA
           ) -> tuple[str, Any]:
    """(dotted key, value) for key ``name`` of ``table`` ("" at top level); unknown ones raise."""
    key = f"{table}.{name}" if table else name
    if key not in schema or key.rpartition(".")[0] != table:  # a quoted "disks.N" is no key
        raise _unknown(file, table, name, value, schema)
    return key, value


def _entries(document: dict[str, Any], file: str, schema: dict = SCHEMA
             ) -> Iterator[tuple[str, Any]]:
    """(dotted key, value) for every key of ``document`` in file order; unknown ones raise."""
    known = tables(schema)
    for name, value in document.items():
        if name not in known:
            yield _entry(file, "", name, value, schema)
        elif not isinstance(value, dict):
            raise SceneError(file, name, f"expected a table, not {kind(value)}", value)
        else:
            yield from (_entry(file, name, inner, item, schema) for inner, item in value.items())


def _check(file: str, key: str, value: Any, schema: dict = SCHEMA) -> Any:
    """The scene value of ``value`` at the known dotted ``key``, by the rule of the field it
    sets; a bad value raises."""
    try:
        return schema[key].rule.check(value)
    except Invalid as invalid:
        raise SceneError(file, key, invalid.what, value) from None


def _checked(entries: Iterator[tuple[str, Any]], file: str, schema: dict = SCHEMA
             ) -> dict[str, Any]:
    """The scene value of every (dotted key, value) of ``entries``; the first bad key raises."""
    return {key: _check(file, key, value, schema) for key, value in entries}


def _geometry(document: dict[str, Any], file: str) -> str:
    """The document's top-level ``geometry`` (taken out of it), "chain" when absent."""
    value = document.pop("geometry", "chain")
    try:
        if expect(value, str, "a string") not in GEOMETRIES:
            raise Invalid(f"unknown geometry: must be one of {' | '.join(GEOMETRIES)}")
    except Invalid as invalid:
        raise SceneError(file, "geometry", invalid.what, value) from None
    return value


def _packing_values(scene: PackingScene) -> dict[str, Any]:
    """Every dotted key of PACKING_SCHEMA with its value in ``scene``."""
    values = {key: getattr(scene, field) for field, key in PACKING_FIELDS.items()}
    values |= {key: getattr(scene.effects, field) for field, key in PACKING_EFFECTS.items()}
    values["effects.friction"] = ["disk-disk"] if scene.effects.pair_friction else []
    return {key: values[key] for key in PACKING_SCHEMA}


def _packing_scene(values: dict[str, Any], given: dict[str, Any], origin: str) -> PackingScene:
    """The PackingScene of the checked dotted ``values``; as _scene, a value that breaks a rule
    of several keys (the typical overlap of pressure, k_n and R) names the first of them that
    ``given`` sets."""
    try:
        effects = Effects(**{field: values[key] for field, key in PACKING_EFFECTS.items()},
                          pair_friction="disk-disk" in values["effects.friction"],
                          wall_friction=False)
        return PackingScene(**{field: values[key] for field, key in PACKING_FIELDS.items()},
                            effects=effects, source=origin)
    except SceneValueError as error:
        keys = [PACKING_KEYS.get(field, "effects.friction") for field in error.fields]
        key = next((each for each in given if each in keys), keys[0])
        made_of = ", ".join(f"{each} = {_show(values[each])}" for each in keys)
        what = error.what if len(keys) == 1 else f"{error.what}, from {made_of}"
        raise SceneError(origin, key, what, values.get(key)) from None


def load_scene(path: str | os.PathLike[str]) -> Scene | PackingScene:
    """The Scene (or, with ``geometry = "packing"``, the PackingScene) in the TOML file
    ``path``: missing keys take the defaults, ``name`` defaults to the file's stem, ``source``
    is the path as given. Raises SceneError on any problem."""
    file = os.fspath(path)
    document = _read_document(file)
    geometry = _geometry(document, file)
    schema = SCHEMAS[geometry]
    given = _checked(_entries(document, file, schema), file, schema)
    if geometry == "packing":
        defaults = _packing_values(replace(PackingScene(), name=Path(file).stem))
        return _packing_scene(defaults | given, given, file)
    defaults = _values(replace(Scene(), name=Path(file).stem))
    return _scene(defaults | given, given, origin=file, source=file)


def number_keys(geometry: str = "chain") -> dict[str, type]:
    """The dotted keys of a `geometry`'s scene ("chain" or "packing") that hold one number,
    each with the type a scene gives it (int for disks.N, packing.N and packing.seed, float for
    the others): the keys a parameter map may vary."""
    values = _packing_values(PackingScene()) if geometry == "packing" else _values(Scene())
    return {key: type(value) for key, value in values.items()
            if isinstance(value, (int, float)) and not isinstance(value, bool)}


def with_values(scene: Scene | PackingScene, values: dict[str, Any], origin: str
                ) -> Scene | PackingScene:
    """``scene`` with the dotted keys of ``values`` set, each checked by the scene's schema as
    if a file ``origin`` held it. Raises SceneError, as load_scene does, for an unknown key or
    a value the key does not take (``disks.N = 2.5``: expected an integer)."""
    schema = PACKING_SCHEMA if isinstance(scene, PackingScene) else SCHEMA
    given = _checked((_entry(origin, *key.rpartition(".")[::2], value, schema)
                      for key, value in values.items()), origin, schema)
    if isinstance(scene, PackingScene):
        return replace(_packing_scene(_packing_values(scene) | given, given, origin),
                       name=scene.name, source=scene.source)
    return _scene(_values(scene) | given, given, origin=origin, source=scene.source)


def default_scene_path() -> Path:
    """The packaged paper scene, scenes/paper.toml."""
    return Path(str(resources.files("diskfriction.scenes") / "paper.toml"))


# ---------------------------------------------------------------- writing a scene


def _line(text: str, comment: str) -> str:
    """``text`` followed by a comment aligned at COMMENT_COLUMN."""
    return f"{text:<{COMMENT_COLUMN}} # {comment}"


def _key_lines(values: dict[str, Any], prefix: str = "", schema: dict = SCHEMA) -> list[str]:
    """``key = value  # comment`` lines for dotted ``values``, with [table] headers.

    With a ``prefix`` (a comment marker) the lines are comments and carry no table headers.
    """
    lines, table = [], ""
    for key, value in values.items():
        head, _, name = key.rpartition(".")
        if head != table and not prefix:
            lines += ["", f"[{head}]"]
        table = head
        lines.append(_line(f"{prefix}{name} = {_toml(value)}", schema[key].comment))
    return lines


def _derived_lines(scene: Scene) -> list[str]:
    """Comment lines with the quantities derived from ``scene`` and its resolved effects."""
    derived = (
        ("L", scene.L, "ring length 2 N R (1 - eps)"),
        ("I", scene.I, "moment of inertia c m R^2"),
        ("delta_w0", scene.delta_w0, "substrate overlap at F_x = 0, (F_y / k_n)^(1/p)"),
        ("tau", scene.tau, "time unit sqrt(m / (k_n (2R)^(1/2)))"),
        ("ndof", scene.ndof, "degrees of freedom, N x (3 with rotation, else 2)"),
    )
    return [
        "",
        "# derived (comments, not read back):",
        *(_line(f"# {name} = {_toml(value)}", comment) for name, value, comment in derived),
        "# resolved effects (mu = 0 turns friction off):",
        *_key_lines(_effect_values(scene.resolved_effects), prefix="#   "),
    ]


def format_scene(scene: Scene | PackingScene) -> str:
    """``scene`` as TOML in the scene-file schema, every key written out, then comment lines
    with the derived quantities (chain: L, I, delta_w0, tau, ndof; packing: delta_0, ndof) and
    the resolved effects."""
    header = f"# scene {_toml_string(scene.name)} from {_toml_string(scene.source)}"
    if isinstance(scene, PackingScene):
        derived = [("delta_0", scene.delta_0, "overlap carrying the force 2 R P, (2 R P / k_n)^(1/p)"),
                   ("ndof", scene.ndof, "degrees of freedom, 3 N")]
        return "\n".join([header, "", _line('geometry = "packing"', "a 2D packing (docs/packings.md)"),
                          *_key_lines(_packing_values(scene), schema=PACKING_SCHEMA), "",
                          "# derived (comments, not read back):",
                          *(_line(f"# {name} = {_toml(value)}", comment)
                            for name, value, comment in derived)]) + "\n"
    return "\n".join([header, *_key_lines(_values(scene)), *_derived_lines(scene)]) + "\n"
