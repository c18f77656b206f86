"""Scenes: the Scene dataclass, TOML loading and validation."""
from scenes.scene import FRICTION_KINDS, MATRICES, TANGENTIAL_LAWS, Effects, Scene

__all__ = ["Effects", "Scene", "TANGENTIAL_LAWS", "FRICTION_KINDS", "MATRICES"]
