"""Symbolic derivation of the contact laws and the numba kernels generated from it.

Data flow: Scene -> load_kernels(effects) (derive, print, cache, import) -> System (any N).
"""
from diskfriction.symbolic.kernels import load_kernels
from diskfriction.symbolic.system import System

__all__ = ["System", "load_kernels"]
