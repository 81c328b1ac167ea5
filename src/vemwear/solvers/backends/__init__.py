"""Sparse direct backends behind one interface (see :mod:`.base`).

========  ==========================================================  ==============
name      Schur complement on the contact dofs                        installed by
========  ==========================================================  ==============
pardiso   MKL PARDISO, partial Cholesky factorization (iparm[35])     ``pypardiso``
scipy     SciPy's SuperLU, trailing block of the full LU factors      always
petsc     MUMPS through PETSc, on the ranks of an MPI job (ICNTL(19))  ``petsc4py``
========  ==========================================================  ==============

``"auto"`` picks the first installed backend of :data:`PREFERENCE` (PARDISO's Schur
factorization on one MKL thread below :data:`SCHUR_SERIAL_MAX` unknowns); ``"petsc"`` is
only used when asked for (``mpirun -n N vemwear run ... --backend petsc``: docs/mpi.md),
and only for the Schur factorization of the condensed scheme. A new backend
(MUMPS through a binding that imports with the installed NumPy, for one; its Schur
output, ICNTL(19), is valid in the lower triangle only, which
:func:`.base.compliance_from_schur` already reads) is one module with a
``available()`` function and a class with the :class:`.base.SchurFactorization`
interface, plus one line in :data:`_MODULES`.
"""

from __future__ import annotations

import hashlib
import importlib
from collections import OrderedDict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from .base import Factorization, SchurFactorization, compliance_from_schur
from .petsc import HINT as _PETSC_HINT

BACKENDS = ("auto", "scipy", "pardiso", "petsc")

#: Installed backends are tried in this order by ``"auto"``.
PREFERENCE = ("pardiso", "scipy")

#: Backends used only when asked for (MUMPS over the ranks of an MPI job).
ON_REQUEST = ("petsc",)

#: Below this many unknowns SuperLU factorizes about as fast as PARDISO; the
#: full-space Newton path (a new factorization per iteration) uses PARDISO above it.
PARDISO_MIN_SIZE = 20_000

#: Below this many unknowns the Schur factorization of ``"auto"`` runs PARDISO on one
#: MKL thread: waking a second thread for each phase costs more than it gains (2.0 and
#: 1.5 times faster at 1,088 and 4,224 unknowns, README.md "Against GetFEM"), and
#: SuperLU was slower than both at every size measured.
SCHUR_SERIAL_MAX = 20_000

_MODULES = {"scipy": ".superlu", "pardiso": ".pardiso", "petsc": ".petsc"}
_HINT = {
    "pardiso": "pip install 'vemwear[fast]' (needs MKL wheels: Linux or Windows x86_64)",
    "petsc": _PETSC_HINT,
}


def _module(name: str) -> Any:
    return importlib.import_module(_MODULES[name], __name__)


def is_available(name: str) -> bool:
    """True when the backend ``name`` can be used on this machine."""
    if name == "scipy":
        return True
    mod = _module(name)
    return bool(mod.available())


def available_backends() -> list[str]:
    """The installed backends, fastest first."""
    return [b for b in PREFERENCE if is_available(b)]


def resolve_backend(backend: str = "auto", size: int = 0, many_factorizations: bool = False) -> str:
    """The backend used for ``backend``: ``"auto"`` becomes the fastest installed one.

    ``many_factorizations`` (with ``size``) describes the full-space Newton path, a new
    factorization per iteration: there ``"auto"`` keeps SuperLU for matrices below
    :data:`PARDISO_MIN_SIZE` unknowns.

    Raises
    ------
    ValueError
        For an unknown name or a backend that is not installed.
    """
    if backend not in BACKENDS:
        raise ValueError(f"unknown linear-algebra backend {backend!r}; expected one of {BACKENDS}")
    if backend == "auto":
        if many_factorizations and size < PARDISO_MIN_SIZE:
            return "scipy"
        return available_backends()[0]
    if not is_available(backend):
        raise ValueError(
            f"backend {backend!r} asked for but it is not installed ({_HINT.get(backend, '')})"
        )
    return backend


def factorize(
    A: sp.spmatrix,
    backend: str = "auto",
    *,
    symmetric: bool = True,
    many_factorizations: bool = False,
) -> Factorization:
    """Factorize a sparse matrix once; the result solves for any number of right-hand sides.

    ``symmetric`` declares ``A`` SPD (SuperLU's symmetric mode, PARDISO's Cholesky);
    ``many_factorizations`` tells ``"auto"`` that the caller factorizes again and again
    (see :func:`resolve_backend`).
    """
    from ..stiffness import Stiffness

    if isinstance(A, Stiffness):
        raise ValueError(
            "the stiffness kept by the MPI ranks (backend 'petsc') makes the Schur "
            "factorization of the condensed Newton (method 'newton') only"
        )
    chosen = resolve_backend(backend, A.shape[0], many_factorizations)
    if chosen == "petsc":
        raise ValueError(
            "backend 'petsc' makes the Schur factorization of the condensed Newton "
            "(method 'newton') only"
        )
    with _failures(chosen):
        if chosen == "pardiso":
            return _module("pardiso").PardisoFactor(A, spd=symmetric)
        return _module("scipy").SuperLUFactor(A, symmetric=symmetric)


#: Schur factorizations kept for reuse (see :func:`keep_factorizations`), newest last.
_KEPT: OrderedDict[bytes, SchurFactorization] = OrderedDict()
_KEEP = 0


