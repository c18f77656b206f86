"""The stability matrix as the eigensolvers take it: A (n x n) with what they may use of its
structure (Problem.stability_structure).

The spectrum of A splits into

  * its coupled part: the m eigenvalues of A_c, the matrix of A on the `kept` coordinates (by
    default the submatrix A[kept, kept]; a problem may give A_c itself, e.g. in coordinates
    relative to a reference body, P A E), whose eigenvectors live on those coordinates;
  * decoupled blocks: b x b diagonal blocks of A coupled to nothing else (a body that feels no
    other), whose eigenvalues are those of the blocks;
  * zero modes: every other coordinate (the gauge: translations, loose bodies), eigenvalue 0.

Only the coupled part's eigenvalues take part in collision detection: the others are
`excluded` (Eigensystem), and only the coupled part's modes carry vectors (Eigensystem.columns).
A problem whose A has none of this structure returns StructuredMatrix(A): every eigenvalue
coupled. Besides, a problem may declare

  * a deflation (nearest.Deflated) to shift-invert in place of A (its LU fills less);
  * a symmetric form of A_c (a real spectrum; SymmetricForm);
  * A's periodic block-tridiagonal layout (block size b and the order of its unknowns), from
    which full spectra may be refined (eigensolvers.RefinedSpectra, refinement.py);
  * the matrix the spectrum is computed from, up to constants of the problem's committed state
    (spectrum_matrix; default A): two points where it is the same have the same eigensystem.

A structure may compute its parts lazily (a subclass with cached properties): an eigensolver
reads only the parts it needs.
"""
from __future__ import annotations

from typing import Optional, Protocol

import numpy as np
import scipy.sparse as sp

from diskfriction.continuation.linalg.solves import Matrix, dense
from diskfriction.continuation.spectra.tracking import Eigensystem, SpectraDevice, eigensystem

Array = np.ndarray


class SymmetricForm(Protocol):
    """A coupled part A_c similar to a symmetric matrix (a real spectrum): its eigensystem from
    that matrix by a symmetric eigensolver, eigenvalues and A_c's own vectors."""

    def eigensystem(self, vectors: bool) -> Eigensystem:
        ...


class StructuredMatrix:
    """A (`matrix`, n x n, dense or sparse) and its structure (module docstring).

    kept: A_c's coordinates (ascending indices into 0..n-1), None: every coordinate not in a
    decoupled block; coupled: A_c (m x m, m = kept.size), None: A[kept, kept]; decoupled: (f, b)
    the coordinates of f decoupled b x b blocks, None: none; deflated: a nearest.Deflated, None:
    shift-invert A itself; symmetric: a SymmetricForm of A_c, None: none; block_size, block_order:
    A's periodic block-tridiagonal layout (block_tridiagonal.PeriodicBlocks.from_matrix), 0:
    none; spectrum_matrix: what the spectrum is computed from (default A)."""

    kept: Optional[Array] = None
    coupled: Optional[Matrix] = None
    decoupled: Optional[Array] = None
    deflated: Optional[object] = None
    symmetric: Optional[SymmetricForm] = None
    block_size: int = 0
    block_order: Optional[Array] = None

    def __init__(self, matrix: Matrix, **structure):
        self.matrix = matrix
        for name, value in structure.items():
            if name not in STRUCTURE:
                raise TypeError(f"StructuredMatrix has no part {name!r} (parts: {', '.join(STRUCTURE)})")
            setattr(self, name, value)

    @property
    def spectrum_matrix(self) -> Matrix:
        """The matrix the spectrum is computed from: A."""
        return self.matrix

    @property
    def reduced(self) -> bool:
        """Whether A has a coupled part smaller than A (kept coordinates or decoupled blocks)."""
        return self.kept is not None or self.decoupled is not None

    def coupled_coordinates(self) -> Array:
        """kept, or every coordinate not in a decoupled block."""
        if self.kept is not None:
            return self.kept
        return np.setdiff1d(np.arange(self.matrix.shape[0]), self.decoupled.ravel())

    def coupled_matrix(self) -> Matrix:
        """A_c: `coupled`, or A on the coupled coordinates."""
        if self.coupled is not None:
            return self.coupled
        A, c = self.matrix, self.coupled_coordinates()
        return A[c][:, c] if sp.issparse(A) else A[np.ix_(c, c)]

    def shifted(self) -> Matrix:
        """The matrix whose eigenvalues nearest a shift a spectral window takes (without
        vectors): A_c where it is given (A's other modes, the zeros of the gauge, are not A's
        to offer), else A (a decoupled block's eigenvalues among them)."""
        return self.matrix if self.coupled is None else self.coupled


STRUCTURE = ("kept", "coupled", "decoupled", "deflated", "symmetric", "block_size", "block_order")
"""The parts a StructuredMatrix may be given besides A."""


def dense_eigensystem(structure: StructuredMatrix, vectors: bool,
                      device: Optional[SpectraDevice] = None) -> Eigensystem:
    """The whole eigensystem of A from dense spectra (tracking.eigensystem, on `device`): A's
    own where it has no coupled part of its own, else A_c's (its symmetric form's where it has
    one) embedded (embedded)."""
    if not structure.reduced:
        return eigensystem(dense(structure.matrix), vectors, device)
    if structure.symmetric is not None:
        found = structure.symmetric.eigensystem(vectors)
    else:
        found = eigensystem(dense(structure.coupled_matrix()), vectors, device)
    return embedded(structure, found, vectors)


def embedded(structure: StructuredMatrix, found: Eigensystem, vectors: bool) -> Eigensystem:
    """A's eigensystem from A_c's (`found`): A_c's eigenvalues at the kept coordinates' labels,
    the decoupled blocks' eigenvalues at theirs and 0 at the others, all but A_c's excluded;
    with `vectors`, A_c's vectors embedded in A's coordinates (zero elsewhere) as the columns
    of `right` and rows of `left` that Eigensystem.columns names (-1 for the excluded)."""
    n = structure.matrix.shape[0]
    kept = structure.coupled_coordinates()
    values, excluded = np.zeros(n, complex), np.ones(n, bool)
    values[kept], excluded[kept] = found.values, False
    if structure.decoupled is not None:
        values[structure.decoupled] = block_eigenvalues(structure.matrix, structure.decoupled)
    if not vectors:
        return Eigensystem(values, excluded=excluded)
    right = np.zeros((n, kept.size), complex)
    left = np.zeros((kept.size, n), complex)
    right[kept], left[:, kept] = found.right, found.left
    columns = np.full(n, -1)
    columns[kept] = np.arange(kept.size)
    return Eigensystem(values, right, left, excluded, columns=columns)


def block_eigenvalues(A: Matrix, blocks: Array) -> Array:
    """The eigenvalues (f, b) of A's b x b diagonal blocks on the coordinates blocks (f, b)."""
    b = blocks.shape[1]
    entries = [np.asarray(A[blocks[:, i], blocks[:, j]]).ravel() for i in range(b) for j in range(b)]
    return np.linalg.eigvals(np.stack(entries, axis=1).reshape(-1, b, b))


def on_blocks(system: Eigensystem, blocks: Array, share: float) -> Array:
    """The modes of `system` whose right vectors carry more than `share` of their norm^2 on the
    coordinates of the decoupled blocks (a block's own modes); none without vectors."""
    if system.right is None:
        return np.zeros(system.values.size, bool)
    on = np.concatenate(list(blocks))
    return np.sum(np.abs(system.right[on]) ** 2, axis=0) / np.sum(np.abs(system.right) ** 2, axis=0) > share
