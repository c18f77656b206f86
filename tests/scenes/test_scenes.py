"""Scene files: loading, validation, the TOML round trip and the ``diskfriction scene`` command."""
from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import numpy as np
import pytest
from commandline import error_line, run_cli, run_main

from diskfriction.cli.main import main
from diskfriction.scenes.load import (KEYS, SCHEMA, SceneError, default_scene_path, format_scene,
                                      load_scene)
from diskfriction.scenes.scene import Effects, Scene, SceneValueError

MISSING, DIRECTORY = object(), object()  # bad-scene contents that are not file text


def write_scene(tmp_path: Path, content: str | bytes | object) -> Path:
    """A path holding ``content``: TOML text, raw bytes, nothing (MISSING) or a DIRECTORY."""
    path = tmp_path / "scene.toml"
    if content is DIRECTORY:
        path.mkdir()
    elif isinstance(content, bytes):
        path.write_bytes(content)
    elif isinstance(content, str):
        path.write_text(content, encoding="utf-8")
    return path


def without_source(scene: Scene) -> Scene:
    """``scene`` with the source field blanked, to compare scenes read from different files."""
    return dataclasses.replace(scene, source="")


# ---------------------------------------------------------------- good scenes


def test_paper_scene_is_the_scene_defaults():
    scene = load_scene(default_scene_path())
    assert without_source(scene) == without_source(Scene())
    for field in dataclasses.fields(Scene):
        if field.name != "source":
            assert getattr(scene, field.name) == getattr(Scene(), field.name), field.name
    assert scene.source == str(default_scene_path())


def test_empty_file_takes_defaults_and_name_from_stem(tmp_path):
    path = tmp_path / "my-chain.toml"
    path.write_text("", encoding="utf-8")
    scene = load_scene(path)
    assert scene == dataclasses.replace(Scene(), name="my-chain", source=str(path))


def test_integers_are_accepted_as_floats_and_stored_as_floats(tmp_path):
    scene = load_scene(write_scene(tmp_path, "[disks]\nR = 1\n[load]\nF_x = [1, 2]\n"))
    assert scene.R == 1.0 and isinstance(scene.R, float)
    assert scene.F_x_range == (1.0, 2.0) and all(isinstance(x, float) for x in scene.F_x_range)


@pytest.mark.parametrize("conventions", ["model", "lammps"])
def test_conventions_are_read_and_model_is_the_default(tmp_path, conventions):
    scene = load_scene(write_scene(tmp_path, f'[effects]\nconventions = "{conventions}"\n'))
    assert scene.effects.conventions == conventions
    assert Scene().effects.conventions == "model"


@pytest.mark.parametrize(("friction", "pair", "wall"), [
    ('["disk-disk", "substrate"]', True, True),
    ('["substrate"]', False, True),
    ('["disk-disk"]', True, False),
    ("[]", False, False),
])
def test_friction_list_maps_to_effect_switches(tmp_path, friction, pair, wall):
    scene = load_scene(write_scene(tmp_path, f"[effects]\nfriction = {friction}\n"))
    assert (scene.effects.pair_friction, scene.effects.wall_friction) == (pair, wall)


ODD_SCENE = Scene(
    N=7, R=0.25, m=2.0, inertia=0.4, eps=0.05, k_n=1000, k_t=1e-05, mu=0.0, F_y=3.0,
    F_x_range=(0.5, 1e16), matrix="M^-1 J",
    effects=Effects("mindlin-linear", pair_friction=False, wall_friction=True, rotation=False,
                    conventions="lammps"),
    name='odd "name" \\ with\nnewline\x7f and ü', source="<test>")


@pytest.mark.parametrize("scene", [Scene(), ODD_SCENE], ids=["defaults", "odd"])
def test_format_scene_round_trips(tmp_path, scene):
    path = tmp_path / "round.toml"
    path.write_text(format_scene(scene), encoding="utf-8")
    assert without_source(load_scene(path)) == without_source(scene)


