"""Print the derived contact kernels as a readable Python module of @numba.njit functions.

The module starts with the normal law's functions (law_functions: normal_force,
normal_stiffness, normal_energy, coulomb_limit, printed from symbolic/laws.py), which the
kernels, the assembly, the dynamics stepper and the continuation call: no other module writes
a contact law. Each kernel is printed after common-subexpression elimination (sympy.cse). The
preamble that computes rho, sqrt(delta) and u = xi / t* (t* by coulomb_limit) is written here,
and delta itself is an input
computed by the assembly (assembly_src.pair_overlap) with the care the symbols cannot express:
- delta keeps its relative accuracy when delta << 2R (see pair_overlap);
- one-sided contact rule: a contact is active iff delta > 0. At delta <= 0 the kernel writes
  zero force and zero stiffness. For Hertz this equals the limit delta -> 0+ for admissible
  histories (|xi| <= t*): every force term carries delta^(3/2) and every stiffness term
  delta^(1/2); a linear spring (Hooke) keeps its stiffness k_n up to contact.
"""
from __future__ import annotations

import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from diskfriction.symbolic import laws
from diskfriction.symbolic.contacts import ContactExprs
from diskfriction.symbolic.laws import delta
from diskfriction.symbolic.template import Dialect, render

sd = sp.Symbol("sd", positive=True)  # sqrt(delta) in the printed code

NJIT = '@numba.njit(cache=True, error_model="numpy")'
"""Every generated function: numba's numpy error model drops the zero-division checks; each
division in the kernels is by a quantity kept positive (rho, delta > 0 guarded, mu k_n delta)."""

_ARGS = {"pair": "dx, dy, delta, xi, R, k_n, k_t, mu", "wall": "delta, xi, R, k_n, k_t, mu",
         "grain": "dx, dy, delta, xi, R_i, R_j, k_n, k_t, mu"}

_RHO = ["rho = math.sqrt(dx * dx + dy * dy)"]
_PREAMBLE = {"pair": _RHO, "wall": [], "grain": _RHO}

_INCREMENT_ARGS = {"pair": "dx, dy, R, w", "wall": "R, w", "grain": "dx, dy, R_i, R_j, w"}


class _KernelPrinter(PythonCodePrinter):
    """Plain math-module Python that numba compiles: abs(), integer powers, no sympy names."""

    def _print_Abs(self, expr):
        return f"abs({self._print(expr.args[0])})"


class _OrderedPrinter(_KernelPrinter):
    """Products with their factors in one fixed order, numbers first, then ORDER, and small
    whole powers written out (delta^2 -> delta*delta): t* prints as mu*k_n*delta/k_t, the
    order the hand-written code had, so that printing the laws changed no result."""

    ORDER = ("xi", "mu", "k_n", "delta", "sd", "k_t")

    def __init__(self):
        super().__init__({"order": "none"})

    def _rank(self, factor: sp.Expr) -> int:
        base = factor.base if factor.is_Pow else factor
        return -1 if factor.is_number else (
            self.ORDER.index(base.name) if base.is_Symbol and base.name in self.ORDER else len(self.ORDER))

    def _print_Mul(self, expr):
        factors = []
        for factor in sp.Mul.make_args(expr):
            whole = factor.is_Pow and factor.exp.is_Integer and 1 < factor.exp <= 4
            factors += [factor.base] * int(factor.exp) if whole else [factor]
        return super()._print_Mul(sp.Mul(*sorted(factors, key=self._rank), evaluate=False))


def _printable(expr: sp.Expr) -> sp.Expr:
    """delta^(k/2) -> sd^k so that the printed code has only integer powers and one sqrt."""
    return sp.sympify(expr).subs(delta, sd**2)


def cse_assignments(exprs: dict[str, sp.Expr], temporary: str = "c") -> list[str]:
    """Python assignments of named outputs ('f[0]', 'J[1, 2]', ...) after common-subexpression
    elimination, the temporaries named temporary0, temporary1, ..."""
    printer = _KernelPrinter()
    names = list(exprs)
    replacements, reduced = sp.cse([exprs[n] for n in names],
                                   symbols=sp.numbered_symbols(temporary), optimizations="basic")
    lines = [f"{s} = {printer.doprint(e)}" for s, e in replacements]
    lines += [f"{name} = {printer.doprint(sp.Float(e) if e.is_number else e)}"
              for name, e in zip(names, reduced)]
    return lines


def _body(exprs: dict[str, sp.Expr]) -> tuple[list[str], set[str]]:
    """cse'd assignments for named outputs ('f[0]', 'J[1, 2]', ...) and the symbols they use."""
    printable = {n: _printable(e) for n, e in exprs.items()}
    used = {s.name for e in printable.values() for s in e.free_symbols}
    return cse_assignments(printable), used


