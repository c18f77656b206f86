"""The PackingScene: N bidisperse frictional disks in a periodic square box, prepared at a
target pressure and sheared quasistatically with Lees-Edwards boundaries (docs/packings.md).

Raw units as the chain's (docs/model.md#units): lengths where the small disks' diameter is 2R,
masses in units of the small disks' mass m (every disk has the same density: a disk of radius
r has mass m r^2 / R^2 and moment of inertia c m_i r^2), stiffnesses k_n [force / length^p],
pressure [force / length] (a 2D pressure). Every field is checked by its rule
(scenes/rules.py: PACKING_RULES) when constructed.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar

from diskfriction.scenes.rules import MAX_OVERLAP, NORMAL_LAWS, PACKING_RULES
from diskfriction.scenes.scene import Effects, SceneValueError, _check_fields


SPECTRA_BY_N = ((64, "full"), (256, "sample:0.0005"), (None, "none"))
"""A packing scene's spectra "auto" by N: (most disks, choice), the first that holds. Chosen so
that the default scene (256 disks to gamma = 0.05) finishes in minutes on 2 cores: every
collision located costs 64 disks under a minute to gamma = 0.01 and 256 disks hours
(docs/notes/packings-speed.md, "Spectra as a choice of the run")."""


@dataclass(frozen=True)
class PackingScene:
    """A packing of N disks: round(N fraction_small) of radius R, the rest of radius
    R size_ratio, placed from `seed` and minimised without friction to the 2D pressure
    `pressure` (its typical overlap delta_0 at most MAX_OVERLAP R, scenes/rules.py); then
    friction is switched on (every history zero) and the box sheared from gamma_range[0] to
    gamma_range[1]. Contacts obey the chain's laws (Hertz normal force
    k_n delta^p with one k_n for every pair, smoothed Mindlin with k_t and mu; Effects) with
    lever arms R_i, R_j; the disks rotate. After a plastic event the packing relaxes by
    `relaxation` (models/packing/plastic.py): FIRE, or Newtonian dynamics with a drag of rate
    damping omega_0 (omega_0: PackingScene.omega_0; `damping` is read only then). `spectra`
    says what the shear computes of the spectrum of `matrix` (scenes/rules.py SPECTRA; "auto":
    chosen from N, resolved_spectra)."""

    geometry: ClassVar[str] = "packing"
    """The scene file's top-level ``geometry`` (Scene.geometry)."""

    N: int = 256
    size_ratio: float = 1.4
    fraction_small: float = 0.5
    pressure: float = 0.1
    seed: int = 1
    R: float = 0.5
    m: float = 1.0
    inertia: float = 0.5
    k_n: float = 2000.0
    k_t: float = 2000.0 * 2.0 / 7.0
    mu: float = 10.0
    gamma_range: tuple[float, float] = (0.0, 0.05)
    relaxation: str = "fire"
    damping: float = 0.1
    matrix: str = "M^-1 J"
    spectra: str = "auto"
    effects: Effects = Effects(wall_friction=False)
    name: str = "packing"
    source: str = "<defaults>"

    def __post_init__(self) -> None:
        _check_fields(self, PACKING_RULES)
        if not isinstance(self.effects, Effects):
            raise SceneValueError("PackingScene", ("effects",), (self.effects,),
                                  "expected an Effects")
        if not self.effects.rotation:
            raise SceneValueError("PackingScene", ("effects",), (self.effects,),
                                  "a packing's disks rotate: rotation must be true")
        if self.effects.conventions != "model":
            raise SceneValueError("PackingScene", ("effects",), (self.effects,),
                                  'a packing takes conventions "model" only')
        if self.spectra.startswith("sample:") and self.sample_spacing > self.gamma_range[1] - self.gamma_range[0]:
            raise SceneValueError(
                "PackingScene", ("spectra", "gamma_range"), (self.spectra, self.gamma_range),
                "the sample grid's spacing is wider than the strain range: no two samples in it")
        try:
            overlap = self.delta_0 / self.R
        except OverflowError:
            overlap = math.inf
        if not overlap <= MAX_OVERLAP:
            p = float(NORMAL_LAWS[self.effects.normal])
            largest = self.k_n * (MAX_OVERLAP * self.R) ** p / (2.0 * self.R)
            raise SceneValueError(
                "PackingScene", ("pressure", "k_n", "R"), (self.pressure, self.k_n, self.R),
                f"the typical overlap at this pressure, delta_0 = (2 R P / k_n)^(1/p), is "
                f"{overlap:.3g} R, more than {MAX_OVERLAP:g} R: the contact laws are laws of "
                f"small overlaps; the largest pressure with this k_n and R is {largest:.3g}")

    @property
    def resolved_effects(self) -> Effects:
        """Effects actually simulated: no substrate; mu = 0 carries no tangential force."""
        pair = self.effects.pair_friction and self.mu > 0.0 and self.effects.tangential != "none"
        return dataclasses.replace(self.effects, pair_friction=pair, wall_friction=False,
                                   tangential=self.effects.tangential if pair else "none")

    @property
    def resolved_spectra(self) -> str:
        """spectra with "auto" resolved from N (SPECTRA_BY_N; a sample grid no wider than the
        strain range): "none", "full" or "sample:DGAMMA"."""
        if self.spectra != "auto":
            return self.spectra
        choice = next(choice for most, choice in SPECTRA_BY_N if most is None or self.N <= most)
        span = self.gamma_range[1] - self.gamma_range[0]
        if choice.startswith("sample:") and float(choice.partition(":")[2]) > span:
            return f"sample:{span!r}"  # a strain range shorter than the grid: its two ends
        return choice

    @property
    def sample_spacing(self) -> float | None:
        """DGAMMA of spectra "sample:DGAMMA" (resolved), else None."""
        kind, _, every = self.resolved_spectra.partition(":")
        return float(every) if kind == "sample" else None

    @property
    def ndof(self) -> int:
        return 3 * self.N

    @property
    def delta_0(self) -> float:
        """The overlap of a contact carrying the force P 2R, (2 R P / k_n)^(1/p): the typical
        overlap at the target pressure [length]."""
        return (2.0 * self.R * self.pressure / self.k_n) ** float(1 / NORMAL_LAWS[self.effects.normal])

    @property
    def omega_0(self) -> float:
        """sqrt(k' / m), k' = dF_n / ddelta = p k_n delta_0^(p - 1): the frequency of a small disk
        on one contact at the typical overlap delta_0 [1 / time]."""
        p = float(NORMAL_LAWS[self.effects.normal])
        return math.sqrt(p * self.k_n * self.delta_0 ** (p - 1.0) / self.m)

    def physics_fields(self) -> dict:
        """Every field that enters physics (all but name and source), as JSON values."""
        fields = dataclasses.asdict(self)
        del fields["name"], fields["source"]
        fields["gamma_range"] = list(fields["gamma_range"])
        return fields
