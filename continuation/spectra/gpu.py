"""Dense spectra on a GPU: cuSOLVER's geev through CuPy (>= 14, cupy.linalg.eig).

cuSOLVER's Xgeev returns eigenvalues and right vectors only (its left vectors are not
implemented), so the left vectors are the rows of R^-1: with A R = R Lambda,

    R^-1 A = Lambda R^-1,      row i of R^-1 = l_i^H,      l_i^H r_j = delta_ij,

the normalisation tracking.Eigensystem asks for, exact for the computed R. Its error is
eps cond(R) |l_i|: it grows like the eigenvalues' condition numbers towards a collision, where
R becomes singular, as LAPACK's left vectors from the Schur form do (the tests find the same
condition numbers and slopes within 1e-9).

decompose() takes the array module as an argument: cupy on a GPU, numpy in the tests that
check the formulas on a machine without one (tests/continuation/spectra/test_gpu_spectra.py).
"""
from __future__ import annotations

import functools
from typing import Optional

import numpy as np

Array = np.ndarray


def decompose(xp, A: Array, vectors: bool) -> Optional[tuple[Array, Optional[Array], Optional[Array]]]:
    """(eigenvalues, right vectors as columns, left vectors as rows with l_i^H r_i = 1) of the
    real dense matrix A, computed with the array module xp and returned as numpy arrays;
    (eigenvalues, None, None) without `vectors`. None where R is singular to working precision
    (an exactly defective eigenvalue, a matrix at a collision): the caller takes LAPACK's."""
    a = xp.asarray(A, dtype=xp.float64)
    if not vectors:
        return _host(xp, xp.linalg.eigvals(a)).astype(complex), None, None
    lam, right = xp.linalg.eig(a)
    right = right.astype(xp.complex128)
    try:
        left = xp.linalg.inv(right)
    except np.linalg.LinAlgError:  # numpy; CuPy's inv returns non-finite entries instead
        return None
    if not bool(xp.isfinite(left).all()):
        return None
    return _host(xp, lam).astype(complex), _host(xp, right), _host(xp, left)


def _host(xp, a) -> Array:
    """a as a numpy array (copied from the device for cupy)."""
    return a.get() if hasattr(a, "get") and xp is not np else np.asarray(a)


@functools.cache
def unavailable() -> Optional[str]:
    """Why dense spectra cannot run on a GPU here (one line), or None when they can: CuPy >= 14
    importable, its cupy.linalg.eig present, and a CUDA device. Checked once per process; the
    check starts CUDA in this process (forked scan workers must then not use it: scans.py)."""
    try:
        import cupy
    except Exception as err:  # ImportError, or a CUDA library that fails to load
        return f"CuPy is not installed ({type(err).__name__}: {err}); pip install 'diskfriction[gpu]'"
    major = int(cupy.__version__.split(".")[0])
    if major < 14 or not hasattr(cupy.linalg, "eig"):
        return f"CuPy {cupy.__version__} has no cupy.linalg.eig (CuPy >= 14 needed)"
    try:
        count = cupy.cuda.runtime.getDeviceCount()
    except Exception as err:  # CUDARuntimeError: no driver, no device
        return f"no CUDA device ({type(err).__name__}: {err})"
    return None if count > 0 else "no CUDA device"


def eigensystem_arrays(A: Array, vectors: bool):
    """decompose(cupy, A, vectors), or None where the GPU's memory does not hold the matrix and
    its vectors (the caller takes LAPACK's); call only where unavailable() is None."""
    import cupy
    try:
        return decompose(cupy, A, vectors)
    except cupy.cuda.memory.OutOfMemoryError:
        return None
