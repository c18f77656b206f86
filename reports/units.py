"""The paper's units (docs/model.md#units), and axis labels that say them.

Raw units are the scene's (m, 2R, k_n as given). The paper reports
  lengths in 2R,  time in tau = sqrt(m / (k_n (2R)^(1/2))),  velocities in 2R / tau,
  eigenvalues of J in k_n (2R)^(1/2) [force / length], eigenvalues of M^-1 J in 1 / tau^2,
  frequencies and growth rates in 1 / tau,  F_x as quoted (raw force; m = 1, 2R = 1).
For the paper's scene (m = 1, 2R = 1) both eigenvalue units are k_n: lambda / k_n, as docs/model.md#units
says, and tau = 0.02236 raw time units.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from diskfriction.scenes import Scene


@dataclass(frozen=True)
class PaperUnits:
    """Conversion factors: paper value = raw value / unit."""

    length: float  # 2R
    time: float  # tau
    eig_J: float  # k_n (2R)^(1/2)
    eig_MJ: float  # 1 / tau^2

    @classmethod
    def of(cls, scene: Scene) -> PaperUnits:
        tau = scene.tau
        return cls(2 * scene.R, tau, scene.k_n * math.sqrt(2 * scene.R), 1.0 / tau**2)

    @property
    def velocity(self) -> float:
        return self.length / self.time

    def eigenvalue(self, matrix: str) -> float:
        """The unit of an eigenvalue of `matrix` ("J" or "M^-1 J")."""
        return self.eig_J if matrix == "J" else self.eig_MJ


EIG_UNIT_LABEL = {"J": r"$k_n (2R)^{1/2}$", "M^-1 J": r"$\tau^{-2}$"}
TIME_LABEL = r"$t$ [$\tau$]"
F_X_LABEL = r"$F_x$ [raw force, as the paper quotes it]"


def eig_label(part: str, matrix: str, unit: str | None = None) -> str:
    """Axis label of Re or Im of an eigenvalue of `matrix`, with `unit` (default its paper
    unit; "" for none)."""
    unit = EIG_UNIT_LABEL[matrix] if unit is None else unit
    return rf"{part} $\lambda$ of {matrix}" + (f" [{unit}]" if unit else "")
