"""Any problem from sympy expressions: G(u, p), its exact derivatives and the tracked matrix,
printed as numba kernels into a cached module, as the disks' contact kernels are.

From G (n expressions in the state symbols u_0..u_(n-1), the parameter p and constants c_k),
sympy derives dG/du = G.jacobian(u) and dG/dp; the tracked matrix A (m x m) defaults to dG/du.
Every symbol is renamed (u[i] -> u_i, p -> p, constant k -> c_k: any sympy name works, even a
Python keyword) and each function is printed after cse (codegen.cse_assignments) as

    @numba.njit(cache=True, error_model="numpy")
    def residual(u, p, c, out): ...     # out (n,)     <- G
    def jacobian(u, p, c, out): ...     # out (n, n)   <- dG/du
    def dG_dp(u, p, c, out): ...        # out (n,)     <- dG/dp
    def stability(u, p, c, out): ...    # out (m, m)   <- A

The constants are an argument, so one module serves every value of them. The module is keyed
by sha256 of the expressions (srepr) and of this generator's sources, written to the cache's
kernels/problem_<hash>.py with its content hash, imported, warmed up and repaired when damaged
(generated.load_generated): a second run with the same expressions compiles nothing.
numba's error model is numpy's: a division by zero gives inf or nan (the front end refuses
non-finite values at the start), never an exception.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass
from types import ModuleType
from typing import Mapping, Optional, Sequence

import numpy as np
import sympy as sp

from diskfriction.files import source_digest
from diskfriction.symbolic.codegen import NJIT, cse_assignments
from diskfriction.symbolic.generated import Progress, load_generated
from diskfriction.symbolic.kernels import cache_dir

Array = np.ndarray
_SOURCES = tuple(f"diskfriction.symbolic.{name}" for name in ("problems", "codegen", "generated"))
FUNCTIONS = ("residual", "jacobian", "dG_dp", "stability")


@dataclass(frozen=True)
class Expressions:
    """The four functions of a problem in renamed symbols (module docstring): G, dG/du, dG/dp
    (sympy column matrices / matrices), A (m x m), and the original constants in the order
    of the kernels' argument c."""

    G: sp.Matrix
    G_u: sp.Matrix
    G_p: sp.Matrix
    A: sp.Matrix
    constants: tuple[sp.Symbol, ...]

    def key(self) -> str:
        """sha256 (16 hex digits) of the expressions and the generator's sources."""
        text = "|".join(sp.srepr(e) for e in (self.G, self.A)) + "|" + source_digest(_SOURCES)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def derive(G: Sequence, u: Sequence, p: sp.Symbol, A=None,
           constants: Sequence[sp.Symbol] = ()) -> Expressions:
    """dG/du and dG/dp of G, A (default dG/du), all renamed. ValueError if G and u differ in
    length, A is not square, or an expression holds a symbol that is none of u, p, constants."""
    u = list(u)
    G = sp.Matrix(list(G))
    if G.shape[0] != len(u) or not u:
        raise ValueError(f"G has {G.shape[0]} expressions for {len(u)} state symbols")
    G_u = G.jacobian(u)
    A = G_u if A is None else sp.Matrix(A)
    if A.shape[0] != A.shape[1]:
        raise ValueError(f"A must be square, got shape {A.shape}")
    known = set(u) | {p} | set(constants)
    stray = sorted(str(s) for s in (G.free_symbols | A.free_symbols) - known)
    if stray:
        raise ValueError(f"no value given for the symbols {', '.join(stray)}")
    names = {s: sp.Symbol(f"u_{i}") for i, s in enumerate(u)}
    names[p] = sp.Symbol("p")
    names.update({s: sp.Symbol(f"c_{k}") for k, s in enumerate(constants)})
    rename = lambda M: M.xreplace(names)  # noqa: E731
    return Expressions(rename(G), rename(G_u), rename(G.diff(p)), rename(A), tuple(constants))