def test_format_scene_writes_every_key_and_the_derived_quantities():
    text = format_scene(Scene())
    document = tomllib.loads(text)
    assert set(document) == {"name", "disks", "contacts", "load", "effects", "stability"}
    assert set(document["disks"]) == {"N", "R", "m", "inertia", "eps"}
    assert set(document["contacts"]) == {"k_n", "k_t", "mu"}
    assert set(document["load"]) == {"F_y", "F_x"}
    assert set(document["effects"]) == {"normal", "tangential", "friction", "rotation",
                                        "conventions"}
    assert set(document["stability"]) == {"matrix"}
    scene = Scene()
    for name, value in [("L", scene.L), ("I", scene.I), ("delta_w0", scene.delta_w0),
                        ("tau", scene.tau), ("ndof", scene.ndof)]:
        assert f"# {name} = {value!r}" in text


def test_format_scene_shows_that_mu_zero_turns_friction_off():
    text = format_scene(dataclasses.replace(Scene(), mu=0.0))
    resolved = text[text.index("# resolved effects"):]
    assert '#   tangential = "none"' in resolved
    assert "#   friction = []" in resolved
    assert tomllib.loads(text)["effects"]["friction"] == ["disk-disk", "substrate"]


# ---------------------------------------------------------------- bad scenes

BAD_VALUES = [
    # id, dotted key, TOML value, expected fragment of the message
    ("name-not-string", "name", "3", "expected a string"),
    ("bool-as-number", "disks.R", "true", "not a boolean"),
    ("string-as-number", "contacts.k_n", '"2000"', "not a string"),
    ("float-N", "disks.N", "10.0", "expected an integer"),
    ("bool-N", "disks.N", "true", "expected an integer"),
    ("huge-N", "disks.N", "9223372036854775808", "64-bit"),
    ("inf", "load.F_y", "inf", "finite"),
    ("nan", "contacts.mu", "nan", "finite"),
    ("N-below-2", "disks.N", "1", ">= 2"),
    ("R-zero", "disks.R", "0", "> 0"),
    ("R-negative", "disks.R", "-0.5", "> 0"),
    ("m-zero", "disks.m", "0.0", "> 0"),
    ("inertia-zero", "disks.inertia", "0", "> 0"),
    ("k_n-zero", "contacts.k_n", "0", "> 0"),
    ("k_t-negative", "contacts.k_t", "-1.0", "> 0"),
    ("mu-negative", "contacts.mu", "-0.1", ">= 0"),
    ("F_y-zero", "load.F_y", "0", "> 0"),
    ("eps-negative", "disks.eps", "-0.01", "[0, 0.1)"),
    ("eps-too-large", "disks.eps", "0.1", "[0, 0.1)"),
    ("F_x-empty", "load.F_x", "[0.1, 0.1]", "empty range"),
    ("F_x-negative", "load.F_x", "[-0.1, 0.1]", "mirror image"),
    ("F_x-reversed", "load.F_x", "[0.12, 0.0]", "reversed range"),
    ("F_x-three", "load.F_x", "[0.0, 0.1, 0.2]", "exactly two"),
    ("F_x-number", "load.F_x", "0.12", "expected an array"),
    ("F_x-string-entry", "load.F_x", '["0", 0.1]', "expected a number"),
    ("F_x-inf-entry", "load.F_x", "[0.0, inf]", "finite"),
    ("normal-unknown", "effects.normal", '"jkr"', "unknown effect"),
    ("tangential-unknown", "effects.tangential", '"coulomb"', "unknown effect"),
    ("tangential-number", "effects.tangential", "1", "expected a string"),
    ("friction-unknown", "effects.friction", '["wall"]', "unknown effect"),
    ("friction-duplicated", "effects.friction", '["substrate", "substrate"]', "duplicated"),
    ("friction-not-strings", "effects.friction", "[1]", "array of strings"),
    ("friction-string", "effects.friction", '"substrate"', "expected an array"),
    ("rotation-string", "effects.rotation", '"yes"', "expected a boolean"),
    ("rotation-int", "effects.rotation", "1", "expected a boolean"),
    ("matrix-unknown", "stability.matrix", '"M"', "unknown effect"),
    ("conventions-unknown", "effects.conventions", '"LAMMPS"',
     "conventions must be one of model | lammps"),
    ("conventions-bool", "effects.conventions", "true", "expected a string"),
    # values each fine alone whose derived quantities are not finite normal numbers
    ("R-overflows-L", "disks.R", "1e308", "L = 2 N R (1 - eps) = inf"),
    ("R-overflows-I", "disks.R", "1e200", "I = c m R^2 = inf"),
    ("R-underflows-I", "disks.R", "1e-200", "I = c m R^2 = 0.0"),
]


