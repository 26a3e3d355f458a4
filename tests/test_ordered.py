"""rocking_model/_ordered.py: the Python reference's small matrix products and inverses in the C engine's
operation order (numpy's BLAS/LAPACK kernels round per CPU, and may fuse multiply-adds)."""
from __future__ import annotations

import numpy as np
import pytest

from rocking_model._ordered import inverse, lstsq, lu_inverse, matmul, matvec, solve


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


def _deficient(rng, rows, cols, rank):
    """A rows x cols matrix of the given rank (rank 0: zeros)."""
    return rng.normal(size=(rows, rank)) @ rng.normal(size=(rank, cols)) if rank else np.zeros((rows, cols))


@pytest.mark.parametrize("seed", range(12))
def test_solve_and_lstsq_are_the_c_engines_bit_for_bit(seed):
    """solve / lstsq run rk_la_solve / rk_la_lstsq (rk_model.c) operation for operation, on square systems of
    full and deficient rank and on rectangular ones (the sliding modes' J), with rcond 1e-12 and numpy's
    default; they agree with numpy's LAPACK to round-off."""
    from rocking_model import _engine

    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 7))
    cols = n if seed % 3 else int(rng.integers(1, n + 1))
    rank = min(n, cols) if seed % 2 else int(rng.integers(0, min(n, cols)))
    A, b = _deficient(rng, n, cols, rank), rng.normal(size=n)
    if seed % 4 == 1:
        A[:, 0] *= 1e-9                                        # badly scaled: pivoting and the rcond cut
    for rcond, c_rcond in ((1e-12, 1e-12), (None, -1.0)):
        x = lstsq(A, b, rcond=rcond)
        c = _engine.model_la("lstsq", n, cols, A.ravel().tolist(), b.tolist(), c_rcond)
        assert x.tolist() == c
        ref = np.linalg.lstsq(A, b, rcond=rcond)[0]
        np.testing.assert_allclose(x, ref, rtol=1e-8, atol=1e-8 * max(1.0, float(np.max(np.abs(ref)))))
    if cols == n:
        c = _engine.model_la("solve", n, n, A.ravel().tolist(), b.tolist(), 0.0)
        try:
            x = solve(A, b)
        except np.linalg.LinAlgError as exc:
            assert c is None and str(exc) == "Singular matrix"
        else:
            assert x.tolist() == c
            if rank == n:
                np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-9, atol=1e-9)


def test_solve_fails_only_on_an_exactly_zero_pivot():
    """As LAPACK's gesv: a matrix singular to round-off is solved (the caller's residual test decides), an
    exactly zero pivot raises numpy's LinAlgError."""
    A = np.array([[1.0, 2.0], [2.0, 4.0 + 1e-15]])
    assert np.all(np.isfinite(solve(A, [1.0, 1.0])))
    with pytest.raises(np.linalg.LinAlgError, match="Singular matrix"):
        solve(np.array([[1.0, 2.0], [2.0, 4.0]]), [1.0, 1.0])
    assert lstsq(np.zeros((2, 2)), [1.0, 1.0], rcond=1e-12).tolist() == [0.0, 0.0]
