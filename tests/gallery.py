"""The gallery's examples (examples/*.py, not a package) imported by file, as
`bifurcate --problem` imports them."""
from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def load_example(name: str) -> ModuleType:
    """A fresh module of examples/NAME.py (a new problem object each time: a problem that
    carries state, like the disk chain's history, is used once)."""
    spec = importlib.util.spec_from_file_location(f"gallery_{name}", EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