def toml_line(key: str, literal: str) -> str:
    """A scene file setting the dotted ``key`` to the TOML ``literal``."""
    table, _, name = key.rpartition(".")
    return (f"[{table}]\n" if table else "") + f"{name} = {literal}\n"


BAD_SCENES = [
    # id, file content, expected key, expected fragment of the message
    *((case, toml_line(key, literal), key, fragment)
      for case, key, literal, fragment in BAD_VALUES),
    ("unknown-key", "[disks]\nradius = 0.5\n", "disks.radius", "unknown key"),
    ("unknown-top-key", 'colour = "red"\n', "colour", "unknown key"),
    ("unknown-table", "[disk]\nN = 10\n", "disk", "unknown table"),
    ("unknown-subtable", "[disks.extra]\nN = 10\n", "disks.extra", "unknown table"),
    ("quoted-dotted-key", '"disks.N" = 3\n', "disks.N", "unknown key"),
    ("table-not-a-table", "disks = 3\n", "disks", "expected a table"),
    ("derived-from-two-keys", "[disks]\nm = 1e300\n[contacts]\nk_n = 1e-300\n", "disks.m",
     "tau = sqrt(m / (k_n (2R)^(1/2))) = inf, not a finite normal number, from disks.m = "
     "1e+300, contacts.k_n = 1e-300, disks.R = 0.5"),
    ("malformed-toml", "[disks\nN = 10\n", "<file>", "line 1"),
    ("missing-file", MISSING, "<file>", "cannot read"),
    ("directory", DIRECTORY, "<file>", "cannot read"),
    ("not-utf8", b'name = "caf\xe9"\n', "<file>", "UTF-8"),
]


@pytest.fixture(params=BAD_SCENES, ids=[case[0] for case in BAD_SCENES])
def bad_scene(request, tmp_path):
    """(path, key, fragment) of one bad scene written under tmp_path."""
    _, content, key, fragment = request.param
    return write_scene(tmp_path, content), key, fragment


def test_bad_scene_raises_one_scene_error(bad_scene):
    path, key, fragment = bad_scene
    with pytest.raises(SceneError) as raised:
        load_scene(path)
    error = raised.value
    assert (error.file, error.key) == (str(path), key)
    message = str(error)
    assert message.startswith(f"scene error: {path}: {key}: ")
    assert fragment in message
    assert "\n" not in message


def test_bad_scene_on_the_command_line_is_one_line_and_exit_2(bad_scene):
    path, key, fragment = bad_scene
    result = run_main("scene", str(path))
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr.endswith("\n") and result.stderr.count("\n") == 1
    assert result.stderr.startswith(f"scene error: {path}: {key}: ")
    assert fragment in result.stderr
    assert "Traceback" not in result.stdout + result.stderr


def test_a_bad_scene_is_refused_alike_in_a_fresh_interpreter(tmp_path):
    """End to end, `python -m diskfriction scene BAD`: exit 2, one line, nothing on stdout;
    the same bytes as in this interpreter (run_main, which the cases above use)."""
    path = write_scene(tmp_path, "[disks]\nN = 1\n")
    fresh = run_cli("scene", str(path))
    assert fresh.returncode == 2 and fresh.stdout == "" and fresh.stderr.count("\n") == 1
    assert error_line(fresh, "scene").startswith(f"scene error: {path}: disks.N: ")
    here = run_main("scene", str(path))
    assert (here.returncode, here.stdout, here.stderr) == (fresh.returncode, fresh.stdout, fresh.stderr)


def test_every_schema_key_has_bad_values():
    assert {key for _, key, _, _ in BAD_VALUES} == set(SCHEMA)


@pytest.mark.parametrize(("key", "literal", "fragment"), [case[1:] for case in BAD_VALUES
                                                           if case[1] != "effects.friction"],
                         ids=[case[0] for case in BAD_VALUES if case[1] != "effects.friction"])
