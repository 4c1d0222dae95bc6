"""Small dense linear algebra over Python floats for the implicit integrators.

The implicit methods solve systems of the size of the state (4 to 11 unknowns) or a small
multiple of it. For such sizes a plain Python LU decomposition is cheaper than a round trip
through NumPy and keeps the FMU's runtime free of compiled dependencies.

:func:`lu_factor` computes ``P A = L U`` by Gaussian elimination with partial (row) pivoting
(Golub, Van Loan, Matrix Computations, 4th ed., algorithm 3.4.1): in column ``k`` the row with
the largest ``|a_ik|``, ``i >= k``, becomes the pivot row, so every multiplier satisfies
``|l_ik| <= 1``. ``L`` (unit lower triangular, without its diagonal) and ``U`` share one matrix.
:func:`lu_solve` then solves ``A x = b`` by forward substitution ``L z = P b`` and back
substitution ``U x = z``. Cost: ``n^3 / 3`` multiply-adds to factor, ``n^2`` per solve.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

Matrix = list[list[float]]


class SingularMatrixError(ArithmeticError):
    """The matrix has a zero (or non-finite) pivot: it is singular to working precision."""


class LUDecomposition:
    """``P A = L U`` of a square matrix: ``lu`` holds ``L`` below and ``U`` on and above the diagonal.

    ``perm[i]`` is the row of ``A`` that ended up in row ``i`` (``(P b)_i = b[perm[i]]``).
    """

    __slots__ = ("lu", "perm")

    def __init__(self, lu: Matrix, perm: list[int]) -> None:
        self.lu = lu
        self.perm = perm

    def solve(self, b: Sequence[float]) -> list[float]:
        """Return ``x`` with ``A x = b``."""
        return lu_solve(self, b)


def _pivot_row(lu: Matrix, k: int) -> int:
    """Row index ``p >= k`` of the largest ``|lu[p][k]|``."""
    best, best_abs = k, abs(lu[k][k])
    for i in range(k + 1, len(lu)):
        value = abs(lu[i][k])
        if value > best_abs:
            best, best_abs = i, value
    return best


def _eliminate_below(lu: Matrix, k: int) -> None:
    """Store the multipliers ``l_ik = a_ik / a_kk`` and subtract ``l_ik`` times row ``k`` (``i > k``)."""
    pivot_row = lu[k]
    inv_pivot = 1.0 / pivot_row[k]
    tail = range(k + 1, len(lu))
    for i in tail:
        row = lu[i]
        m = row[k] * inv_pivot
        row[k] = m
        if m != 0.0:
            for j in tail:
                row[j] -= m * pivot_row[j]


def lu_factor(a: Sequence[Sequence[float]]) -> LUDecomposition:
    """Return the LU decomposition of the square matrix ``a`` (not modified).

    Raises :class:`SingularMatrixError` if a pivot is zero or not finite.
    """
    lu = [list(map(float, row)) for row in a]
    n = len(lu)
    perm = list(range(n))
    for k in range(n):
        p = _pivot_row(lu, k)
        pivot = lu[p][k]
        if pivot == 0.0 or not math.isfinite(pivot):
            raise SingularMatrixError(f"pivot {pivot!r} in column {k} of a {n}x{n} matrix")
        if p != k:
            lu[k], lu[p] = lu[p], lu[k]
            perm[k], perm[p] = perm[p], perm[k]
        _eliminate_below(lu, k)
    return LUDecomposition(lu, perm)


def lu_solve(decomposition: LUDecomposition, b: Sequence[float]) -> list[float]:
    """Solve ``A x = b`` with the decomposition of ``A`` from :func:`lu_factor`."""
    lu, perm = decomposition.lu, decomposition.perm
    n = len(lu)
    x = [b[p] for p in perm]
    for i in range(1, n):  # L z = P b (unit diagonal)
        row = lu[i]
        s = x[i]
        for j in range(i):
            s -= row[j] * x[j]
        x[i] = s
    for i in range(n - 1, -1, -1):  # U x = z
        row = lu[i]
        s = x[i]
        for j in range(i + 1, n):
            s -= row[j] * x[j]
        x[i] = s / row[i]
    return x
