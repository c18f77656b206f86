"""LAMMPS conventions: Figs. 5 and 7 rerun the way LAMMPS would integrate the scene.

The paper's dynamics came from LAMMPS; how is in its unavailable Supplemental Material. This
section reruns the fronts (V1, V2: Fig. 5's ensemble) and the centre-of-mass velocity (V_cm:
Fig. 7's ensemble), and the 0.062 outcome (the spectrum there and one run), with conventions
"lammps" (lever arm R - delta/2, end-of-step history increment, whole increment on first
contact: docs/physics.md) and each c LAMMPS has (1/2: nve/sphere disc; 2/5: nve/sphere). Only
the conventions and the inertia change; the tangential law stays the scene's (the smoothed law
for the paper). It says, from the numbers, whether each reading moves V1, V2, V_cm or the 0.062
outcome toward the paper.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from diskfriction.reports import analysis as A
from diskfriction.reports.registry import Need, Section
from diskfriction.reports.figures import new_figure, outcome_word
from diskfriction.reports.sections.common import MATRICES, ensemble_need, failures, fmt, run_need, table
from diskfriction.reports.sections.runs import NEEDS_ENSEMBLE
from diskfriction.scenes import Scene



@dataclass(frozen=True)
class Variant:
    """A reading of the scene: its name in the tables and the scene variant."""

    name: str
    scene: Scene


def variants(scene: Scene, settings) -> list[Variant]:
    """The scene as it is (the reading of Figs. 5 and 7), then conventions "lammps" with each
    c of settings.lammps_inertias (a variant equal to the scene itself is not repeated)."""
    base = Variant(f"{scene.effects.conventions}, c = {scene.inertia:g} (the scene)", scene)
    out = [base]
    for c in settings.lammps_inertias:
        variant = dataclasses.replace(scene, inertia=c,
                                      effects=dataclasses.replace(scene.effects, conventions="lammps"))
        if variant != scene:
            out.append(Variant(f"lammps, c = {c:g}", variant))
    return out


def variant_needs(variant: Variant, settings) -> dict[str, Need]:
    """What one reading needs, by role: the two ensembles (shared with Figs. 5 and 7 for the
    scene itself: the same cache keys), one run and the spectra of J and M^-1 J at 0.062."""
    at = A.PAPER_REAL_LOAD
    needs = {"fronts": ensemble_need(variant.scene, settings, "fronts"),
             "vcm": ensemble_need(variant.scene, settings, "vcm"),
             "run": run_need(variant.scene, settings, at)}
    needs |= {matrix: Need(f"spectra_at[{matrix}, F_x={at:g}]", "spectra_at", variant.scene,
                           {"matrix": matrix, "loads": [at]}) for matrix in MATRICES}
    return {role: dataclasses.replace(need, label=f"{need.label} {variant.name}")
            for role, need in needs.items()}


def needs(scene, settings):
    return [need for v in variants(scene, settings) for need in variant_needs(v, settings).values()]


def scaled(estimate: dict | None, unit: float) -> dict | None:
    """An Estimate dict (value, error, n) from raw to paper units; None stays None."""
    if estimate is None:
        return None
    divide = lambda v: None if v is None else v / unit  # noqa: E731
    return {"value": divide(estimate["value"]), "error": divide(estimate["error"]), "n": estimate["n"]}


@dataclass(frozen=True)
class Reading:
    """One variant's numbers in the paper's units (None where missing or failed): V1 by load,
    V2, the V_cm fit (intercept, slope) [2R/tau]; at 0.062 the complex pairs of J and
    M^-1 J (None: no equilibrium), whether a run was made (ran) and whether it slid (None: no
    run, or a run whose energy budget did not close: not resolved)."""

    V1: dict
    V2: dict | None
    intercept: dict | None
    slope: dict | None
    V_cm: dict
    pairs: dict
    ran: bool
    slid: bool | None

    @classmethod
    def of(cls, ctx, variant: Variant) -> Reading:
        get = {role: ctx.get(need.label) for role, need in variant_needs(variant, ctx.settings).items()}
        v = ctx.units.velocity
        fronts, vcm, run = get["fronts"], get["vcm"], get["run"]
        fit = None if vcm is None else vcm["V_cm_fit"]
        pairs = {m: (int(get[m]["n_complex"][0]) if get[m] is not None and get[m]["n_complex"][0] >= 0
                     else None) for m in MATRICES}
        return cls({F: scaled(fronts["V1"].get(str(float(F))), v) for F in ctx.settings.ensemble_loads}
                   if fronts else {},
                   None if fronts is None else scaled(fronts["V2"], v),
                   None if fit is None else scaled(fit["intercept"], v),
                   None if fit is None else scaled(fit["slope"], v),
                   {} if vcm is None else {float(F): scaled(e, v) for F, e in vcm["V_cm"].items()},
                   pairs, run is not None, None if run is None else run["summary"]["slid"])

    def claims_held(self) -> int | None:
        """How many of the paper's two 0.062 claims hold: J all real, the chain stays put."""
        if self.pairs["J"] is None or self.slid is None:
            return None
        return int(self.pairs["J"] == 0) + int(not self.slid)


