"""Scenes: the Scene dataclass, TOML loading and validation."""
from diskfriction.scenes.load import SceneError, default_scene_path, format_scene, load_scene
from diskfriction.scenes.scene import (CONVENTIONS, FRICTION_KINDS, MATRICES, TANGENTIAL_LAWS,
                                       Effects, Scene)

__all__ = [
    "Effects",
    "Scene",
    "TANGENTIAL_LAWS",
    "FRICTION_KINDS",
    "MATRICES",
    "CONVENTIONS",
    "SceneError",
    "load_scene",
    "default_scene_path",
    "format_scene",
]
