"""Eigensolvers: how the tracked spectrum of A(u, p) is computed at every sample, a choice of the
run (Options.eigensolver, ContinuationParams.eigensolver), as BifurcationKit's eigsolver.

    DenseSpectra(device=None)      every eigenvalue, from a dense decomposition of A (LAPACK's
                                   dgeev, or cuSOLVER's geev on a GPU: tracking.eigensystem);
                                   device "cpu", "gpu" or "auto", None: spectra_on's
    RefinedSpectra(device=None,    the same, but a full spectrum with vectors is refined from the
                   refine_from=None)  previous sample's where A declares a periodic
                                   block-tridiagonal layout, n >= refine_from (None:
                                   refinement.REFINE_FROM), on the CPU, and the refinement is
                                   certified (refinement.py); the default
    SpectralWindow(lo, hi)         the eigenvalues with Re lambda near [lo, hi], by sparse
                                   shift-invert (window.py); it holds its own size k

An eigensolver reads the problem's StructuredMatrix (Problem.stability_structure): the coupled
part and the modes excluded, a deflation, the periodic layout (structure.py). It is a frozen
value: one that is sized at a run's start or widened where it crowded is a new one (prepared,
widened), which the caller carries to the next run.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Optional

import numpy as np

from diskfriction.continuation.linalg.block_tridiagonal import PeriodicBlocks
from diskfriction.continuation.spectra import refinement
from diskfriction.continuation.spectra.structure import dense_eigensystem
from diskfriction.continuation.spectra import gpu as gpu_spectra
from diskfriction.continuation.spectra.tracking import Eigensystem, NoGpu, SpectraDevice, on_gpu

if TYPE_CHECKING:  # pragma: no cover
    from diskfriction.continuation.detection.samples import Sample
    from diskfriction.continuation.problem import Problem

Array = np.ndarray


class Eigensolver:
    """The interface of an eigensolver (module docstring). dense: whether it takes dense spectra
    (which may run on a GPU: scans.planned_workers keeps the scans inline then)."""

    dense = True

    def eigensystem(self, problem: Problem, u: Array, p: float, vectors: bool = False) -> Eigensystem:
        """The eigensystem of A(u, p) (with normalised left and right vectors if `vectors`)."""
        raise NotImplementedError

    def refined(self, problem: Problem, x: Array, reference: Sample) -> Optional[Eigensystem]:
        """A full eigensystem with vectors at x = (u, p) from the nearby sample `reference`'s,
        or None (then eigensystem() is taken)."""
        return None

    def on_gpu(self, n: int) -> bool:
        """Whether its dense spectra of an n x n matrix run on a GPU."""
        return False

    def prepared(self, problem: Problem, u: Array, p: float) -> "Eigensolver":
        """The eigensolver for a run that starts at (u, p) (a window sized there): itself."""
        return self

    def widened(self, problem: Problem, u: Array, p: float) -> Optional["Eigensolver"]:
        """A wider one, sized at (u, p), where this one crowded; None: it cannot be widened."""
        return None


@dataclass(frozen=True)
class DenseSpectra(Eigensolver):
    """Every eigenvalue of A from a dense decomposition (module docstring): of A, or of its
    coupled part with the other modes excluded (structure.dense_eigensystem). device: "cpu",
    "gpu" or "auto" (tracking.SpectraDevice), None: spectra_on's; "gpu" where no GPU spectra
    can run raises NoGpu, as spectra_on("gpu") does, an unknown name ValueError."""

    device: Optional[SpectraDevice] = None

    def __post_init__(self):
        if self.device is not None:
            object.__setattr__(self, "device", SpectraDevice(self.device))
        if self.device is SpectraDevice.GPU and (why := gpu_spectra.unavailable()) is not None:
            raise NoGpu(why)

    def eigensystem(self, problem, u, p, vectors=False):
        return dense_eigensystem(problem.stability_structure(u, p), vectors, self.device)

    def on_gpu(self, n: int) -> bool:
        return on_gpu(n, self.device)


@dataclass(frozen=True)
class RefinedSpectra(DenseSpectra):
    """DenseSpectra whose full spectra with vectors are refined from the previous sample's where
    A is periodic block-tridiagonal (module docstring; refinement.py). refine_from: the least n
    refined (None: refinement.REFINE_FROM)."""

    refine_from: Optional[int] = None

    def refined(self, problem, x, reference):
        if not refinement.refinable(reference, self.refine_from, self.device):
            return None
        structure = problem.stability_structure(x[:-1], float(x[-1]))
        if not structure.block_size:
            return None
        blocks = PeriodicBlocks.from_matrix(structure.matrix, structure.block_size, structure.block_order)
        return refinement.refined_eigensystem(blocks, x, reference)


DEFAULT = RefinedSpectra()
"""The eigensolver of a run that names none."""
