"""The report's parameters (loads, step sizes, run lengths), one frozen dataclass.

Raw units (docs/model.md#units) for every value; `--set KEY=VALUE` on the command line changes one
(tuples as comma-separated lists). A changed setting changes the cache key of exactly the
computations that take it.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Settings:
    # the paper's loads (docs/model.md#targets, Fig. 2 and 5): spectra at exactly these F_x
    loads: tuple[float, ...] = (0.03, 0.04, 0.062, 0.083, 0.087, 0.090)
    ds_divisions: int = 60  # sweeps: ds_max = span / ds_divisions (continuation's default)
    # Fig. 6: the state the shear mode is taken at, and the pre-compressed reading shown beside it
    mode_F_x: float = 0.087
    mode_eps: float = 1e-5
    # readings (the ambiguous ones of docs/model.md#stability)
    inertias: tuple[float, ...] = (0.4, 0.5, 1.0, 4.0)
    eps_values: tuple[float, ...] = (0.0, 1e-5, 1e-4)
    # accuracy against cost
    accuracy_divisions: tuple[int, ...] = (15, 30, 60, 120, 240)
    accuracy_tol_p: tuple[float, ...] = (1e-6, 1e-8, 1e-10)
    reference_divisions: int = 960
    reference_tol_p: float = 1e-12
    jacobian_F_x: float = 0.087
    jacobian_steps: tuple[float, ...] = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11)
    dt_fractions: tuple[float, ...] = (0.4, 0.2, 0.1, 0.05)
    reference_dt_fraction: float = 0.0125
    dynamics_accuracy_F_x: float = 0.083
    dynamics_accuracy_t_end: float = 300.0
    # single runs (Figs. 3, 4, 7 upper): start from the branch point plus a seeded random
    # velocity kick of this amplitude [2R / raw time]
    fig3_loads: tuple[float, ...] = (0.03, 0.04, 0.062, 0.083)
    t_end: float = 1000.0
    kick: float = 1e-6
    seed: int = 0
    fig4_F_x: float = 0.083
    fig4_disk: int = 4
    fig7_F_x: float = 0.087
    # ensembles (Fig. 5, Fig. 7 lower)
    ensemble_loads: tuple[float, ...] = (0.083, 0.087, 0.090)
    realizations: int = 25
    ensemble_t_end: float = 1000.0
    vcm_loads: tuple[float, ...] = (0.083, 0.087, 0.090, 0.095, 0.10, 0.11)
    vcm_realizations: int = 5
    # LAMMPS conventions: Figs. 5 and 7 rerun with conventions "lammps" and these c (LAMMPS's
    # nve/sphere disc and nve/sphere)
    lammps_inertias: tuple[float, ...] = (0.5, 0.4)


ZERO_ALLOWED = ("eps_values", "mode_eps", "seed", "kick", "mode_F_x")
"""Settings that may be 0; every other number must be > 0."""


class SettingError(ValueError):
    pass


def _convert(text: str, kind, name: str):
    try:
        if kind is int:
            return int(text)
        value = float(text)
    except ValueError:
        raise SettingError(f"--set {name}: expected {kind.__name__} (got {text!r})") from None
    if not math.isfinite(value):
        raise SettingError(f"--set {name}: must be finite (got {text!r})")
    return value


def with_setting(settings: Settings, assignment: str) -> Settings:
    """settings with KEY=VALUE applied; SettingError (one line) on an unknown key or bad value."""
    name, sep, text = assignment.partition("=")
    name = name.strip()
    fields = {f.name: f for f in dataclasses.fields(Settings)}
    if not sep or name not in fields:
        raise SettingError(f"--set: expected KEY=VALUE with KEY one of {', '.join(fields)} "
                           f"(got {assignment!r})")
    current = getattr(settings, name)
    if isinstance(current, tuple):
        kind = type(current[0]) if current else float
        parts = [p for p in text.split(",") if p.strip()]
        if not parts:
            raise SettingError(f"--set {name}: empty list (got {text!r})")
        value = tuple(_convert(p.strip(), kind, name) for p in parts)
    else:
        value = _convert(text.strip(), type(current), name)
    values = value if isinstance(value, tuple) else (value,)
    allow_zero = name in ZERO_ALLOWED
    if any(v < 0 or (v == 0 and not allow_zero) for v in values):
        raise SettingError(f"--set {name}: must be {'>= 0' if allow_zero else '> 0'} (got {text!r})")
    return dataclasses.replace(settings, **{name: value})