def _kernel(c: ContactExprs, with_J: bool) -> str:
    """Source of one kernel: <kind>_contact(..., f, J) -> active, or <kind>_force(..., f)."""
    n = len(c.dofs)
    outputs = {f"f[{a}]": c.f[a] for a in range(n)}
    if with_J:
        outputs.update({f"J[{a}, {b}]": c.J[a, b] for a in range(n) for b in range(n)})
    body, used = _body(outputs)
    u = _half_powers(laws.xi / laws.coulomb_limit(c.normal))
    if "u" in used:
        used |= {s.name for s in u.free_symbols}
    active = [line for line, sym in (("sd = math.sqrt(delta)", "sd"),
                                      (f"u = {_OrderedPrinter().doprint(u)}", "u")) if sym in used]
    name = f"{c.kind}_{'contact' if with_J else 'force'}"
    outs = "f, J" if with_J else "f"
    what = "f and the total stiffness block J = -(df/dq + df/dxi w^T)" if with_J else "f"
    zero = ["f[:] = 0.0"] + (["J[:, :] = 0.0"] if with_J else [])
    lines = [
        NJIT,
        f"def {name}({_ARGS[c.kind]}, {outs}):",
        f'    """{c.kind} contact, law {c.law!r}, normal law {c.normal!r}: writes {what}',
        f"    over the local dofs {', '.join(c.dofs)}. Returns 1 if active (delta > 0), else 0.\"\"\"",
        *[f"    {line}" for line in _PREAMBLE[c.kind]],
        "    if not delta > 0.0:",
        *[f"        {line}" for line in zero],
        "        return 0",
        *[f"    {line}" for line in active + body],
        "    return 1",
    ]
    return "\n".join(lines) + "\n"


LAWS = {
    "normal_force": (laws.normal_force, "k_n", "F_n(delta) [force]"),
    "normal_stiffness": (laws.normal_stiffness, "k_n", "dF_n / ddelta [force / length]"),
    "normal_energy": (laws.normal_energy, "k_n",
                      "U_n(delta), the integral of F_n from first contact [energy]"),
    "coulomb_limit": (laws.coulomb_limit, "k_n, k_t, mu",
                      "t*(delta), the Coulomb limit of the history, |F_t(t*)| = mu F_n [length]"),
}
"""The functions of the normal law printed into every kernel module: name -> (its expression
in symbolic/laws.py, the parameters after delta, what it returns)."""


def _half_powers(expr: sp.Expr) -> sp.Expr:
    """delta^(n/2) with n odd -> delta^((n-1)/2) sd: one square root and integer powers, and
    delta itself kept where the power is whole (so that t* = mu k_n delta / k_t is not
    computed from sd^2)."""
    return sp.sympify(expr).replace(
        lambda e: e.is_Pow and e.base == delta and e.exp.is_Rational and e.exp.q == 2,
        lambda e: delta ** (e.exp - sp.Rational(1, 2)) * sd)


def law_functions(normal: str) -> str:
    """Source of the functions of LAWS for the normal law `normal`, each (delta, parameters) ->
    value for delta >= 0; numba compiles them for an array of delta too (np.sqrt), as
    System.coulomb_limit calls coulomb_limit."""
    printer = _OrderedPrinter()
    parts = []
    for name, (law, args, what) in LAWS.items():
        expr = _half_powers(law(normal))
        lines = [NJIT, f"def {name}(delta, {args}):",
                 f'    """{what}:',
                 f'    {law(normal)} ({normal}, symbolic/laws.py)."""']
        if sd in expr.free_symbols:
            lines.append("    sd = np.sqrt(delta)")
        lines.append(f"    return {printer.doprint(expr)}")
        parts.append("\n".join(lines) + "\n")
    return "\n\n".join(parts)


def _increment_coeffs(c: ContactExprs) -> str:
    """Source of <kind>_increment_coeffs: w with d xi = w . dq over the local dofs."""
    printer = _KernelPrinter()
    lines = [NJIT, f"def {c.kind}_increment_coeffs({_INCREMENT_ARGS[c.kind]}):",
             f'    """d xi = w . dq over the local dofs {", ".join(c.dofs)}."""']
    lines += [f"    {line}" for line in _PREAMBLE[c.kind]]
    lines += [f"    w[{a}] = {printer.doprint(e)}" for a, e in enumerate(c.w)]
    return "\n".join(lines) + "\n"


def _kernels(c: ContactExprs) -> list[str]:
    """The three functions of one contact kernel: with J, force only, increment coefficients."""
    return [_kernel(c, True), _kernel(c, False), _increment_coeffs(c)]


def module_source(contacts: list[ContactExprs], dialect: Dialect, header: str,
                  sources: list[str]) -> str:
    """The whole generated module: header, the flags (D, <KIND>_FRICTION for each contact
    kind), the normal law's functions, the kernels of `contacts`, then the assembly `sources`
    rendered for the dialect (symbolic/template.py)."""
    parts = [
        header,
        "import math\n\nimport numba\nimport numpy as np\n",
        f"D = {3 if dialect.rotation else 2}  # degrees of freedom per disk",
        *[f"{c.kind.upper()}_FRICTION = {c.law != 'none'}" for c in contacts],
        f"CONVENTIONS = {dialect.conventions!r}  # docs/physics.md, Conventions\n\n",
        law_functions(contacts[0].normal),
        *[text for c in contacts for text in _kernels(c)],
        *[render(source, dialect) for source in sources],
    ]
    return "\n\n".join(p.rstrip("\n") + "\n" for p in parts)
