"""Scenes: the Scene dataclass, the rules its values obey, TOML loading."""
from diskfriction.scenes.load import SceneError, default_scene_path, format_scene, load_scene
from diskfriction.scenes.scene import (CONVENTIONS, FRICTION_KINDS, MATRICES, NORMAL_LAWS,
                                       TANGENTIAL_LAWS, Effects, Scene, SceneValueError)

__all__ = [
    "Effects",
    "Scene",
    "SceneValueError",
    "NORMAL_LAWS",
    "TANGENTIAL_LAWS",
    "FRICTION_KINDS",
    "MATRICES",
    "CONVENTIONS",
    "SceneError",
    "load_scene",
    "default_scene_path",
    "format_scene",
]
