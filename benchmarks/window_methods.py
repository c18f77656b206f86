"""Every eigenvalue in a spectral window at 1024 disks: the window's shift-invert samples
captured from a sheared packing, then solved again by several methods on one core, at equal
accuracy; and a pseudospectral bound that would skip a step's samples
(docs/notes/packings-window-methods.md).

capture: shears a prepared packing (PackingScene(N, seed), defaults otherwise, spectra "full";
  plastic events passed) with the scans inline (workers 0) and the spectral window (LO, HI),
  and records every call of the window's sampling function (window.window_eigensystem, wrapped
  here, the core untouched): the matrix it shift-inverts with vectors (A_g and its deflation
  nearest.Deflated: B = M^-1 J with the loose disks parked, the null spaces and maps) or
  without (A_red), A_red, A_g's spectrum matrix, the mass diagonal M, the window (lo, hi,
  sigma, k), gamma, the committed state's key and the eigenvalues the window returned; one
  .npz per call under --cache/N{N}_s{seed}_w{LO}:{HI} (gitignored), up to --count calls or
  gamma = --gamma-end. The dense eigenvalues of A_red (the reference) are computed when first
  needed and cached beside (.dense.npy).
compare: --stretches runs of --length consecutive captured problems (warm starts carry along a
  run), spread over the capture; each method times each problem in turn, the order rotating
  from problem to problem, BLAS on one thread:
  arpack         the window's own sample (window.window_eigensystem: one real LU, ARPACK on
                 both sides, two-sided Rayleigh-Ritz);
  contour        the contour filter (continuation/spectra/contour.py) on the circle of
                 CONTOUR_SCALE times the window's reach about its centre, CONTOUR_NODES nodes,
                 CONTOUR_SIZE k columns, residuals to CONTOUR_TOL, started from the previous
                 problem's bases;
  contour-1e-10  the same stopped at residuals of 1e-10 ||A||_1;
  slepc          SLEPc's two-sided Krylov-Schur shift-invert on A_red (PETSc's LU), started from
                 the previous problem's vectors (a subprocess per problem, timed inside it, with
                 Debian's python3-slepc4py-real or --slepc-python).
  Per problem: seconds, the eigenvalues found in the window's disc (|lambda - sigma| < reach,
  the disc SpectralWindow's certificate covers) against the dense ones (count, largest
  distance), the largest residual ||A r - lambda r|| and ||l^H A - lambda l^H|| over
  ||A||_1 (unit vectors). Then per method the median and mean seconds, the median of ARPACK's
  time over the method's, and the accuracy against BOUND.
pseudo: gamma-adjacent captured samples of one committed state: whether sigma_min(A - z I) on a
  circle about each real eigenvalue of the band exceeds ||A_b - A_a||_2 (no eigenvalue can leave
  the real axis in the step), first order (rho / kappa) on every step and by inverse iteration
  on --rigorous steps, and what the bound costs against a window sample.

Run: python benchmarks/window_methods.py capture [--N 1024] [--lo=-3 --hi 2] [--count 800] [--gamma-end 1e-3]
     python benchmarks/window_methods.py compare [--lo=-3 --hi 2] [--methods arpack,contour,contour-1e-10,slepc]
                                                 [--stretches 4 --length 10] [--repeat 1]
     python benchmarks/window_methods.py pseudo [--steps 40 --rigorous 6]
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

CACHE = Path(__file__).resolve().parent / "cache" / "window_methods"


def _sparse_parts(name: str, M) -> dict:
    import scipy.sparse as sp
    M = sp.csr_array(M)
    return {f"{name}_data": M.data, f"{name}_indices": M.indices, f"{name}_indptr": M.indptr,
            f"{name}_shape": np.array(M.shape)}


def _sparse(z, name: str):
    import scipy.sparse as sp
    return sp.csr_array((z[f"{name}_data"], z[f"{name}_indices"], z[f"{name}_indptr"]),
                        shape=tuple(z[f"{name}_shape"]))


# ---------------------------------------------------------------- capture

def capture(args, folder: Path) -> None:
    from diskfriction.continuation.spectra import window as window_module
    from diskfriction.models.packing.prepared import prepare_scene
    from diskfriction.models.packing.shear import ShearParams, shear
    from diskfriction.scenes.packing import PackingScene

    folder.mkdir(parents=True, exist_ok=True)
    for old in folder.glob("p*.npz"):
        old.unlink()
    context = {}
    count = [0]
    original_eigensystem = window_module.SpectralWindow.eigensystem
    original_sample = window_module.window_eigensystem

    class Enough(Exception):
        pass

    def eigensystem(self, problem, u, p, vectors=False):
        context.update(problem=problem, u=u, p=p)
        return original_eigensystem(self, problem, u, p, vectors)

    def sample(A, window, vectors, deflated=None):
        start = time.perf_counter()
        found = original_sample(A, window, vectors, deflated)
        seconds = time.perf_counter() - start
        problem, u, p = context["problem"], context["u"], context["p"]
        structure = problem.stability_structure(u, p)
        parts = dict(vectors=vectors, lo=window.lo, hi=window.hi, k=window.k, sigma=window.sigma,
                     gamma=p, q=u, mass=problem.mass, kept=structure.kept, values=found.values,
                     seconds=seconds, committed=np.frombuffer(getattr(problem, "_key", b""), np.uint8))
        parts.update(_sparse_parts("A", A))
        parts.update(_sparse_parts("coupled", structure.coupled))
        parts.update(_sparse_parts("spectrum", structure.spectrum_matrix))
        if deflated is not None:
            parts.update(_sparse_parts("B", deflated.matrix))
            parts.update(_sparse_parts("right_map", deflated.right_map))
            parts.update(_sparse_parts("left_map", deflated.left_map))
            parts.update(right_null=deflated.right_null, left_null=deflated.left_null)
        np.savez_compressed(folder / f"p{count[0]:04d}.npz", **parts)
        count[0] += 1
        print(f"  {count[0]:4d} gamma = {p:.6e} vectors {int(vectors)} k {window.k} "
              f"n {A.shape[0]} {seconds:.2f} s", flush=True)
        if count[0] >= args.count:
            raise Enough
        return found

    window_module.SpectralWindow.eigensystem = eigensystem
    window_module.window_eigensystem = sample
    extra = {"spectra": "full"} if "spectra" in PackingScene.__dataclass_fields__ else {}
    scene = PackingScene(N=args.N, seed=args.seed, gamma_range=(0.0, args.gamma_end), **extra)
    start = time.perf_counter()
    packing = prepare_scene(scene)
    print(f"prepared {args.N} disks in {time.perf_counter() - start:.1f} s", flush=True)
    try:
        shear(scene, packing, ShearParams(workers=0), plastic_events=1000, window=(args.lo, args.hi))
    except Enough:
        pass
    print(f"captured {count[0]} samples in {time.perf_counter() - start:.1f} s", flush=True)


def dense_values(path: Path) -> np.ndarray:
    """The dense eigenvalues of the captured state's A_red (one BLAS thread), cached beside the
    problem (.dense.npy)."""
    from diskfriction.continuation.linalg.solves import blas_threads
    cached = path.with_suffix(".dense.npy")
    if cached.exists():
        return np.load(cached)
    with np.load(path) as z, blas_threads():
        values = np.linalg.eigvals(_sparse(z, "coupled").toarray())
    np.save(cached, values)
    return values


# ---------------------------------------------------------------- problems

class Problem:
    """One captured window sample: the matrix the window takes (A), its deflation, the window."""

    def __init__(self, path: Path):
        from diskfriction.continuation.spectra.nearest import Deflated
        from diskfriction.continuation.spectra.window import SpectralWindow
        self.path = path
        with np.load(path) as z:
            self.vectors = bool(z["vectors"])
            self.gamma = float(z["gamma"])
            self.window = SpectralWindow(float(z["lo"]), float(z["hi"]), int(z["k"]))
            self.A = _sparse(z, "A")
            self.coupled = _sparse(z, "coupled")
            self.committed = bytes(z["committed"])
            self.captured = z["values"]
            self.deflated = None
            if "B_data" in z:
                self.deflated = Deflated(_sparse(z, "B"), z["right_null"], z["left_null"],
                                         _sparse(z, "right_map"), _sparse(z, "left_map"))
        self.norm = float(abs(self.A).sum(axis=0).max())

    @property
    def dense(self) -> np.ndarray:
        return dense_values(self.path)


def problems(folder: Path, stretches: int, length: int) -> list[list[Path]]:
    """`stretches` runs of `length` consecutive captured samples, spread evenly over them."""
    paths = sorted(folder.glob("p*[0-9].npz"))
    if not paths:
        sys.exit(f"no captured problems in {folder}: run the capture first")
    length = min(length, len(paths))
    starts = np.linspace(0, len(paths) - length, stretches).round().astype(int)
    return [paths[a:a + length] for a in np.unique(starts)]


class Found:
    """A method's answer: eigenvalues, right vectors (columns), left vectors (rows l^H), the
    seconds, and what the method counts (iterations, solves)."""

    def __init__(self, values, right, left, seconds, **counts):
        self.values, self.right, self.left, self.seconds, self.counts = values, right, left, seconds, counts


def residual(problem: Problem, values, right, left) -> float:
    """max over the pairs of ||A r - lambda r|| / ||r|| and ||l^H A - lambda l^H|| / ||l||, over
    ||A||_1."""
    if values.size == 0:
        return 0.0
    A = problem.A
    r = right / np.linalg.norm(right, axis=0)
    worst = np.linalg.norm(A @ r - r * values, axis=0).max()
    if left is not None:
        lh = left / np.linalg.norm(left, axis=1)[:, None]
        worst = max(worst, np.linalg.norm((A.T @ lh.T).T - lh * values[:, None], axis=1).max())
    return float(worst / problem.norm)


def run_arpack(problem: Problem, state: dict) -> Found:
    from diskfriction.continuation.spectra.window import window_eigensystem
    start = time.perf_counter()
    found = window_eigensystem(problem.A, problem.window, problem.vectors, problem.deflated)
    seconds = time.perf_counter() - start
    return Found(found.values, found.right, found.left, seconds)


CONTOUR_NODES = 8
"""Trapezoid nodes on the contour (four complex factorizations: its conjugate pairs)."""
CONTOUR_SCALE = 1.1
"""The contour's radius over the window's reach."""
CONTOUR_SIZE = 1.5
"""The filtered subspace's size over the window's k."""
BOUND = 2e-15
"""The accuracy every method must reach: the largest residual of an eigenpair in the window's
disc, relative to ||A||_1 (about 1.5e-10 absolute for 1024 disks); ARPACK's after its
Rayleigh-Ritz projection lies below it (printed)."""
CONTOUR_TOL = 1e-15
"""The contour iteration's residual bound, relative to ||A||_1 (at most BOUND)."""