def keep_factorizations(n: int) -> None:
    """Keep the last ``n`` Schur factorizations of this process for reuse (0: none, the
    default).

    Runs of a parameter study that change only the contact data, the loads or the time
    grid (kappa, mu, g, the compliance law, v*) have the same stiffness and the same
    contact dofs; with ``n >= 1`` the second such run in a process reuses the first
    one's factorization instead of computing it again. Factorizations are recognised by
    a digest of the matrix, the Schur dofs, the dof points and the backend, so a reused
    one is that of the same matrix, and the results are bitwise those of a fresh one
    (the factorizations are not changed by solving). Each kept factorization holds its
    memory until it is evicted.
    """
    global _KEEP
    if n < 0:
        raise ValueError(f"keep_factorizations: n must be >= 0, got {n}")
    _KEEP = int(n)
    while len(_KEPT) > _KEEP:
        _KEPT.popitem(last=False)


@contextmanager
def reusing_factorizations() -> Iterator[Callable[[], None]]:
    """Keep at least the last Schur factorization in this block (:func:`keep_factorizations`),
    and the caller's limit again after it.

    Yields ``forget``, which drops the factorizations kept so far: a caller about to
    factorize another matrix calls it first, so that the old factors do not stay in
    memory beside the new ones. An adaptive run keeps the factorization of a mesh that
    the next segment uses again.
    """
    previous = _KEEP
    keep_factorizations(max(previous, 1))

    def forget() -> None:
        _KEPT.clear()

    try:
        yield forget
    finally:
        keep_factorizations(previous)


def _digest(K: sp.spmatrix, *arrays: NDArray[Any], backend: str) -> bytes:
    A = sp.csr_matrix(K)
    h = hashlib.blake2b(digest_size=20)
    h.update(backend.encode())
    for a in (np.asarray(A.shape), A.indptr, A.indices, A.data, *arrays):
        a = np.ascontiguousarray(a)
        h.update(str((a.dtype.str, a.shape)).encode())
        h.update(a.data)
    return h.digest()


def schur_factorize(
    K: Any,
    last: NDArray[np.int64],
    points: NDArray[np.float64],
    backend: str = "auto",
    assembly: Any = None,
) -> SchurFactorization:
    """Factorize SPD ``K`` once, with the block of ``K^{-1}`` on the dofs ``last``.

    With :func:`keep_factorizations` on, a factorization of the same matrix and dofs
    made earlier in this process is returned instead. ``"auto"`` factorizes with
    PARDISO on one MKL thread below :data:`SCHUR_SERIAL_MAX` unknowns.

    Parameters
    ----------
    K : (n, n) sparse SPD matrix (the stiffness on the free dofs), or (backend petsc)
        the operator of one kept by the MPI ranks (:mod:`.petsc_operator`)
    last : (c,) dof ids of the Schur block (the contact dofs), in the order wanted
    points : (n, 2) coordinates of each dof's vertex (SuperLU's geometric ordering)
    backend : a name of :data:`BACKENDS`
    assembly : optional
        K as a sum over cells (:attr:`vemwear.solvers.system.ContactSystem.assembly`):
        the petsc backend assembles its distributed matrix from the ranks' cells with
        it instead of sending K's rows from rank 0; the other backends factorize K.
    """
    from ..stiffness import Stiffness

    chosen = resolve_backend(backend)
    # K kept by the MPI ranks (an operator) is factorized where it is, and not kept for
    # reuse: it is not recognised by a digest of its entries, which rank 0 does not hold
    kept = _KEEP and not isinstance(K, Stiffness)
    if isinstance(K, Stiffness) and chosen != "petsc":
        raise ValueError(
            "the stiffness kept by the MPI ranks is factorized by the petsc backend, "
            f"not {chosen!r}"
        )
    serial = chosen == "pardiso" and backend == "auto" and K.shape[0] < SCHUR_SERIAL_MAX
    key = _digest(K, last, points, backend=chosen + " serial" * serial) if kept else b""
    if key in _KEPT:
        _KEPT.move_to_end(key)
        return _KEPT[key]
    with _failures(chosen), _one_mkl_thread(serial):
        if chosen == "pardiso":
            factor: SchurFactorization = _module("pardiso").PardisoSchur(K, last, points)
        elif chosen == "petsc":
            factor = _module("petsc").PetscSchur(K, last, points, assembly=assembly)
        else:
            factor = _module("scipy").SuperLUSchur(K, last, points)
    if kept:
        _KEPT[key] = factor
        while len(_KEPT) > _KEEP:
            _KEPT.popitem(last=False)
    return factor


@contextmanager
def _one_mkl_thread(on: bool) -> Iterator[None]:
    """MKL on one thread for this thread while the enclosed factorization is made (its
    handle keeps the count for every later solve)."""
    if not on:
        yield
        return
    set_local = _module("pardiso")._thread_functions()[1]
    previous = set_local(1)
    try:
        yield
    finally:
        set_local(previous)


@contextmanager
def _failures(backend: str) -> Iterator[None]:
    """A failed factorization (singular or indefinite matrix) as a FactorizationError."""
    from ..system import FactorizationError

    try:
        yield
    except (RuntimeError, np.linalg.LinAlgError) as exc:
        raise FactorizationError(
            f"the stiffness matrix could not be factorized ({backend}: {exc}); it is singular "
            "or not positive definite (rigid motions not removed, or material data out of range)"
        ) from None


__all__ = [
    "BACKENDS",
    "ON_REQUEST",
    "PARDISO_MIN_SIZE",
    "PREFERENCE",
    "SCHUR_SERIAL_MAX",
    "Factorization",
    "SchurFactorization",
    "available_backends",
    "compliance_from_schur",
    "factorize",
    "is_available",
    "keep_factorizations",
    "resolve_backend",
    "reusing_factorizations",
    "schur_factorize",
]