def estimate(e: dict | None) -> str:
    if e is None or e["value"] is None:
        return "n/a"
    return fmt(e["value"]) + ("" if e["error"] is None else f" +- {e['error']:.2g}")


def outcome(r: Reading) -> str:
    J, MJ = (("n/a" if r.pairs[m] is None else str(r.pairs[m])) for m in MATRICES)
    run = outcome_word(r.slid) if r.ran else "n/a"
    return f"pairs J {J}, M^-1 J {MJ}; {run}"


def numbers_table(ctx, readings: dict[str, Reading]) -> str:
    loads = ctx.settings.ensemble_loads
    header = (["reading"] + [f"V1 at {F:g}" for F in loads]
              + ["V2", "V_cm intercept", "V_cm slope", f"at {A.PAPER_REAL_LOAD:g}"])
    rows = [[name] + [estimate(r.V1.get(F)) for F in loads]
            + [estimate(r.V2), estimate(r.intercept), estimate(r.slope), outcome(r)]
            for name, r in readings.items()]
    paper_v1 = [f"{A.PAPER_V1[round(F, 6)][0]:g}" if round(F, 6) in A.PAPER_V1 else "-" for F in loads]
    rows.append(["paper"] + paper_v1 + [f"{A.PAPER_V2:g}", f"{A.PAPER_VCM[0]:g}",
                                        f"{A.PAPER_VCM[1]:g}", "J all real; M minute (stayed)"])
    return table(header, rows)


def moves(base: Reading, r: Reading, loads) -> dict[str, str]:
    """Per quantity, whether `r` moves it toward the paper relative to `base` (A.movement)."""
    out = {f"V1 at {F:g}": A.movement(A.PAPER_V1[round(F, 6)][0], base.V1.get(F), r.V1.get(F))
           for F in loads if round(F, 6) in A.PAPER_V1}
    out["V2"] = A.movement(A.PAPER_V2, base.V2, r.V2)
    out["V_cm slope"] = A.movement(A.PAPER_VCM[1], base.slope, r.slope)
    out["V_cm intercept"] = A.movement(A.PAPER_VCM[0], base.intercept, r.intercept)
    held = (base.claims_held(), r.claims_held())
    out[f"{A.PAPER_REAL_LOAD:g} outcome"] = ("n/a" if None in held else "no change" if held[0] == held[1]
                                             else "toward" if held[1] > held[0] else "away")
    return out


def verdict(name: str, movement: dict[str, str]) -> str:
    """One sentence on one reading, from its movements."""
    groups = {kind: [q for q, m in movement.items() if m == kind]
              for kind in ("toward", "away", "no change", "n/a")}
    parts = [f"{kind} the paper: {', '.join(qs)}" if kind in ("toward", "away") else f"{kind}: {', '.join(qs)}"
             for kind, qs in groups.items() if qs]
    return f"- {name}: " + "; ".join(parts) + "."


