"""Dense spectra on a GPU (issue 26 item 2): gpu_spectra's formulas (checked with numpy as the
array module, where no GPU is), the device switch, and, where CuPy and a CUDA device are
present, cuSOLVER against LAPACK."""
from __future__ import annotations

import re

import numpy as np
import pytest

from diskfriction.continuation.spectra import gpu as gpu_spectra

from diskfriction.continuation.detection import scans

from diskfriction.continuation.spectra import tracking as spectra
from diskfriction.continuation.detection.collisions import DetectionParams
from diskfriction.continuation.problem import FunctionProblem
from diskfriction.continuation.spectra.eigensolvers import DenseSpectra, RefinedSpectra
from diskfriction.continuation.spectra.window import SpectralWindow
from diskfriction.continuation.spectra.tracking import NoGpu, eigensystem, spectra_on
from commandline import error_line, run_main

WHY_NO_GPU = gpu_spectra.unavailable()


def relaxed_jacobian(N: int, F_x: float = 0.002):
    """The stability matrix J of the paper's scene with N disks and eps = 1e-4, relaxed from
    rest to F_x (benchmarks/dense_spectrum.py's matrix)."""
    from diskfriction.continuation.linalg.solves import dense
    from diskfriction.models.chain.equilibria import DiskEquilibria, relax
    from diskfriction.scenes import Scene
    from diskfriction.symbolic import System

    system = System.from_scene(Scene(N=N, eps=1e-4))
    q, xi = relax(system, *system.rest_state(), F_x)
    return dense(DiskEquilibria(system, q, xi, F_x, "J").stability_matrix(q, F_x))


@pytest.fixture(scope="module")
def paper(chain_sweep):
    """The paper's scene and its sweep 0 -> 0.12 (22 collisions; on the CPU wherever the test
    suite runs without a GPU, and "auto" keeps n = 30 there anyway)."""
    from diskfriction.scenes import Scene
    from diskfriction.symbolic import System

    return System.from_scene(Scene()), chain_sweep(Scene())[0]


def complex_jacobian(paper):
    """J at the paper branch's first accepted point with three complex pairs."""
    system, branch = paper
    k = int(np.flatnonzero(branch.n_complex >= 3)[0])
    return system.stability_matrix(system.jacobian(branch.q[k], branch.xi[k]), "J")


def same_spectrum(a: np.ndarray, b: np.ndarray) -> float:
    """Largest |a_i - b_perm(i)| / max|a| over the best matching of the two spectra."""
    return float(np.abs(a - spectra.track(a, b)).max() / np.abs(a).max())


@pytest.fixture
def fake_gpu(monkeypatch):
    """A 'GPU' that runs gpu_spectra.decompose with numpy: counts its calls."""
    calls = []

    def arrays(A, vectors):
        calls.append(A.shape[0])
        return gpu_spectra.decompose(np, A, vectors)

    monkeypatch.setattr(gpu_spectra, "unavailable", lambda: None)
    monkeypatch.setattr(gpu_spectra, "eigensystem_arrays", arrays)
    return calls


@pytest.mark.parametrize("which", ["random", "paper"])
def test_left_vectors_from_the_inverse_of_the_right_ones_are_lapacks(which, paper):
    """decompose's left vectors (rows of R^-1) are left eigenvectors with l_i^H r_i = 1, and
    give LAPACK's eigenvalues, condition numbers and slopes."""
    rng = np.random.default_rng(3)
    A = rng.standard_normal((60, 60)) if which == "random" else complex_jacobian(paper)
    lam, right, left = gpu_spectra.decompose(np, A, vectors=True)
    assert np.abs(left @ A - lam[:, None] * left).max() <= 1e-11 * np.abs(A).max() * np.abs(left).max()
    assert np.abs(np.einsum("ij,ji->i", left, right) - 1.0).max() <= 1e-12
    cpu = eigensystem(A, vectors=True)
    perm = spectra.match_eigenvalues(cpu.values, lam)
    assert same_spectrum(cpu.values, lam) <= 1e-12
    gpu = spectra.Eigensystem(lam, right, left).permuted(perm)
    kappa_cpu, kappa_gpu = spectra.condition_numbers(cpu), spectra.condition_numbers(gpu)
    assert np.abs(kappa_gpu / kappa_cpu - 1.0).max() <= 1e-9
    dA = rng.standard_normal(A.shape)
    slopes_cpu, slopes_gpu = spectra.eigenvalue_slopes(cpu, dA), spectra.eigenvalue_slopes(gpu, dA)
    assert np.abs(slopes_gpu - slopes_cpu).max() <= 1e-9 * np.abs(slopes_cpu).max()
    values, none, also_none = gpu_spectra.decompose(np, A, vectors=False)
    assert none is None and also_none is None and same_spectrum(cpu.values, values) <= 1e-12


def test_the_device_decides_where_each_spectrum_runs(fake_gpu, monkeypatch):
    monkeypatch.setattr(spectra, "GPU_FROM", 40)
    small, large = np.diag(np.arange(30.0)) + np.triu(np.ones((30, 30)), 1), relaxed_jacobian(N=14)  # n = 30, 42
    with spectra_on("cpu"):
        eigensystem(large, vectors=True)
    assert fake_gpu == []
    eigensystem(small, vectors=False)  # "auto", the default: below GPU_FROM on the CPU
    eigensystem(large, vectors=False)
    assert fake_gpu == [42]
    with spectra_on("gpu"):
        system = eigensystem(small, vectors=True)
    assert fake_gpu == [42, 30] and system.left is not None
    jordan = np.eye(30) + np.diag(np.ones(29), 1)  # defective: R is singular, LAPACK's vectors
    with spectra_on("gpu"), np.errstate(invalid="ignore", divide="ignore"):  # LAPACK: l^H r = 0
        system = eigensystem(jordan, vectors=True)
    assert fake_gpu == [42, 30, 30] and np.isfinite(system.values).all() and system.left is not None
    with pytest.raises(ValueError):
        with spectra_on("tpu"):
            pass