def test_bad_value_is_refused_by_the_dataclass_itself(key, literal, fragment):
    """The value a file gives, given to Scene or Effects directly: one line naming the field
    and the value (effects.friction is a file's spelling of two switches, tested below)."""
    value = tomllib.loads(f"x = {literal}")["x"]
    field = next(field for field, each in KEYS.items() if each == key)
    owner = Effects if key.startswith("effects.") else Scene
    with pytest.raises(SceneValueError) as raised:
        owner(**{field: value})
    message = str(raised.value)
    assert "\n" not in message and fragment in message and repr(value) in message
    assert field in raised.value.fields
    if len(raised.value.fields) == 1:
        assert message.startswith(f"{owner.__name__}.{field}: ")
    with pytest.raises(SceneValueError):  # a changed copy is checked as a new one
        dataclasses.replace(owner(), **{field: value})


@pytest.mark.parametrize("switch", ["pair_friction", "wall_friction"])
def test_friction_switches_are_booleans(switch):
    with pytest.raises(SceneValueError, match=f"^Effects.{switch}: expected a boolean"):
        Effects(**{switch: "yes"})


@pytest.mark.parametrize(("fields", "fragment"), [
    (dict(m=1e300, k_n=1e-300), "tau = sqrt(m / (k_n (2R)^(1/2))) = inf"),
    (dict(F_y=1e-320, k_n=1e10), "delta_w0 = (F_y / k_n)^(1/p) = 0.0"),
    (dict(N=2**62, R=1e300), "L = 2 N R (1 - eps) = inf"),
])
def test_derived_quantities_that_are_not_finite_normal_numbers_are_refused(fields, fragment):
    with pytest.raises(SceneValueError) as raised:
        Scene(**fields)
    assert str(raised.value).startswith(f"Scene: {fragment}, not a finite normal number (got ")
    assert set(fields) <= set(raised.value.fields)


def test_scene_stores_numbers_as_floats_and_N_as_an_int():
    scene = Scene(N=np.int64(5), R=1, F_x_range=[0, 1])
    assert type(scene.N) is int and type(scene.R) is float
    assert scene.F_x_range == (0.0, 1.0) and type(scene.F_x_range) is tuple
    assert scene == Scene(N=5, R=1.0, F_x_range=(0.0, 1.0))


def test_effects_must_be_an_effects():
    with pytest.raises(SceneValueError, match="^Scene.effects: expected an Effects"):
        Scene(effects="mindlin-smooth")


def test_paper_scene_file_holds_what_the_scene_command_prints_for_it():
    """scenes/paper.toml's keys, values and comments (the rules' bounds) are format_scene's."""
    printed = format_scene(load_scene(default_scene_path()))
    keys = printed[printed.index("\n") + 1:printed.index("\n# derived")]
    assert default_scene_path().read_text(encoding="utf-8").endswith(keys)


def test_scene_error_message_format(tmp_path):
    path = write_scene(tmp_path, '[effects]\ntangential = "coulomb"\n')
    with pytest.raises(SceneError) as raised:
        load_scene(path)
    assert str(raised.value) == (
        f"scene error: {path}: effects.tangential: unknown effect: tangential law must be one "
        "of mindlin-smooth | mindlin-linear | none (got 'coulomb')")


# ---------------------------------------------------------------- the command line


def test_cli_scene_without_file_prints_the_paper_scene():
    result = run_cli("scene")
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert result.stdout == format_scene(load_scene(default_scene_path()))


def test_cli_scene_output_is_a_loadable_scene(tmp_path, capsys):
    assert main(["scene"]) == 0
    path = tmp_path / "printed.toml"
    path.write_text(capsys.readouterr().out, encoding="utf-8")
    assert without_source(load_scene(path)) == without_source(Scene())


def test_cli_bad_scene_in_process_returns_2(tmp_path, capsys):
    path = write_scene(tmp_path, "[disks]\nN = 1\n")
    assert main(["scene", str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(f"scene error: {path}: disks.N: ")


@pytest.mark.parametrize("argv", [[], ["nonsense"], ["scene", "a.toml", "b.toml"]])
def test_cli_usage_errors_exit_2_with_one_line(argv, capsys):
    with pytest.raises(SystemExit) as raised:
        main(argv)
    assert raised.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and ": error: " in err


def test_scene_error_stays_one_line_for_a_path_with_a_newline(tmp_path):
    path = tmp_path / "two\nlines.toml"
    path.write_text("[disks]\nN = 1\n")
    with pytest.raises(SceneError) as raised:
        load_scene(path)
    assert "\n" not in str(raised.value) and "two\\nlines.toml" in str(raised.value)
