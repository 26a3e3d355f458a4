"""Small matrix products summed in index order, as the C engine's loops sum them (rocking_model/engine/src:
``acc = 0.0; for k: acc += a[k] * b[k]``), and the C's inverses and dense solves operation for operation, for
the Python reference's contact paths.

Why not ``@``: numpy hands even a 3 x 3 product to its BLAS, whose kernels are chosen per CPU and may fuse
``a * b + c`` into one rounding (FMA) or reorder the sum. A chaotic record amplifies that last bit: the rigid
block's Moreau-Jean run over the benchmark's 30 s record drifted 2.2e-4 rad from the C engine on an Intel Xeon
(bit for bit the same under OpenBLAS's generic kernels). Python floats never fuse, so these sums round as the
C's do on every machine."""
from __future__ import annotations

import math

import numpy as np


def _dot(row, col) -> float:
    """sum(row[k] * col[k]) from 0.0 in index order (Python floats: each product and sum rounded apart)."""
    acc = 0.0
    for a, b in zip(row, col):
        acc += a * b
    return acc


def matvec(A: np.ndarray, x) -> np.ndarray:
    """A @ x for a 2-D A and a 1-D x, each row summed from 0.0 in index order."""
    xs = x.tolist() if isinstance(x, np.ndarray) else list(x)
    return np.array([_dot(row, xs) for row in A.tolist()], dtype=float)