def test_scans_run_inline_where_the_spectra_run_on_the_gpu(fake_gpu, monkeypatch):
    monkeypatch.setattr(scans.os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    detection = DetectionParams()
    assert scans.planned_workers(300, detection) == 2
    with spectra_on("gpu"):
        assert scans.planned_workers(300, detection) == 0
        with pytest.raises(scans.WorkersOnGpu, match="--device cpu"):
            scans.planned_workers(300, detection, asked=2)
        # a spectral window takes no dense spectra: its scans stay on workers
        window = SpectralWindow(-1.0, 0.0)
        assert scans.planned_workers(300, detection, dense=False) == 2
        assert scans.planned_workers(300, detection, asked=3, dense=False) == 3
        problem = FunctionProblem(np.subtract, None, None)
        assert scans.default_workers(problem, 300, detection, eigensolver=window) == 2
        assert scans.default_workers(problem, 300, detection, eigensolver=DenseSpectra("cpu")) == 2
    assert scans.default_workers(problem, 300, detection, eigensolver=DenseSpectra("gpu")) == 0


def test_the_dense_eigensolvers_take_dense_spectra_on_their_device(fake_gpu):
    """DenseSpectra and RefinedSpectra take dense spectra, on spectra_on's device or their own;
    a spectral window takes none."""
    assert DenseSpectra().dense and RefinedSpectra().dense and not SpectralWindow(-1.0, 0.0).dense
    assert DenseSpectra("gpu").on_gpu(10) and not DenseSpectra("cpu").on_gpu(5000)
    assert not SpectralWindow(-1.0, 0.0).on_gpu(5000)
    with pytest.raises(ValueError):
        DenseSpectra("tpu")


@pytest.mark.skipif(WHY_NO_GPU is None, reason="a GPU is present: spectra_on('gpu') runs")
def test_asking_for_gpu_spectra_without_a_gpu_says_why_in_one_line():
    with pytest.raises(NoGpu) as error:
        with spectra_on("gpu"):
            pass
    assert "\n" not in str(error.value) and str(error.value) == WHY_NO_GPU
    with pytest.raises(NoGpu, match="^" + re.escape(WHY_NO_GPU) + "$"):
        DenseSpectra("gpu")  # the eigensolver's own device: the same line


@pytest.mark.skipif(WHY_NO_GPU is None, reason="a GPU is present: bifurcate --device gpu runs")
def test_bifurcate_asked_for_gpu_spectra_without_a_gpu_says_why_in_one_line(tmp_path):
    result = run_main("bifurcate", "--device", "gpu", "--out", str(tmp_path / "out"))
    assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
    assert error_line(result, "bifurcate") == f"bifurcate error: --device gpu: {WHY_NO_GPU}"
    assert not (tmp_path / "out").exists()


def test_bifurcate_refuses_an_unknown_device_in_one_line(tmp_path):
    result = run_main("bifurcate", "--device", "xpu", "--out", str(tmp_path / "out"))
    assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
    assert error_line(result, "bifurcate") == "bifurcate error: --device: must be cpu, gpu or auto (got 'xpu')"


@pytest.mark.skipif(WHY_NO_GPU is not None, reason=f"no GPU spectra here: {WHY_NO_GPU}")
def test_cusolver_gives_lapacks_spectrum_at_n_1020():
    """cuSOLVER's geev on the paper's scene with 340 disks (n = 1020): LAPACK's eigenvalues
    within 1e-12 of the spectral radius, and left vectors with l_i^H A = lambda_i l_i^H."""
    A = relaxed_jacobian(N=340)
    with spectra_on("cpu"):
        cpu = eigensystem(A, vectors=True)
    with spectra_on("gpu"):
        gpu = eigensystem(A, vectors=True)
    assert same_spectrum(cpu.values, gpu.values) <= 1e-12
    residual = gpu.left @ A - gpu.values[:, None] * gpu.left
    assert np.abs(residual).max() <= 1e-10 * np.abs(A).max() * np.abs(gpu.left).max()


def test_a_matrix_too_large_for_the_gpu_goes_to_lapack(monkeypatch):
    """gpu_spectra.eigensystem_arrays with a CuPy whose allocation fails: None, and
    eigensystem takes LAPACK's spectrum instead."""
    import sys
    import types

    class OutOfMemoryError(Exception):
        pass

    def asarray(*args, **kwargs):
        raise OutOfMemoryError("out of memory allocating 144,000,000 bytes")

    cupy = types.SimpleNamespace(asarray=asarray, float64=np.float64,
                                 cuda=types.SimpleNamespace(memory=types.SimpleNamespace(OutOfMemoryError=OutOfMemoryError)))
    monkeypatch.setitem(sys.modules, "cupy", cupy)
    monkeypatch.setattr(gpu_spectra, "unavailable", lambda: None)
    A = np.diag(np.arange(1.0, 7.0)) + np.triu(np.ones((6, 6)), 1)
    assert gpu_spectra.eigensystem_arrays(A, True) is None
    with spectra_on("gpu"):
        system = eigensystem(A, vectors=True)
    assert np.allclose(np.sort(system.values.real), np.arange(1.0, 7.0)) and system.left is not None
