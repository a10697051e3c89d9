"""LAPACK ``dsyevr`` called from compiled code (numba; imported only when kernels run).

:func:`syevr_second_kernel` is the call :func:`tether.graph.fiedler._subset` makes
through scipy's f2py wrapper (``scipy.linalg.lapack.dsyevr(a, compute_v=1, range="I",
il=2, iu=2, lower=1, lwork=..., liwork=...)``): the same routine of the same library
(scipy's ``cython_lapack`` exports the LAPACK that scipy links), with the same
arguments -- ``jobz = 'V'``, ``range = 'I'``, ``uplo = 'L'``, ``il = iu = 2``,
``vl = 0``, ``vu = 1``, ``abstol = 0``, ``ldz = n`` and the workspace sizes the caller
passes (the f2py wrapper's query, :func:`tether.graph.fiedler._syevr_lwork`) -- so the
same bits (``tests/test_lapack_kernels.py``), without the wrapper's argument checks and
array copies, so that a kernel can solve the second eigenpair inside its own call.

LAPACK: Anderson et al., *LAPACK Users' Guide*, 3rd ed., SIAM 1999 (``xSYEVR``: Dhillon,
Parlett, "Multiple representations to compute orthogonal eigenvectors", 2004).
"""

from __future__ import annotations

import llvmlite.binding as ll
import numpy as np
from numba import njit, types
from numba.extending import get_cython_function_address

#: dsyevr's 21 arguments are pointers; the routine is linked by name, so that numba can
#: cache the kernels that call it (a ctypes function pointer would be a dynamic global)
_SYMBOL = "tether_cython_lapack_dsyevr"
ll.add_symbol(_SYMBOL, get_cython_function_address("scipy.linalg.cython_lapack", "dsyevr"))
_dsyevr = types.ExternalFunction(_SYMBOL, types.void(*([types.voidptr] * 21)))

#: the characters 'V', 'I', 'L' (jobz, range, uplo)
_V, _I, _L = ord("V"), ord("I"), ord("L")


@njit(cache=True)
def syevr_second_kernel(lap, lwork, liwork):  # noqa: ANN001, ANN201
    """The second-smallest eigenpair of the symmetric ``(n, n)`` ``lap`` by ``dsyevr``.

    Returns ``(value, vector, m, info)`` as the f2py wrapper's ``w[0]``, ``z[:, 0]``,
    ``m`` and ``info`` (``lap`` is not changed: LAPACK works on a copy). ``lap`` must be
    exactly symmetric (it is read as its lower triangle in column-major order, which is
    its upper triangle in row-major order).
    """
    n = lap.shape[0]
    a = lap.copy()  # C order; exactly symmetric, so the same matrix in Fortran order
    jobz = np.full(1, _V, np.uint8)
    rng = np.full(1, _I, np.uint8)
    uplo = np.full(1, _L, np.uint8)
    ints = np.empty(8, np.int32)  # n, lda, il, iu, m, ldz, lwork, liwork
    ints[0], ints[1], ints[2], ints[3] = n, n, 2, 2
    ints[4], ints[5], ints[6], ints[7] = 0, n, lwork, liwork
    info = np.zeros(1, np.int32)
    reals = np.array([0.0, 1.0, 0.0])  # vl, vu, abstol: the wrapper's defaults
    w = np.zeros(n)
    z = np.zeros(n)  # (ldz = n, 1): one column
    isuppz = np.zeros(2, np.int32)
    work = np.zeros(max(lwork, 1))
    iwork = np.zeros(max(liwork, 1), np.int32)
    _dsyevr(
        jobz.ctypes, rng.ctypes, uplo.ctypes, ints[0:].ctypes, a.ctypes, ints[1:].ctypes,
        reals[0:].ctypes, reals[1:].ctypes, ints[2:].ctypes, ints[3:].ctypes, reals[2:].ctypes,
        ints[4:].ctypes, w.ctypes, z.ctypes, ints[5:].ctypes, isuppz.ctypes, work.ctypes,
        ints[6:].ctypes, iwork.ctypes, ints[7:].ctypes, info.ctypes,
    )  # fmt: skip
    return w[0], z, int(ints[4]), int(info[0])


def warm_up() -> None:
    """Compile (or load) the kernel on a 3-node path graph."""
    lap = np.array([[1.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
    syevr_second_kernel(lap, 78, 30)