def matmul(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """A @ B for 2-D A and B, each entry summed from 0.0 in index order."""
    cols = B.T.tolist()
    out = [[_dot(row, col) for col in cols] for row in A.tolist()]
    return np.array(out, dtype=float).reshape(A.shape[0], B.shape[1])


def inverse(A: np.ndarray) -> np.ndarray:
    """A^-1 by Gauss-Jordan elimination with partial pivoting, operation for operation as the C engine's
    rk_model_inverse_mass (np.linalg.inv's LAPACK rounds per CPU)."""
    n = A.shape[0]
    a = A.tolist()
    inv = [[1.0 if i == j else 0.0 for j in range(n)] for i in range(n)]
    for k in range(n):
        p = k
        for i in range(k + 1, n):
            if abs(a[i][k]) > abs(a[p][k]):
                p = i
        if p != k:
            a[k], a[p] = a[p], a[k]
            inv[k], inv[p] = inv[p], inv[k]
        piv = a[k][k]
        if piv == 0.0:
            raise np.linalg.LinAlgError("Singular matrix")
        a[k] = [x / piv for x in a[k]]
        inv[k] = [x / piv for x in inv[k]]
        for i in range(n):
            if i == k:
                continue
            f = a[i][k]
            ak, ik = a[k], inv[k]
            a[i] = [x - f * y for x, y in zip(a[i], ak)]
            inv[i] = [x - f * y for x, y in zip(inv[i], ik)]
    return np.array(inv, dtype=float)


def _back_substitute(lu: list, y: list, x: list) -> None:
    """x = U^-1 y for the upper triangle U of ``lu`` (lists), from the last row up, each row's sum in index
    order (rk_mj.c's invert, rk_la_solve); y may be x itself (its entry i is read before x[i] is written)."""
    for i in range(len(lu) - 1, -1, -1):
        s = y[i]
        row = lu[i]
        for j in range(i + 1, len(lu)):
            s -= row[j] * x[j]
        x[i] = s / row[i]


def lu_inverse(A: np.ndarray) -> np.ndarray:
    """A^-1 by LU with partial pivoting (the first largest |entry|, as LAPACK's getrf) and the columns of the
    identity solved, operation for operation as the C engine's Moreau-Jean (rk_mj.c's invert)."""
    n = A.shape[0]
    lu = A.tolist()
    piv = list(range(n))
    for k in range(n):
        p, big = k, abs(lu[k][k])
        for i in range(k + 1, n):
            if abs(lu[i][k]) > big:
                big, p = abs(lu[i][k]), i
        if big == 0.0:
            raise np.linalg.LinAlgError("Singular matrix")
        if p != k:
            piv[k], piv[p] = piv[p], piv[k]
            lu[k], lu[p] = lu[p], lu[k]
        for i in range(k + 1, n):
            row_i, row_k = lu[i], lu[k]
            l = row_i[k] / row_k[k]
            row_i[k] = l
            for j in range(k + 1, n):
                row_i[j] -= l * row_k[j]
    inv = [[0.0] * n for _ in range(n)]
    for j in range(n):
        x = [0.0] * n
        for i in range(n):
            s = 1.0 if piv[i] == j else 0.0
            row = lu[i]
            for k in range(i):
                s -= row[k] * x[k]
            x[i] = s
        _back_substitute(lu, x, x)
        for i in range(n):
            inv[i][j] = x[i]
    return np.array(inv, dtype=float)


def solve(A: np.ndarray, b) -> np.ndarray:
    """np.linalg.solve(A, b) for a square A and a 1-D b: LU with partial pivoting (the first largest |entry|),
    failing only on an exactly zero pivot as LAPACK's gesv (LinAlgError "Singular matrix"), operation for
    operation as the C engine's rk_la_solve (rk_model.c)."""
    lu = np.asarray(A, dtype=float).tolist()
    y = [float(a) for a in b]
    n = len(y)
    x = [0.0] * n
    for k in range(n):
        p, best = k, abs(lu[k][k])
        for i in range(k + 1, n):
            if abs(lu[i][k]) > best:
                best, p = abs(lu[i][k]), i
        if p != k:
            lu[k], lu[p] = lu[p], lu[k]
            y[k], y[p] = y[p], y[k]
        row_k = lu[k]
        if row_k[k] == 0.0:
            raise np.linalg.LinAlgError("Singular matrix")
        for i in range(k + 1, n):
            row_i = lu[i]
            l = row_i[k] / row_k[k]
            row_i[k] = l
            for j in range(k + 1, n):
                row_i[j] -= l * row_k[j]
            y[i] -= l * y[k]
    _back_substitute(lu, y, x)
    return np.array(x, dtype=float)


#: [1] machine epsilon of a double (C's DBL_EPSILON)
_EPS = 2.220446049250313e-16


def lstsq(A: np.ndarray, b, rcond: float | None) -> np.ndarray:
    """np.linalg.lstsq(A, b, rcond)[0] for a 2-D A and a 1-D b: the minimum-norm least-squares solution, the
    singular values at most rcond * s_max dropped (rcond None: eps * max(rows, cols), numpy's default), from a
    one-sided Jacobi SVD, operation for operation as the C engine's rk_la_lstsq (rk_model.c). numpy's gelsd
    agrees to round-off only, and rounds per CPU."""
    A_rows = np.asarray(A, dtype=float).tolist()
    rows, cols = len(A_rows), len(A_rows[0]) if A_rows else 0
    if rcond is None or rcond < 0.0:
        rcond = _EPS * max(rows, cols)
    # columns as lists (the rotations act on pairs of columns of U and V): the same operations as the C's
    # row-major loops, each column's sums in row order
    U = [list(col) for col in zip(*A_rows)] if rows else [[] for _ in range(cols)]
    V = [[1.0 if i == j else 0.0 for i in range(cols)] for j in range(cols)]       # V[j]: column j
    sqrt = math.sqrt
    for _sweep in range(60):
        rotated = False
        for j in range(cols - 1):
            for k in range(j + 1, cols):
                uj, uk = U[j], U[k]
                alpha = beta = gamma = 0.0
                for p, q in zip(uj, uk):
                    alpha += p * p
                    beta += q * q
                    gamma += p * q
                if gamma == 0.0 or abs(gamma) <= _EPS * sqrt(alpha * beta):
                    continue
                rotated = True
                zeta = (beta - alpha) / (2.0 * gamma)
                t = (1.0 if zeta >= 0.0 else -1.0) / (abs(zeta) + sqrt(1.0 + zeta * zeta))
                c = 1.0 / sqrt(1.0 + t * t)
                sn = c * t
                U[j] = [c * u1 - sn * u2 for u1, u2 in zip(uj, uk)]
                U[k] = [sn * u1 + c * u2 for u1, u2 in zip(uj, uk)]
                vj, vk = V[j], V[k]
                V[j] = [c * v1 - sn * v2 for v1, v2 in zip(vj, vk)]
                V[k] = [sn * v1 + c * v2 for v1, v2 in zip(vj, vk)]
        if not rotated:
            break
    s = []
    for col in U:
        nrm = 0.0
        for p in col:
            nrm += p * p
        s.append(sqrt(nrm))
    smax = max([0.0] + s)
    bs = [float(a) for a in b]
    x = [0.0] * cols
    for j in range(cols):
        if not (s[j] > rcond * smax) or s[j] == 0.0:
            continue
        ub = 0.0
        for u, bi in zip(U[j], bs):
            ub += u * bi
        ub /= s[j] * s[j]               # U's column j is s_j times the unit singular vector
        vj = V[j]
        for i in range(cols):
            x[i] += vj[i] * ub
    return np.array(x, dtype=float)