def run_contour(problem: Problem, state: dict, tol: float = CONTOUR_TOL) -> Found:
    from diskfriction.continuation.spectra.contour import Circle, contour_eigensystem
    window = problem.window
    start = time.perf_counter()
    previous = state.get("values", np.zeros(0, complex))
    basis = state.get("basis")
    reach = window.reach(previous)
    iterations = solves = 0
    while True:
        circle = Circle(window.sigma, CONTOUR_SCALE * reach, CONTOUR_NODES)
        size = min(problem.A.shape[0] - 1, round(CONTOUR_SIZE * window.k))
        found = contour_eigensystem(problem.A, circle, size, start=basis and basis[0],
                                    left_start=basis and basis[1], tol=tol,
                                    deflated=problem.deflated, within=reach)
        iterations, solves = iterations + found.iterations, solves + found.solves
        basis = (found.basis, found.left_basis)
        if window.reach(found.values) <= reach:
            break
        reach = window.reach(found.values)  # a pair with a larger |Im| in the band: widen
    seconds = time.perf_counter() - start
    state.update(values=found.values, basis=basis)
    return Found(found.values, found.right, found.left, seconds, iterations=iterations, solves=solves,
                 certified=found.certified)


METHODS = {"arpack": run_arpack, "contour": run_contour,
           "contour-1e-10": lambda problem, state: run_contour(problem, state, 1e-10)}
