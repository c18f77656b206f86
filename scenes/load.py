"""Scene files: load and validate a TOML scene, write a resolved scene back as TOML.

A scene file has a top-level ``name`` and the tables [disks], [contacts], [load], [effects],
[stability] (schema and units: scenes/paper.toml). Every key is optional; a missing key takes the
Scene() default. Files are parsed with tomllib only: nothing in a file is ever evaluated as code.
Every problem raises one SceneError whose str() is a single line naming the file and dotted key.
"""
from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path
from typing import Any, Callable, Iterator

from diskfriction.scenes.scene import (CONVENTIONS, FRICTION_KINDS, MATRICES, NEGATIVE_LOAD,
                                       TANGENTIAL_LAWS, Effects, Scene)

FILE_KEY = "<file>"
INT64 = (-(2**63), 2**63 - 1)
COMMENT_COLUMN = 36

# Scene field -> dotted key, for the fields a file sets one to one.
_FIELDS = {
    "name": "name",
    "N": "disks.N",
    "R": "disks.R",
    "m": "disks.m",
    "inertia": "disks.inertia",
    "eps": "disks.eps",
    "k_n": "contacts.k_n",
    "k_t": "contacts.k_t",
    "mu": "contacts.mu",
    "F_y": "load.F_y",
    "F_x_range": "load.F_x",
    "matrix": "stability.matrix",
}
# Friction kind in a file -> the Effects switch it turns on.
_FRICTION_SWITCHES = {"disk-disk": "pair_friction", "substrate": "wall_friction"}


class SceneError(Exception):
    """One problem with a scene file: ``scene error: FILE: KEY: what is wrong (got VALUE)``.

    ``key`` is the dotted key (``disks.N``, ``load.F_x``) or ``<file>`` for whole-file problems.
    """

    def __init__(self, file: str, key: str, what: str, value: Any) -> None:
        self.file, self.key, self.what, self.value = file, key, what, value
        shown = file if file.isprintable() else repr(file)[1:-1]  # one line, whatever the path
        super().__init__(f"scene error: {shown}: {key}: {what} (got {_show(value)})")


class _Invalid(Exception):
    """A value breaking a rule; ``what`` says which. The loader adds the file and the key."""

    def __init__(self, what: str) -> None:
        super().__init__(what)
        self.what = what


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


def _kind(value: Any) -> str:
    """The TOML kind of a parsed value, for "expected X, not Y" messages."""
    kinds = ((bool, "a boolean"), (int, "an integer"), (float, "a float"), (str, "a string"),
             (list, "an array"), (dict, "a table"))
    return next((name for kind, name in kinds if isinstance(value, kind)), "a date/time")


# ---------------------------------------------------------------- checking one value


def _expect(value: Any, kinds: tuple[type, ...], expected: str) -> Any:
    """``value`` if it is one of ``kinds`` (a boolean only if bool is listed), else _Invalid."""
    if not isinstance(value, kinds) or (isinstance(value, bool) and bool not in kinds):
        raise _Invalid(f"expected {expected}, not {_kind(value)}")
    if isinstance(value, int) and not isinstance(value, bool) and not INT64[0] <= value <= INT64[1]:
        raise _Invalid("integer outside TOML's 64-bit range")
    return value


def _number(value: Any) -> float:
    """A finite float from a TOML integer or float; never a boolean or a string."""
    number = float(_expect(value, (int, float), "a number"))
    if not math.isfinite(number):
        raise _Invalid("must be a finite number")
    return number


def _number_where(holds: Callable[[float], bool], rule: str) -> Callable[[Any], float]:
    """A check for a finite number for which ``holds``; ``rule`` says what is wrong otherwise."""

    def check(value: Any) -> float:
        number = _number(value)
        if not holds(number):
            raise _Invalid(rule)
        return number

    return check


_positive = _number_where(lambda x: x > 0.0, "must be > 0")
_non_negative = _number_where(lambda x: x >= 0.0, "must be >= 0")
_pre_compression = _number_where(lambda x: 0.0 <= x < 0.1, "must be in [0, 0.1)")


def _disk_count(value: Any) -> int:
    """N: an integer (not a boolean or a float) of at least 2."""
    count = _expect(value, (int,), "an integer")
    if count < 2:
        raise _Invalid("must be >= 2")
    return count


def _load_range(value: Any) -> tuple[float, float]:
    """F_x: an array [start, stop] of two finite numbers with 0 <= start < stop (NEGATIVE_LOAD
    says why not below 0)."""
    if len(_expect(value, (list,), "an array [start, stop]")) != 2:
        raise _Invalid(f"expected exactly two numbers [start, stop], not {len(value)}")
    start, stop = map(_number, value)
    if start < 0:
        raise _Invalid(f"must be >= 0: {NEGATIVE_LOAD}")
    if start == stop:
        raise _Invalid("empty range: start == stop")
    if start > stop:
        raise _Invalid("reversed range: start > stop")
    return (start, stop)