def plot(ctx, readings: dict[str, Reading]):
    fig, (left, right) = new_figure(1, 2, figsize=(10, 4))
    for k, (name, r) in enumerate(readings.items()):
        loads = [F for F in r.V1 if r.V1[F] is not None and r.V1[F]["value"] is not None]
        left.errorbar(loads, [r.V1[F]["value"] for F in loads],
                      [r.V1[F]["error"] or 0.0 for F in loads], fmt="o-", ms=3, capsize=2,
                      color=f"C{k}", label=name)
        loads = sorted(F for F, e in r.V_cm.items() if e is not None and e["value"] is not None)
        right.errorbar(loads, [r.V_cm[F]["value"] for F in loads], [r.V_cm[F]["error"] or 0.0 for F in loads],
                       fmt="o", ms=3, capsize=2, color=f"C{k}", label=name)
        if r.slope is not None and r.slope["value"] is not None and loads:
            right.plot(loads, [r.intercept["value"] + r.slope["value"] * F for F in loads], "-",
                       lw=0.8, color=f"C{k}")
    paper = sorted(A.PAPER_V1)
    left.errorbar(paper, [A.PAPER_V1[F][0] for F in paper], [A.PAPER_V1[F][1] for F in paper],
                  fmt="kx", ms=7, capsize=2, label="paper")
    span = np.array(ctx.settings.vcm_loads)
    right.plot(span, A.PAPER_VCM[0] + A.PAPER_VCM[1] * span, "k--", lw=0.8, label="paper fit")
    left.set(xlabel="F_x [raw force]", ylabel=r"$V_1$ [$2R/\tau$]", title="Fig. 5: forward breach front")
    right.set(xlabel="F_x [raw force]", ylabel=r"$V_{cm}$ [$2R/\tau$]", title="Fig. 7: centre of mass")
    for ax in (left, right):
        ax.legend(fontsize=7)
        ax.title.set_fontsize(9)
    fig.tight_layout()
    return fig


def render(ctx):
    readings = {v.name: Reading.of(ctx, v) for v in variants(ctx.scene, ctx.settings)}
    names = list(readings)
    base = readings[names[0]]
    s = ctx.settings
    text = [ctx.figure(plot(ctx, readings), "lammps", "LAMMPS conventions: V1 (left) and V_cm "
                       "(right) against F_x for the scene's reading and conventions \"lammps\" "
                       "with each c, the paper's values in black"),
            f"Every reading keeps the scene's tangential law ({ctx.scene.resolved_effects.tangential}); "
            f"only the conventions (docs/physics.md) and c change. Ensembles as Figs. 5 and 7 "
            f"({s.realizations} realizations per load for the fronts, {s.vcm_realizations} for "
            f"V_cm, kicks of {s.kick:g}, t = {s.ensemble_t_end:g} raw); at {A.PAPER_REAL_LOAD:g}: the "
            f"complex pairs of J and M^-1 J on the branch, and whether one run "
            f"(t = {s.t_end:g} raw) slid. Velocities in 2R/tau.\n",
            numbers_table(ctx, readings),
            f"Toward the paper? Each reading against the scene's ({names[0]}): a quantity moves "
            f"toward (away from) the paper when it lies closer to (farther from) the paper's value "
            f"by more than the two standard errors combined, else no change; at "
            f"{A.PAPER_REAL_LOAD:g}, when more (fewer) of the paper's two claims hold (J all real, "
            f"the chain stays).\n"]
    text += [verdict(name, moves(base, readings[name], s.ensemble_loads)) for name in names[1:]]
    if ctx.scene.effects.conventions != "lammps" and len(names) > 2:
        text.append(f"\nThe effect of c alone, each against {names[1]} (both with LAMMPS's "
                    f"conventions):\n")
        text += [verdict(f"{name} against {names[1]}", moves(readings[names[1]], readings[name],
                                                             s.ensemble_loads))
                 for name in names[2:]]
    return "\n".join(text) + "\n" + failures(ctx)


SECTION = Section("lammps", "LAMMPS conventions", needs, render, NEEDS_ENSEMBLE)
