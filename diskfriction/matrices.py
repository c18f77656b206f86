"""The stability matrices whose spectra are followed, by name: one definition for the scene's
`matrix`, the commands' `--matrix` and the disk problem (models/chain/equilibria.py)."""
from __future__ import annotations

from enum import StrEnum


class Matrix(StrEnum):
    """J (the paper's eq. 8) or M^-1 J (small oscillations M q'' = -J q: its eigenvalues are
    omega^2). str-valued: a Matrix is its name in every file (collisions.json's "matrix") and
    line; Matrix(name) refuses any other name (ValueError)."""

    J = "J"
    M_INV_J = "M^-1 J"


MATRIX_OPTIONS = {"J": Matrix.J, "M^-1J": Matrix.M_INV_J, "M^-1 J": Matrix.M_INV_J}
"""The values `--matrix` takes (the space may be left out on a command line)."""

EIGENVALUE_UNITS = {Matrix.J: "force / length", Matrix.M_INV_J: "1 / time^2"}
"""The units of each matrix's eigenvalues in the raw units of a scene (docs/outputs.md): J's
are a stiffness (its rows mix forces and torques, its columns lengths and angles), M^-1 J's
are omega^2."""