"""The methods by name; contour-1e-10: the contour iteration stopped at residuals of 1e-10 ||A||_1
(its eigenvalues still agree with the dense ones to their rounding: printed)."""


def compare(args, folder: Path) -> None:
    from diskfriction.continuation.linalg.solves import blas_threads
    methods = args.methods.split(",")
    for name in methods:
        if name not in METHODS and name != "slepc":
            sys.exit(f"unknown method {name!r} ({', '.join(METHODS)}, slepc)")
    if "slepc" in methods:
        runner = slepc_runner(args)
        if runner is None:
            methods.remove("slepc")
        else:
            METHODS["slepc"] = runner
    stretches = problems(folder, args.stretches, args.length)
    for stretch in stretches:  # the dense references first, outside the timed loop
        for path in stretch:
            dense_values(path)
    print(f"{sum(map(len, stretches))} problems in {len(stretches)} stretches from {folder}; "
          f"load average {open('/proc/loadavg').read().split()[0]} at the start")
    rows = {name: [] for name in methods}
    header = f"{'problem':>8} {'gamma':>12} {'k':>4} {'disc':>4}"
    for name in methods:
        header += f" | {name:>8} {'s':>7} {'found':>5} {'err':>7} {'resid':>7}"
    print(header)
    with blas_threads():
        turn = 0
        for stretch in stretches:
            states = {name: {} for name in methods}
            for path in stretch:
                problem = Problem(path)
                dense = problem.dense
                order = methods[turn % len(methods):] + methods[:turn % len(methods)]
                turn += 1
                answers = {}
                for name in order:
                    times = []
                    for r in range(args.repeat):  # warm starts from the previous problem's state
                        state = dict(states[name])
                        answers[name] = METHODS[name](problem, state)
                        times.append(answers[name].seconds)
                    states[name] = state
                    answers[name].seconds = float(np.median(times))
                reach = problem.window.reach(answers[methods[0]].values)
                disc = dense[np.abs(dense - problem.window.sigma) < reach]
                line = f"{path.stem:>8} {problem.gamma:12.6e} {problem.window.k:4d} {disc.size:4d}"
                for name in methods:
                    a = answers[name]
                    near = np.abs(a.values - problem.window.sigma) < reach
                    err = _distance(disc, a.values[near])
                    res = residual(problem, a.values[near], a.right[:, near],
                                   None if a.left is None else a.left[near])
                    rows[name].append((a.seconds, near.sum() == disc.size, err, res, a.counts))
                    line += f" | {'':>8} {a.seconds:7.3f} {int(near.sum()):5d} {err:7.1e} {res:7.1e}"
                print(line, flush=True)
    print()
    base = np.array([r[0] for r in rows[methods[0]]])
    for name in methods:
        seconds = np.array([r[0] for r in rows[name]])
        same = sum(r[1] for r in rows[name])
        err = max(r[2] for r in rows[name])
        res = max(r[3] for r in rows[name])
        extra = ""
        its = [r[4]["iterations"] for r in rows[name] if "iterations" in r[4]]
        if its:
            extra = f"; iterations median {np.median(its):g}, max {max(its)}"
        if any("certified" in r[4] for r in rows[name]):
            extra += f"; certified {sum(r[4].get('certified', False) for r in rows[name])}/{len(rows[name])}"
        print(f"{name:>8}: median {np.median(seconds) * 1e3:.1f} ms, mean {seconds.mean() * 1e3:.1f} ms; "
              f"{methods[0]} / {name} median of ratios {np.median(base / seconds):.2f}; the disc's "
              f"eigenvalues found {same}/{len(seconds)}, largest error {err:.1e} (over ||A||_1: "
              f"{err / Problem(stretches[0][0]).norm:.1e}), largest residual {res:.1e} "
              f"({'within' if res <= BOUND else 'above'} the bound {BOUND:g}){extra}")


