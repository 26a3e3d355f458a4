"""rocking_model/_ordered.py: the Python reference's small matrix products and inverses in the C engine's
operation order (numpy's BLAS/LAPACK kernels round per CPU, and may fuse multiply-adds)."""
from __future__ import annotations

import numpy as np
import pytest

from rocking_model._ordered import inverse, lu_inverse, matmul, matvec


def _seq(row, col):
    acc = 0.0
    for a, b in zip(row, col):
        acc = acc + a * b
    return acc


@pytest.mark.parametrize("seed", range(5))
def test_products_are_index_order_sums(seed):
    rng = np.random.default_rng(seed)
    m, n, p = (int(k) for k in rng.integers(1, 9, size=3))
    A, B, x = rng.normal(size=(m, n)), rng.normal(size=(n, p)), rng.normal(size=n)
    y = matvec(A, x)
    assert y.shape == (m,) and y.tolist() == [_seq(A[i].tolist(), x.tolist()) for i in range(m)]
    C = matmul(A, B)
    assert C.shape == (m, p)
    assert C.tolist() == [[_seq(A[i].tolist(), B[:, j].tolist()) for j in range(p)] for i in range(m)]
    np.testing.assert_allclose(y, A @ x, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(C, A @ B, rtol=1e-12, atol=1e-14)
    assert matvec(A, list(x)).tolist() == y.tolist()            # a list or an array: the same sums


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("invert", [inverse, lu_inverse])
def test_inverses_agree_with_numpy(seed, invert):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 9))
    Q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    A = Q @ np.diag(rng.uniform(0.5, 2.0, size=n)) @ Q.T + 0.3 * rng.normal(size=(n, n))
    Ainv = invert(A)
    np.testing.assert_allclose(Ainv, np.linalg.inv(A), rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(Ainv @ A, np.eye(n), atol=1e-10)


@pytest.mark.parametrize("invert", [inverse, lu_inverse])
def test_singular_matrix_is_numpys_error(invert):
    with pytest.raises(np.linalg.LinAlgError, match="Singular matrix"):
        invert(np.zeros((3, 3)))
