"""Linear combinations of Runge-Kutta stages, compiled once per tableau row and state size.

An explicit Runge-Kutta step is dominated by sums like ``y + h * sum_j a_ij k_j`` over a handful
of components: as Python loops they cost more than the right-hand sides themselves. This module
writes each such sum out as one straight-line Python expression per component, with the
coefficients as literals, compiles it with the runtime's one code generator
(:func:`double_pendulum.codegen.define`) and caches the function by ``(coefficients, n)``.
The arithmetic is exactly the loop's, in the same order (results are
bit-identical); only the interpreter overhead goes (the stage sums of a DOP853 step on the
pendulum's 4 states: about 6.5 us instead of 12).

The generated source contains nothing but float literals, indices and the argument names, so it
is safe to compile and run.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from functools import cache

from ..codegen import define

SparseRow = tuple[tuple[int, float], ...]


def _terms(row: SparseRow, c: int) -> str:
    return " + ".join(f"{a!r} * k{j}[{c}]" for j, a in row) or "0.0"


def _compile(name: str, args: str, row: SparseRow, body: str) -> Callable:
    unpack = "".join(f"    k{j} = ks[{j}]\n" for j in sorted({j for j, _ in row}))
    return define(f"def {name}({args}):\n{unpack}    return [{body}]\n", name)


@cache
def step_combination(row: SparseRow, n: int) -> Callable[[list[float], float, Sequence[list[float]]], list[float]]:
    """Return ``g(y, h, ks) -> [y_c + sum_j (h a_j) ks[j][c] for c in range(n)]``.

    Summed left to right from ``y_c``, with the products ``h a_j`` formed first: exactly the
    arithmetic of the plain loop ``out[c] += (h * a_j) * k_j[c]`` (and of the NumPy batch version).
    """
    scaled = "".join(f"    ha{i} = h * {a!r}\n" for i, (_, a) in enumerate(row))
    body = ", ".join(
        f"y[{c}]" + "".join(f" + ha{i} * k{j}[{c}]" for i, (j, _) in enumerate(row)) for c in range(n)
    )
    unpack = "".join(f"    k{j} = ks[{j}]\n" for j in sorted({j for j, _ in row}))
    source = f"def stage(y, h, ks):\n{unpack}{scaled}    return [{body}]\n"
    return define(source, "stage")


@cache
def weighted_sum(row: SparseRow, n: int) -> Callable[[Sequence[list[float]]], list[float]]:
    """Return ``g(ks) -> [sum_j w_j ks[j][c] for c in range(n)]``."""
    body = ", ".join(_terms(row, c) for c in range(n))
    return _compile("weighted", "ks", row, body)


@cache
def explicit_stages(a: tuple[SparseRow, ...], c: tuple[float, ...], n_stages: int, b: SparseRow, n: int) -> Callable:
    """Return ``g(f, t, y, k0, h) -> (y_new, [k0, ..., k_{s-1}])``: one explicit Runge-Kutta step as one
    straight-line function (tableau rows ``a``, nodes ``c``, the first ``n_stages`` stages, weights ``b``).

    The state and each stage derivative are unpacked into locals once, so the stage inputs
    ``y_c + (h a_ij) k_j[c] + ...`` cost no list indexing and no call per stage; the arithmetic is
    exactly that of :func:`step_combination` (products ``h a_ij`` first, summed left to right from
    ``y_c``), so the step is bit-identical to the loop over stages.
    """

    def unpack(name: str) -> str:
        return f"    {', '.join(f'{name}_{i}' for i in range(n))}, = {name}\n"

    def combination(row: SparseRow, prefix: str) -> str:
        scaled = "".join(f"    {prefix}{j} = h * {w!r}\n" for j, w in row)
        terms = [f"y_{i}" + "".join(f" + {prefix}{j} * k{j}_{i}" for j, _ in row) for i in range(n)]
        return scaled, f"[{', '.join(terms)}]"

    source = "def stages(f, t, y, k0, h):\n" + unpack("y") + unpack("k0")
    for i in range(1, n_stages):
        scaled, state = combination(a[i], f"ha{i}_")
        source += scaled + f"    k{i} = f(t + {c[i]!r} * h, {state})\n" + unpack(f"k{i}")
    scaled, y_new = combination(b, "hb")
    source += scaled + f"    return {y_new}, [{', '.join(f'k{i}' for i in range(n_stages))}]\n"
    return define(source, "stages")


@cache
def scaled_error_norm(row: SparseRow, n: int) -> Callable[..., float]:
    """Return ``g(y, y_new, ks, h, rtol, atol)``: the scaled RMS norm of an embedded error estimate.

    With ``e_c = h * sum_j w_j ks[j][c]`` (``row``: the sparse weights of the error estimate) and
    ``s_c = atol + rtol * max(|y_c|, |y_new_c|)`` it returns ``sqrt(sum_c (e_c / s_c)^2 / n)``, in
    the order of operations of the plain loop (``runge_kutta.scaled_rms``), as straight-line code.
    """
    lines = ["def norm(y, y_new, ks, h, rtol, atol):"]
    lines += [f"    k{j} = ks[{j}]" for j in sorted({j for j, _ in row})]
    terms = []
    for c in range(n):
        lines.append(f"    e{c} = h * ({_terms(row, c)})")
        lines.append(f"    a{c} = abs(y[{c}])")
        lines.append(f"    b{c} = abs(y_new[{c}])")
        lines.append(f"    s{c} = atol + rtol * (b{c} if b{c} > a{c} else a{c})")
        terms.append(f"(e{c} / s{c}) ** 2")
    lines.append(f"    return sqrt((0.0 + {' + '.join(terms)}) / {n})")
    return define("\n".join(lines) + "\n", "norm", {"sqrt": math.sqrt})


def dense_columns(
    extra: Sequence[tuple[int, SparseRow, float]], d_rows: Sequence[SparseRow], n: int
) -> Callable[..., list[tuple[float, ...]]]:
    """Return ``g(f, t, y, y_new, fy, f_new, h, ks)``: the coefficients of DOP853's dense output per component.

    ``extra`` lists the extra stages ``(index, sparse row, node)`` evaluated first (appended to the
    step's ``ks``); then for each component ``c``, with ``dy = y_new[c] - y[c]``, the column
    ``(h D_3.k, h D_2.k, h D_1.k, h D_0.k, 2 dy - h (fy + f_new), h fy - dy, dy)`` (highest first,
    as :func:`alternating_horner` takes it), in the arithmetic of the plain loops, as one
    straight-line function.
    """
    used = sorted({j for _, row, _ in extra for j, _ in row} | {j for row in d_rows for j, _ in row})
    source = "def dense(f, t, y, y_new, fy, f_new, h, ks):\n"
    source += "".join(f"    k{j} = ks[{j}]\n" for j in used if j < min(i for i, _, _ in extra))
    for index, row, node in extra:
        scaled = "".join(f"    ha{index}_{j} = h * {w!r}\n" for j, w in row)
        state = ", ".join(f"y[{c}]" + "".join(f" + ha{index}_{j} * k{j}[{c}]" for j, _ in row) for c in range(n))
        source += scaled + f"    k{index} = f(t + {node!r} * h, [{state}])\n"
    columns = []
    for c in range(n):
        source += f"    dy{c} = y_new[{c}] - y[{c}]\n"
        ds = [f"h * ({_terms(row, c)})" for row in d_rows]
        hermite = [f"2.0 * dy{c} - h * (fy[{c}] + f_new[{c}])", f"h * fy[{c}] - dy{c}", f"dy{c}"]
        columns.append(f"({', '.join([*reversed(ds), *hermite])})")
    source += f"    return [{', '.join(columns)}]\n"
    return define(source, "dense")


@cache
def two_estimate_error_norm(row5: SparseRow, row3: SparseRow, n: int) -> Callable[..., float]:
    """Return ``g(y, y_new, ks, h, rtol, atol)``: DOP853's error norm from its 5th- and 3rd-order estimates.

    With ``e5_c, e3_c`` the estimates' weighted stage sums and ``s_c`` as in :func:`scaled_error_norm`,
    ``n5 = sum_c (e5_c / s_c)^2``, ``n3`` alike: ``|h| n5 / sqrt((n5 + 0.01 n3) n)`` (0 if both are 0;
    Hairer, Norsett, Wanner, code DOP853), as straight-line code in the order of the plain loop.
    """
    lines = ["def norm(y, y_new, ks, h, rtol, atol):"]
    lines += [f"    k{j} = ks[{j}]" for j in sorted({j for j, _ in (*row5, *row3)})]
    fives, threes = [], []
    for c in range(n):
        lines.append(f"    a{c} = abs(y[{c}])")
        lines.append(f"    b{c} = abs(y_new[{c}])")
        lines.append(f"    s{c} = atol + rtol * (b{c} if b{c} > a{c} else a{c})")
        fives.append(f"(({_terms(row5, c)}) / s{c}) ** 2")
        threes.append(f"(({_terms(row3, c)}) / s{c}) ** 2")
    lines.append(f"    n5 = 0.0 + {' + '.join(fives)}")
    lines.append(f"    n3 = 0.0 + {' + '.join(threes)}")
    lines.append("    if n5 == 0.0 and n3 == 0.0:")
    lines.append("        return 0.0")
    lines.append(f"    return abs(h) * n5 / sqrt((n5 + 0.01 * n3) * {n})")
    return define("\n".join(lines) + "\n", "norm", {"sqrt": math.sqrt})


def sparse(weights: Sequence[float]) -> SparseRow:
    """Turn dense weights into a sparse row ``((j, w_j), ...)`` of the non-zero ones."""
    return tuple((j, float(w)) for j, w in enumerate(weights) if w != 0.0)


@cache
def alternating_horner(n: int, m: int) -> Callable[[Sequence[Sequence[float]], Sequence[float], float], list[float]]:
    """Return ``g(columns, y, x)`` evaluating DOP853's dense-output polynomial for ``n`` components
    (``x`` last, so ``functools.partial(g, columns, y)`` is the interpolant).

    For each component with coefficients ``(c_0, ..., c_{m-1})`` (highest first) it computes
    ``((((c_0 x + c_1)(1-x) + c_2) x + c_3)(1-x) ...) + y`` -- factors alternating ``x`` and
    ``1 - x`` starting with ``x`` -- in the same order as the equivalent loop.
    """
    lines = ["def horner(columns, y, x):", "    u = 1.0 - x"]
    results = []
    for c in range(n):
        names = [f"a{c}_{i}" for i in range(m)]
        lines.append(f"    {', '.join(names)}{',' if m == 1 else ''} = columns[{c}]")
        expr = names[0]
        for i in range(m):
            if i > 0:
                expr = f"({expr} + {names[i]})"
            expr = f"{expr} * {'x' if i % 2 == 0 else 'u'}"
        results.append(f"{expr} + y[{c}]")
    lines.append(f"    return [{', '.join(results)}]")
    return define("\n".join(lines) + "\n", "horner")