def _distance(reference: np.ndarray, found: np.ndarray) -> float:
    """The largest distance of a reference eigenvalue from its match among `found` (optimal
    one-to-one matching; inf where the counts differ)."""
    from scipy.optimize import linear_sum_assignment
    if reference.size != found.size:
        return float("inf")
    if reference.size == 0:
        return 0.0
    cost = np.abs(reference[:, None] - found[None, :])
    rows, cols = linear_sum_assignment(cost)
    return float(cost[rows, cols].max())


SLEPC_PATHS = ("/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real/lib/python3/dist-packages",
               "/usr/lib/slepcdir/slepc3.18/x86_64-linux-gnu-real/lib/python3/dist-packages")
"""Where Debian bookworm's python3-slepc4py-real puts petsc4py and slepc4py (pip could not
build them: docs/notes/packings-window-methods.md)."""


SLEPC_TOL = 1e-13
"""SLEPc's stopping tolerance (relative to |lambda|, its default convergence test): at ARPACK's
1e-10 (nearest.ARPACK_TOL) its residuals reach 2e-13 ||A||_1, above the common bound (BOUND),
and at 1e-12 up to 2.8e-15; at 1e-13 they are below it, for one more restart."""


def slepc_runner(args):
    """run_slepc for the Python `args.slepc_python` (with slepc4py; default: Debian's python3 with
    SLEPC_PATHS), one subprocess per problem (timed inside it); warm starts through a file. None
    where that Python has no slepc4py."""
    import subprocess
    import tempfile
    python = args.slepc_python or "/usr/bin/python3"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(SLEPC_PATHS), OMP_NUM_THREADS="1",
               OPENBLAS_NUM_THREADS="1")
    try:
        missing = subprocess.run([python, "-c", "import slepc4py, petsc4py"], env=env,
                                 capture_output=True).returncode
    except OSError:
        missing = True
    if missing:
        print(f"slepc left out: {python} cannot import slepc4py and petsc4py", flush=True)
        return None
    scratch = Path(tempfile.mkdtemp(prefix="slepc-"))

    def run_slepc(problem: Problem, state: dict) -> Found:
        out = scratch / f"{problem.path.stem}.npz"
        start = state.get("start", "")
        subprocess.run([python, __file__, "slepc-worker", str(problem.path), start, str(out)], env=env,
                       check=True)
        with np.load(out) as z:
            found = Found(z["values"], z["right"], _paired(problem.A, z["values"], z["left"]),
                          float(z["seconds"]), iterations=int(z["its"]), solves=int(z["solves"]))
        state["start"] = str(out)
        return found
    return run_slepc