def _string(value: Any) -> str:
    """A string."""
    return _expect(value, (str,), "a string")


def _flag(value: Any) -> bool:
    """A boolean."""
    return _expect(value, (bool,), "a boolean (true or false)")


def _effect_choice(options: tuple[str, ...], effect: str) -> Callable[[Any], str]:
    """A check for a string naming one of ``options``; anything else is an unknown effect."""

    def check(value: Any) -> str:
        if _string(value) not in options:
            raise _Invalid(f"unknown effect: {effect} must be one of {' | '.join(options)}")
        return value

    return check


def _friction_kinds(value: Any) -> tuple[str, ...]:
    """friction: an array of distinct strings from FRICTION_KINDS (may be empty)."""
    kinds = _expect(value, (list,), "an array of strings")
    if not all(isinstance(kind, str) for kind in kinds):
        raise _Invalid("expected an array of strings")
    unknown = [kind for kind in kinds if kind not in FRICTION_KINDS]
    if unknown:
        raise _Invalid(f"unknown effect: friction kind {unknown[0]!r}, "
                       f"expected a subset of {', '.join(FRICTION_KINDS)}")
    if len(set(kinds)) != len(kinds):
        raise _Invalid("duplicated friction kind")
    return tuple(kinds)


@dataclass(frozen=True)
class _Key:
    """One key of the schema: its check (parsed value -> Scene value) and its comment."""

    check: Callable[[Any], Any]
    comment: str


# Dotted key -> its check and comment, in the order format_scene writes them.
SCHEMA: dict[str, _Key] = {
    "name": _Key(_string, "label"),
    "disks.N": _Key(_disk_count, "number of disks (integer >= 2)"),
    "disks.R": _Key(_positive, "disk radius [length]"),
    "disks.m": _Key(_positive, "disk mass [mass]"),
    "disks.inertia": _Key(_positive, "c in I = c m R^2 (0.5: uniform disk)"),
    "disks.eps": _Key(_pre_compression, "pre-compression in [0, 0.1): L = 2 N R (1 - eps)"),
    "contacts.k_n": _Key(_positive, "Hertz normal stiffness [force / length^(3/2)]"),
    "contacts.k_t": _Key(_positive, "Mindlin tangential stiffness [force / length^(3/2)]"),
    "contacts.mu": _Key(_non_negative, "friction coefficient (0 turns friction off)"),
    "load.F_y": _Key(_positive, "downward force on every disk [force]"),
    "load.F_x": _Key(_load_range, "quasistatic range [start, stop], 0 <= start < stop, of the "
                                  "force on disk 1"),
    "effects.tangential": _Key(_effect_choice(TANGENTIAL_LAWS, "tangential law"),
                               " | ".join(TANGENTIAL_LAWS)),
    "effects.friction": _Key(_friction_kinds,
                             "where the tangential law acts (subset, may be empty)"),
    "effects.rotation": _Key(_flag, "disks rotate (3 dof per disk) or not (2)"),
    "effects.conventions": _Key(_effect_choice(CONVENTIONS, "conventions"),
                                " | ".join(CONVENTIONS) + " (disk-disk lever arm and history "
                                "increment, docs/physics.md)"),
    "stability.matrix": _Key(_effect_choice(MATRICES, "stability matrix"), " | ".join(MATRICES)),
}
TABLES = tuple(dict.fromkeys(key.partition(".")[0] for key in SCHEMA if "." in key))


# ---------------------------------------------------------------- Scene <-> dotted values


def _effect_values(effects: Effects) -> dict[str, Any]:
    """The [effects] keys of ``effects``."""
    return {
        "effects.tangential": effects.tangential,
        "effects.friction": [kind for kind, switch in _FRICTION_SWITCHES.items()
                             if getattr(effects, switch)],
        "effects.rotation": effects.rotation,
        "effects.conventions": effects.conventions,
    }


def _values(scene: Scene) -> dict[str, Any]:
    """Every dotted key of the schema with its value in ``scene``."""
    values = {key: getattr(scene, field) for field, key in _FIELDS.items()}
    values |= _effect_values(scene.effects)
    return {key: values[key] for key in SCHEMA}


def _scene(values: dict[str, Any], source: str) -> Scene:
    """The Scene holding the checked ``values`` of every dotted key."""
    friction = values["effects.friction"]
    effects = Effects(
        tangential=values["effects.tangential"],
        rotation=values["effects.rotation"],
        conventions=values["effects.conventions"],
        **{switch: kind in friction for kind, switch in _FRICTION_SWITCHES.items()},
    )
    plain = {field: values[key] for field, key in _FIELDS.items()}
    return Scene(**plain, effects=effects, source=source)


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