def _function(name: str, M: sp.Matrix, what: str, n: int, c: int) -> str:
    """Source of one kernel writing the matrix (or column) M into out."""
    vector = M.shape[1] == 1
    outputs = {(f"out[{i}]" if vector else f"out[{i}, {j}]"): M[i, j]
               for i in range(M.shape[0]) for j in range(M.shape[1]) if M[i, j] != 0}
    unpack = [f"u_{i} = u[{i}]" for i in range(n)] + [f"c_{k} = c[{k}]" for k in range(c)]
    lines = [NJIT, f"def {name}(u, p, c, out):", f'    """Writes {what} into out."""',
             "    out[:] = 0.0" if vector else "    out[:, :] = 0.0",
             *[f"    {line}" for line in unpack + cse_assignments(outputs, "t")]]
    return "\n".join(lines) + "\n"


def module_source(e: Expressions, key: str) -> str:
    """The generated module: header, the four kernels, warm_up."""
    n, m, c = e.G.shape[0], e.A.shape[0], len(e.constants)
    header = (f'"""diskfriction generated problem kernels. Do not edit: regenerated from '
              f'symbolic/problems.py.\n\nhash: {key}\nstate: u_0..u_{n - 1}; constants: '
              f'{", ".join(f"c_{k} = {s}" for k, s in enumerate(e.constants)) or "none"}\n"""')
    parts = [header, "import math\n\nimport numba\nimport numpy as np\n",
             f"N = {n}  # state size\nM = {m}  # size of the tracked matrix\nC = {c}  # constants\n",
             _function("residual", e.G, "G(u, p)", n, c),
             _function("jacobian", e.G_u, "dG/du", n, c),
             _function("dG_dp", e.G_p, "dG/dp", n, c),
             _function("stability", e.A, "the tracked matrix A", n, c),
             "def warm_up(progress=None):\n"
             '    """Call every kernel once (compiles it or loads numba\'s cache)."""\n'
             "    u, c = np.zeros(N), np.zeros(C)\n"
             "    for k, (f, out) in enumerate(((residual, np.empty(N)), (jacobian, np.empty((N, N))),\n"
             "                                  (dG_dp, np.empty(N)), (stability, np.empty((M, M))))):\n"
             "        f(u, 0.0, c, out)\n"
             "        if progress is not None:\n"
             "            progress((k + 1) / 4)\n"]
    return "\n\n".join(part.rstrip("\n") + "\n" for part in parts)


@dataclass(frozen=True)
class ProblemKernels:
    """The compiled functions of one problem with its constants bound: residual(u, p) (n,),
    jacobian(u, p) (n, n), dG_dp(u, p) (n,), stability(u, p) (m, m)."""

    module: ModuleType
    constants: Array

    def _call(self, kernel, shape, u, p) -> Array:
        out = np.empty(shape)
        kernel(np.asarray(u, dtype=float), float(p), self.constants, out)
        return out

    def residual(self, u, p) -> Array:
        return self._call(self.module.residual, (self.module.N,), u, p)

    def jacobian(self, u, p) -> Array:
        return self._call(self.module.jacobian, (self.module.N, self.module.N), u, p)

    def dG_dp(self, u, p) -> Array:
        return self._call(self.module.dG_dp, (self.module.N,), u, p)

    def stability(self, u, p) -> Array:
        return self._call(self.module.stability, (self.module.M, self.module.M), u, p)


def compile_problem(G: Sequence, u: Sequence, p: sp.Symbol, A=None,
                    values: Optional[Mapping[sp.Symbol, float]] = None,
                    progress: Optional[Progress] = None) -> ProblemKernels:
    """The cached, compiled kernels of the problem (module docstring), the constants bound to
    `values` ({symbol: number}; every free symbol other than u and p needs one)."""
    values = dict(values or {})
    clash = [str(s) for s in values if s in set(u) or s == p]
    if clash:
        raise ValueError(f"values given for state or parameter symbols: {', '.join(clash)}")
    constants = tuple(sorted(values, key=str))
    e = derive(G, u, p, A, constants)
    key = e.key()
    module = load_generated(cache_dir() / f"problem_{key}.py", f"diskfriction_problem_{key}",
                            lambda: module_source(e, key), progress)
    return ProblemKernels(module, np.array([float(values[s]) for s in constants]))