def _paired(A, values: np.ndarray, left: np.ndarray) -> np.ndarray:
    """SLEPc's left vectors (rows) each given to the member of its complex pair it belongs to:
    a real PETSc build returns y with y^T A = lambda y^T for some pairs and for the conjugate
    lambda for others; the row or its conjugate, whichever has the smaller residual (untimed)."""
    fixed = left.copy()
    for i in np.flatnonzero(values.imag != 0):
        row = left[i]
        if (np.linalg.norm(A.T @ row.conj() - values[i] * row.conj())
                < np.linalg.norm(A.T @ row - values[i] * row)):
            fixed[i] = row.conj()
    return fixed


def slepc_worker(path: str, start: str, out: str) -> None:
    """SLEPc's Krylov-Schur, two-sided, shift-invert at the window's sigma (PETSc's own sparse
    LU) for the window's k eigenvalues nearest sigma of A_red (the captured coupled matrix: PETSc
    takes no projected operator), to ARPACK's tolerance and Krylov size (nearest.py), started from
    the sums of the previous problem's right and of its left vectors where `start` names its
    output (a Krylov method takes one start vector). Writes
    values, vectors embedded in A's coordinates (kept dofs), seconds of setUp + solve."""
    import slepc4py
    slepc4py.init(sys.argv[:1])
    from petsc4py import PETSc
    from slepc4py import SLEPc
    with np.load(path) as z:
        n = int(z["coupled_shape"][0])
        mat = PETSc.Mat().createAIJ(size=(n, n), csr=(z["coupled_indptr"].astype(PETSc.IntType),
                                                      z["coupled_indices"].astype(PETSc.IntType),
                                                      z["coupled_data"]))
        k, sigma, kept, N = int(z["k"]), float(z["sigma"]), z["kept"], int(z["A_shape"][0])
    mat.assemble()
    eps = SLEPc.EPS().create()
    eps.setOperators(mat)
    eps.setProblemType(SLEPc.EPS.ProblemType.NHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setTwoSided(True)
    eps.setDimensions(nev=k, ncv=min(n, max(20, min(2 * k + 1, k + 60))))
    eps.setTarget(sigma)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTolerances(tol=float(os.environ.get("SLEPC_TOL", SLEPC_TOL)), max_it=10000)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    ksp = st.getKSP()
    ksp.setType(PETSc.KSP.Type.PREONLY)
    ksp.getPC().setType(PETSc.PC.Type.LU)
    if start and os.path.exists(start):
        with np.load(start) as z:
            r0, l0 = z["start_right"], z["start_left"]
        if r0.size == n:
            eps.setInitialSpace([PETSc.Vec().createWithArray(np.ascontiguousarray(r0))])
            eps.setLeftInitialSpace([PETSc.Vec().createWithArray(np.ascontiguousarray(l0))])
    begin = time.perf_counter()
    eps.setUp()
    eps.solve()
    seconds = time.perf_counter() - begin
    m = eps.getConverged()
    values = np.array([eps.getEigenvalue(i) for i in range(m)], dtype=complex)
    right, left = np.zeros((N, m), complex), np.zeros((m, N), complex)
    vr, vi = mat.createVecs()
    for i in range(m):
        eps.getEigenvector(i, vr, vi)
        right[kept, i] = vr.getArray() + 1j * vi.getArray()
        eps.getLeftEigenvector(i, vr, vi)  # real PETSc: y with y^T A = lambda y^T, so l^H = y^T
        left[i, kept] = vr.getArray() + 1j * vi.getArray()
    its = eps.getIterationNumber()
    solves = st.getKSP().getIterationNumber()
    np.savez(out, values=values, right=right, left=left, seconds=seconds, its=its, solves=solves,
             start_right=right[kept].real.sum(axis=1), start_left=left[:, kept].real.sum(axis=0))


PSEUDO_NODES = 16
"""Points on each circle where sigma_min(A - z I) is computed (pseudo)."""


def pseudo(args, folder: Path) -> None:
    """The pseudospectral step bound on gamma-adjacent captured samples of one committed state
    (the same contact network and pattern): a step from A to A + E cannot turn a real eigenvalue
    complex if, on a circle about it that holds no other eigenvalue, min_z sigma_min(A - z I) >
    ||E||_2 (the count in the circle stays 1 along A + t E, and a real matrix's lone eigenvalue
    in a circle symmetric about the real axis is real). Here A and A + E are the two samples'
    A_g, E their difference (the path between them taken straight). For each step: ||E||_2;
    per real eigenvalue of the tracked band (sample A's window), the circle of half the distance rho to its nearest
    other eigenvalue (of the k computed), the first-order margin rho / kappa (kappa = ||l|| ||r||
    / |l^H r|, free from the window's vectors) and, on --rigorous steps, min over PSEUDO_NODES
    points of sigma_min (inverse iteration with one complex LU per point) less the Lipschitz
    allowance pi rho / PSEUDO_NODES between points; whether the step is proved free of births;
    the complex pairs in the band at both ends (the window's; the dense spectra's where the step
    is proved: a proof over a step whose count changes would be wrong); the seconds of the bound
    against the window sample's. sigma_min at a point is estimated by inverse iteration, which
    approaches it from above: the rigorous column is a bound up to that estimate."""
    import scipy.sparse.linalg as spla
    from diskfriction.continuation.linalg.solves import blas_threads
    paths = sorted(folder.glob("p*[0-9].npz"))
    groups = {}
    for path in paths:
        with np.load(path) as z:
            groups.setdefault(bytes(z["committed"]), []).append((float(z["gamma"]), path))
    steps = []
    for members in groups.values():
        members.sort()
        steps += [(a[1], b[1]) for a, b in zip(members, members[1:]) if b[0] > a[0]]
    steps.sort()
    pick = np.unique(np.linspace(0, len(steps) - 1, min(args.steps, len(steps))).round().astype(int))
    steps = [steps[i] for i in pick]
    rigorous = set(np.unique(np.linspace(0, len(steps) - 1, min(args.rigorous, len(steps))).round().astype(int)))
    print(f"{len(steps)} steps of {sum(len(m) - 1 for m in groups.values())} between gamma-adjacent samples "
          f"of one committed state ({len(groups)} states); load average {open('/proc/loadavg').read().split()[0]}")
    print(f"{'from':>6} {'to':>6} {'dgamma':>9} {'||E||':>9} {'real':>4} {'min rho/kappa':>13} "
          f"{'min sigma':>9} {'proved':>6} {'pairs':>5} {'bound s':>7} {'sample s':>8}")
    proved1 = proved2 = tried2 = 0
    bound_seconds, sample_seconds = [], []
    with blas_threads():
        for s, (pa, pb) in enumerate(steps):
            a, b = Problem(pa), Problem(pb)
            E = (b.A - a.A).tocsr()
            norm_E = float(spla.svds(E, k=1, return_singular_vectors=False)[0]) if E.nnz else 0.0
            found = run_arpack(a, {})
            sample_seconds.append(found.seconds)
            values, right, left = found.values, found.right, found.left
            band = a.window.tracked(values) & (np.abs(values.imag) <= 1e-9 * a.norm)
            rho_kappa, circles = [], []
            for i in np.flatnonzero(band):
                others = np.delete(values, i)
                rho = 0.5 * float(np.abs(others - values[i]).min())
                kappa = float(np.linalg.norm(left[i]) * np.linalg.norm(right[:, i]) / abs(left[i] @ right[:, i]))
                rho_kappa.append(rho / kappa)
                circles.append((values[i].real, rho))
            first = min(rho_kappa, default=np.inf)
            proved1 += first > norm_E
            sigma_text, bound_text, proved_text = "-", "-", f"{'yes' if first > norm_E else 'no':>3}/-"
            if s in rigorous:
                start = time.perf_counter()
                least = min((_least_singular_on(a.A, c, r) for c, r in circles), default=np.inf)
                bound_seconds.append(time.perf_counter() - start)
                tried2 += 1
                proved2 += least > norm_E
                sigma_text, bound_text = f"{least:9.2e}", f"{bound_seconds[-1]:7.2f}"
                proved_text = f"{'yes' if first > norm_E else 'no':>3}/{'yes' if least > norm_E else 'no'}"
            proved = first > norm_E or (s in rigorous and least > norm_E)
            pairs = [int((a.window.tracked(d) & (d.imag > 1e-9 * a.norm)).sum())
                     for d in ((a.dense, b.dense) if proved else (a.captured, b.captured))]
            print(f"{pa.stem[1:]:>6} {pb.stem[1:]:>6} {b.gamma - a.gamma:9.2e} {norm_E:9.2e} {int(band.sum()):4d} "
                  f"{first:13.2e} {sigma_text:>9} {proved_text:>6} {pairs[0]:>2}>{pairs[1]:<2} {bound_text:>7} "
                  f"{found.seconds:8.3f}", flush=True)
    print(f"\nproved free of births: first order {proved1}/{len(steps)} steps, sigma_min on circles "
          f"{proved2}/{tried2}; the bound {np.median(bound_seconds) if bound_seconds else np.nan:.2f} s "
          f"(median) against a window sample's {np.median(sample_seconds):.3f} s")


def _least_singular_on(A, center: float, radius: float) -> float:
    """A lower bound on min over the circle |z - center| = radius of sigma_min(A - z I): at
    PSEUDO_NODES points by inverse iteration on (A - z I)^-H (A - z I)^-1 (one complex LU each),
    less pi radius / PSEUDO_NODES (sigma_min is 1-Lipschitz in z; every point of the circle lies
    within that of a node)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    n = A.shape[0]
    I = sp.identity(n, format="csc")
    least = np.inf
    rng = np.random.default_rng(0)
    for z in center + radius * np.exp(2j * np.pi * np.arange(PSEUDO_NODES) / PSEUDO_NODES):
        lu = spla.splu(sp.csc_array(A - z * I), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.01,
                       options=dict(SymmetricMode=True))
        x = rng.standard_normal(n) + 0j
        x /= np.linalg.norm(x)
        estimate = 0.0
        for _ in range(8):
            y = lu.solve(x)
            x = lu.solve(y, trans="H")
            grown = np.linalg.norm(x)
            x /= grown
            if abs(grown - estimate) <= 1e-3 * grown:
                break
            estimate = grown
        least = min(least, 1.0 / np.sqrt(grown))
    return least - np.pi * radius / PSEUDO_NODES


# ---------------------------------------------------------------- main

def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    if sys.argv[1:2] == ["slepc-worker"]:
        return slepc_worker(*sys.argv[2:5])
    ap.add_argument("command", choices=("capture", "compare", "pseudo"))
    ap.add_argument("--cache", default=str(CACHE))
    ap.add_argument("--N", type=int, default=1024)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--lo", type=float, default=-3.0)
    ap.add_argument("--hi", type=float, default=2.0)
    ap.add_argument("--count", type=int, default=800)
    ap.add_argument("--gamma-end", type=float, default=1e-3)
    ap.add_argument("--methods", default="arpack,contour,contour-1e-10,slepc")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--stretches", type=int, default=4)
    ap.add_argument("--length", type=int, default=10)
    ap.add_argument("--slepc-python", default="")
    ap.add_argument("--steps", type=int, default=40, help="pseudo: steps studied")
    ap.add_argument("--rigorous", type=int, default=6, help="pseudo: steps with sigma_min on circles")
    args = ap.parse_args()
    folder = Path(args.cache) / f"N{args.N}_s{args.seed}_w{args.lo:g}:{args.hi:g}"
    if args.command == "capture":
        capture(args, folder)
    elif args.command == "compare":
        compare(args, folder)
    else:
        pseudo(args, folder)


if __name__ == "__main__":
    main()