def _unknown(file: str, table: str, name: str, value: Any) -> SceneError:
    """The error for a key or table the schema does not know in ``table``, listing known ones."""
    siblings = [key.rpartition(".")[2] for key in SCHEMA if key.rpartition(".")[0] == table]
    known = siblings if table else siblings + [f"[{each}]" for each in TABLES]
    what = "unknown table" if isinstance(value, dict) else "unknown key"
    where = f" in [{table}]" if table else ""
    key = f"{table}.{name}" if table else name
    return SceneError(file, key, f"{what}{where}, expected one of {', '.join(known)}", value)


def _entry(file: str, table: str, name: str, value: Any) -> tuple[str, Any]:
    """(dotted key, value) for key ``name`` of ``table`` ("" at top level); unknown ones raise."""
    key = f"{table}.{name}" if table else name
    if key not in SCHEMA or key.rpartition(".")[0] != table:  # a quoted "disks.N" is no key
        raise _unknown(file, table, name, value)
    return key, value


def _entries(document: dict[str, Any], file: str) -> Iterator[tuple[str, Any]]:
    """(dotted key, value) for every key of ``document`` in file order; unknown ones raise."""
    for name, value in document.items():
        if name not in TABLES:
            yield _entry(file, "", name, value)
        elif not isinstance(value, dict):
            raise SceneError(file, name, f"expected a table, not {_kind(value)}", value)
        else:
            yield from (_entry(file, name, inner, item) for inner, item in value.items())


def _check(file: str, key: str, value: Any) -> Any:
    """The Scene value of ``value`` at the known dotted ``key``; a bad value raises."""
    try:
        return SCHEMA[key].check(value)
    except _Invalid as invalid:
        raise SceneError(file, key, invalid.what, value) from None


def _checked(document: dict[str, Any], file: str) -> dict[str, Any]:
    """The Scene value of every key set in ``document``; the first bad key raises."""
    return {key: _check(file, key, value) for key, value in _entries(document, file)}


def load_scene(path: str | os.PathLike[str]) -> Scene:
    """The Scene in the TOML file ``path``: missing keys take Scene() defaults, ``name`` defaults
    to the file's stem, ``source`` is the path as given. Raises SceneError on any problem."""
    file = os.fspath(path)
    defaults = _values(replace(Scene(), name=Path(file).stem))
    return _scene(defaults | _checked(_read_document(file), file), source=file)


def number_keys() -> dict[str, type]:
    """The dotted keys that hold one number, each with the type a scene gives it (int for
    disks.N, float for the others): the keys a parameter map may vary."""
    return {key: type(value) for key, value in _values(Scene()).items()
            if isinstance(value, (int, float)) and not isinstance(value, bool)}


def with_values(scene: Scene, values: dict[str, Any], origin: str) -> Scene:
    """``scene`` with the dotted keys of ``values`` set, each checked by the schema as if a
    file ``origin`` held it. Raises SceneError, as load_scene does, for an unknown key or a
    value the key does not take (``disks.N = 2.5``: expected an integer)."""
    entries = (_entry(origin, *key.rpartition(".")[::2], value) for key, value in values.items())
    return _scene(_values(scene) | {key: _check(origin, key, value) for key, value in entries},
                  source=scene.source)


def default_scene_path() -> Path:
    """The packaged paper scene, scenes/paper.toml."""
    return Path(str(resources.files("diskfriction.scenes") / "paper.toml"))


# ---------------------------------------------------------------- writing a scene


def _line(text: str, comment: str) -> str:
    """``text`` followed by a comment aligned at COMMENT_COLUMN."""
    return f"{text:<{COMMENT_COLUMN}} # {comment}"


def _key_lines(values: dict[str, Any], prefix: str = "") -> list[str]:
    """``key = value  # comment`` lines for dotted ``values``, with [table] headers.

    With a ``prefix`` (a comment marker) the lines are comments and carry no table headers.
    """
    lines, table = [], ""
    for key, value in values.items():
        head, _, name = key.rpartition(".")
        if head != table and not prefix:
            lines += ["", f"[{head}]"]
        table = head
        lines.append(_line(f"{prefix}{name} = {_toml(value)}", SCHEMA[key].comment))
    return lines


def _derived_lines(scene: Scene) -> list[str]:
    """Comment lines with the quantities derived from ``scene`` and its resolved effects."""
    derived = (
        ("L", scene.L, "ring length 2 N R (1 - eps)"),
        ("I", scene.I, "moment of inertia c m R^2"),
        ("delta_w0", scene.delta_w0, "substrate overlap at F_x = 0, (F_y / k_n)^(2/3)"),
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


def format_scene(scene: Scene) -> str:
    """``scene`` as TOML in the scene-file schema, every key written out, then comment lines
    with the derived quantities (L, I, delta_w0, tau, ndof) and the resolved effects."""
    header = f"# scene {_toml_string(scene.name)} from {_toml_string(scene.source)}"
    return "\n".join([header, *_key_lines(_values(scene)), *_derived_lines(scene)]) + "\n"
