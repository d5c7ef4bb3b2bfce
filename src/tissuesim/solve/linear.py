"""Sparse linear solvers for the Newton system H dx = -g, with reusable analysis.

The matrix pattern never changes within a model (see ``assembly.pattern``), so a solver analyses
it once and then only refactorises numbers. Every ``factorize`` must get a matrix of the same
pattern as the first one.

- ``pardiso``: Intel MKL PARDISO through pypardiso's library loader (``tissuesim[fast]``, pip
  wheels only). Cholesky mode (mtype 2) on the upper triangle; analysis (phase 11) once, numeric
  factorisation (22) and solve (33) per iteration. The fastest direct solver in 2D here.
- ``cholmod``: CHOLMOD via scikit-sparse (optional extra ``tissuesim[cholmod]``, which needs
  Debian's ``libsuitesparse-dev``). Symbolic analysis once, ``cholesky_inplace`` per iteration.
- ``splu``: SciPy's SuperLU, always available. SciPy exposes no reusable symbolic factorisation,
  so we reuse its fill-reducing column ordering (computed on the first matrix) instead.
- ``cg`` / ``amg``: conjugate gradients preconditioned by Jacobi, or by smoothed-aggregation AMG
  (``tissuesim[amg]``) built with the rigid-body modes of the mesh as near-null space (6x fewer
  CG iterations in 3D elasticity than without) and a *lagged* hierarchy: it is rebuilt only
  when CG needs more than ``rebuild_growth`` times the iterations it needed right after the last
  rebuild, so its setup is paid about once per few Newton iterations or time steps.

Every direct solver raises ``NotPositiveDefiniteError`` on an indefinite matrix, which the Newton
solver uses to shift the Hessian (CG raises it when it does not converge).
"""

from __future__ import annotations

import functools
import importlib.util
import weakref
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from tissuesim.errors import InputError
from tissuesim.validate import short

__all__ = [
    "LinearSolver",
    "NotPositiveDefiniteError",
    "PardisoSolver",
    "CholmodSolver",
    "SuperLUSolver",
    "CGSolver",
    "make_linear_solver",
    "rigid_body_modes",
    "LINEAR_SOLVERS",
]

AMG_SEED = 20261201  # see _build_amg: repeatable AMG hierarchies
LINEAR_SOLVERS = ("auto", "pardiso", "cholmod", "splu", "cg", "amg")

#: 3D systems above this many DOFs go to AMG-CG under "auto" (docs/performance.md: at 59,049
#: DOFs lagged AMG-CG solved 4.5x faster than CHOLMOD; at 6,591 DOFs AMG-CG alone was faster
#: too, but the whole Newton iteration with it was slower than with CHOLMOD, 0.24 s against
#: 0.13 s, and a direct solver reports indefiniteness exactly).
AMG_MIN_DOFS_3D = 30_000
#: Without PARDISO or CHOLMOD, 3D FEM systems above this many DOFs go to CG (AMG-preconditioned
#: when pyamg is installed, else Jacobi) instead of SuperLU (``benchmarks/solver_choice.py``,
#: one thread, per iteration: 1,029 DOFs SuperLU 0.009 s, AMG-CG 0.010 s, Jacobi-CG 0.011 s;
#: 3,000 DOFs 0.121 / 0.036 / 0.042 s; 20,577 DOFs 4.68 / 0.21 / 0.51 s).
SPLU_MAX_DOFS_3D = 1_500
#: lambda / mu above which "auto" keeps to direct solvers: CG's iterations grow with the
#: condition number, which grows with lambda / mu (nu = 0.4545 at 10). Measured: a P2
#: mean-dilatation ellipsoid at nu = 0.49 (2,187 DOFs) took 3 s per AMG-CG solve, SuperLU 0.02 s
#: (benchmarks/liver_compression.py).
NEARLY_INCOMPRESSIBLE_RATIO = 10.0


class NotPositiveDefiniteError(RuntimeError):
    """The matrix is not positive definite (Cholesky failed or CG met negative curvature)."""


class LinearSolver:
    name = "base"

    def factorize(self, A: sp.csr_matrix) -> None:
        raise NotImplementedError

    def solve(self, b: np.ndarray) -> np.ndarray:
        raise NotImplementedError


def has_cholmod() -> bool:
    return importlib.util.find_spec("sksparse") is not None


def has_pyamg() -> bool:
    return importlib.util.find_spec("pyamg") is not None


def has_pardiso() -> bool:
    return importlib.util.find_spec("pypardiso") is not None


@functools.cache
def _mkl_pardiso():
    """MKL's pardiso function, located once per process: pypardiso finds mkl_rt by globbing
    the whole environment (0.2-0.5 s each time), and a new solver is made after every cut.
    Its import already made one (its scipy aliases' solver): that one's library is taken
    where present, not located a second time."""
    import pypardiso  # locates mkl_rt; we call PARDISO ourselves to control the phases

    made = getattr(getattr(pypardiso, "scipy_aliases", None), "pypardiso_solver", None)
    libmkl = getattr(made, "libmkl", None)
    if libmkl is None:
        libmkl = pypardiso.PyPardisoSolver().libmkl
    return libmkl.pardiso


class PardisoSolver(LinearSolver):
    """MKL PARDISO, real symmetric positive definite mode, with explicit phases."""

    name = "pardiso"
    _MTYPE = 2  # real SPD: Cholesky; error -4 on a non-positive pivot (indefinite matrix)

    def __init__(self) -> None:
        import ctypes
        from types import SimpleNamespace

        pardiso = _mkl_pardiso()
        i32 = ctypes.POINTER(ctypes.c_int32)
        pardiso.argtypes = [ctypes.POINTER(ctypes.c_int64), i32, i32, i32, i32, i32,
                            ctypes.c_void_p, i32, i32, i32, i32, i32, i32,
                            ctypes.c_void_p, ctypes.c_void_p, i32]  # fmt: skip
        pardiso.restype = None
        iparm = np.zeros(64, dtype=np.int32)
        iparm[[0, 1, 9, 34]] = (1, 2, 13, 1)  # own iparm; METIS; pivot eps 1e-13; 0-based
        # PARDISO's state apart from the solver, so that the finalizer that frees it holds
        # the state and not the solver (holding the solver kept every one alive: FEBio's
        # solver makes one per reformation, 17 GB in co40 before it was killed)
        self._h = SimpleNamespace(
            ct=ctypes, pardiso=pardiso, pt=np.zeros(64, dtype=np.int64), iparm=iparm,
            mtype=self._MTYPE, n=0, ia=None, ja=None, perm=None,
        )  # fmt: skip
        self._upper: np.ndarray | None = None
        self._finalizer = None

    def _call(self, phase: int, a: np.ndarray, b: np.ndarray, x: np.ndarray, nrhs: int = 1) -> int:
        return _pardiso_call(self._h, phase, a, b, x, nrhs)

    def factorize(self, A: sp.csr_matrix) -> None:
        if self._upper is not None and not _same_pattern(self._analysed, A):
            # contact pairs change the sparsity: analyse the new pattern
            self._finalizer()
            self._h.pt[:] = 0
            self._upper = None
        if self._upper is None:  # analysis, once per pattern: its upper triangle
            self._analysed = (A.indptr.copy(), A.indices.copy())
            A = A if A.has_sorted_indices else A.sorted_indices()
            rows = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
            self._upper = np.flatnonzero(A.indices >= rows)
            upper_rows = rows[self._upper]
            h = self._h
            h.n = A.shape[0]
            counts = np.bincount(upper_rows, minlength=h.n)
            h.ia = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
            h.ja = A.indices[self._upper].astype(np.int32)
            h.perm = np.zeros(h.n, dtype=np.int32)
            self._a = np.ascontiguousarray(A.data[self._upper])
            dummy = np.zeros(h.n)
            self._finalizer = weakref.finalize(self, _pardiso_release, h)
            if self._call(11, self._a, dummy, dummy.copy()) != 0:
                raise RuntimeError("PARDISO analysis failed")
        else:
            self._a = np.ascontiguousarray(A.data[self._upper])
        dummy = np.zeros(self._h.n)
        error = self._call(22, self._a, dummy, dummy.copy())
        if error == -4:
            raise NotPositiveDefiniteError("PARDISO: zero or negative pivot (matrix not SPD)")
        if error != 0:
            raise RuntimeError(f"PARDISO numeric factorisation failed (error {error})")

    def solve(self, b: np.ndarray) -> np.ndarray:
        """x with A x = b; b (n,) or (n, k): k right-hand sides in one call (PARDISO reads
        them column after column)."""
        if b.ndim == 2:
            B = np.asfortranarray(b, dtype=float)
            X = np.zeros_like(B, order="F")
            error = self._call(33, self._a, B, X, nrhs=B.shape[1])
        else:
            B = np.ascontiguousarray(b, dtype=float)
            X = np.zeros_like(B)
            error = self._call(33, self._a, B, X)
        if error != 0:
            raise RuntimeError(f"PARDISO solve failed (error {error})")
        return X


def _same_pattern(analysed: tuple[np.ndarray, np.ndarray], A: sp.csr_matrix) -> bool:
    """Whether A has the sparsity (indptr, indices) a symbolic analysis was made for."""
    indptr, indices = analysed
    return (
        indptr.shape == A.indptr.shape
        and indices.shape == A.indices.shape
        and np.array_equal(indptr, A.indptr)
        and np.array_equal(indices, A.indices)
    )


def _pardiso_call(h, phase: int, a: np.ndarray, b: np.ndarray, x: np.ndarray, nrhs: int = 1) -> int:
    """One call of PARDISO on the state ``h`` (PardisoSolver._h); its error code."""
    ct, i32 = h.ct, h.ct.c_int32
    error = i32(0)
    h.pardiso(
        h.pt.ctypes.data_as(ct.POINTER(ct.c_int64)),
        ct.byref(i32(1)), ct.byref(i32(1)), ct.byref(i32(h.mtype)),
        ct.byref(i32(phase)), ct.byref(i32(h.n)), a.ctypes.data,
        h.ia.ctypes.data_as(ct.POINTER(i32)), h.ja.ctypes.data_as(ct.POINTER(i32)),
        h.perm.ctypes.data_as(ct.POINTER(i32)), ct.byref(i32(nrhs)),
        h.iparm.ctypes.data_as(ct.POINTER(i32)), ct.byref(i32(0)),
        b.ctypes.data, x.ctypes.data, ct.byref(error),
    )  # fmt: skip
    return int(error.value)


def _pardiso_release(h) -> None:
    """Phase -1: free PARDISO's internal memory (it is not Python-managed)."""
    dummy = np.zeros(1)
    try:
        _pardiso_call(h, -1, dummy, dummy, dummy.copy())
    except Exception:  # interpreter shutdown: the library may already be gone
        pass


class CholmodSolver(LinearSolver):
    name = "cholmod"

    def __init__(self) -> None:
        from sksparse import cholmod

        self._cholmod = cholmod
        self._factor = None

    def factorize(self, A: sp.csr_matrix) -> None:
        # A symmetric CSR matrix read as CSC is itself: no conversion needed.
        csc = sp.csc_matrix((A.data, A.indices, A.indptr), shape=A.shape)
        if self._factor is not None and not _same_pattern(self._analysed, A):
            self._factor = None  # contact pairs change the sparsity: analyse the new pattern
        try:
            if self._factor is None:
                self._analysed = (A.indptr.copy(), A.indices.copy())
                self._factor = self._cholmod.analyze(csc, mode="supernodal")
            self._factor.cholesky_inplace(csc)
        except self._cholmod.CholmodNotPositiveDefiniteError as exc:
            raise NotPositiveDefiniteError(str(exc)) from exc

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self._factor(b)


class SuperLUSolver(LinearSolver):
    name = "splu"

    def __init__(self) -> None:
        self._perm: np.ndarray | None = None
        self._lu = None

    def factorize(self, A: sp.csr_matrix) -> None:
        try:
            self._factorize(A)
        except RuntimeError as exc:  # "exactly singular": not positive definite either
            raise NotPositiveDefiniteError(str(exc)) from exc

    def _factorize(self, A: sp.csr_matrix) -> None:
        # Newton's matrix is symmetric positive definite (shifted when it is not): pivot on
        # the diagonal only (DiagPivotThresh 0). Partial pivoting picks off-diagonal pivots
        # where stiff terms (near-incompressible volume, contact barriers) dwarf others, and
        # fills in: 30x the fill on a Cook's membrane at nu = 0.4999 (issue 14)
        options = {"SymmetricMode": True, "DiagPivotThresh": 0.0}
        if self._perm is not None and (
            A.shape != self._lu.shape or abs(A.nnz - self._analysed_nnz) > 0.02 * self._analysed_nnz
        ):
            # contact pairs changed the sparsity much: a new fill-reducing order (any order is
            # valid; one made for a pattern close to this one keeps the fill low)
            self._perm = None
        if self._perm is None:
            self._analysed_nnz = A.nnz
            self._lu = spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", options=options)
            # perm_c sends column j to position perm_c[j]; the ordering as a gather index
            # (A[p][:, p]) is its inverse. Using perm_c itself gave 4x the fill and 20x the
            # time on a coupled organ/tissue matrix.
            self._perm = np.argsort(self._lu.perm_c)
            self._permuted = False
            return
        p = self._perm
        self._lu = spla.splu(A[p][:, p].tocsc(), permc_spec="NATURAL", options=options)
        self._permuted = True

    def solve(self, b: np.ndarray) -> np.ndarray:
        if not self._permuted:
            return self._lu.solve(b)
        p = self._perm
        x = np.empty_like(b)
        x[p] = self._lu.solve(b[p])
        return x


def rigid_body_modes(points: np.ndarray) -> np.ndarray:
    """Translations and infinitesimal rotations of ``points`` (n, d) as DOF vectors (n*d, k):
    the near-null space of elasticity, which smoothed-aggregation AMG needs to coarsen well."""
    n, d = points.shape
    c = points - points.mean(axis=0)
    if d == 2:
        B = np.zeros((n, 2, 3))
        B[:, 0, 0] = B[:, 1, 1] = 1.0
        B[:, 0, 2], B[:, 1, 2] = -c[:, 1], c[:, 0]
        return B.reshape(2 * n, 3)
    B = np.zeros((n, 3, 6))
    B[:, 0, 0] = B[:, 1, 1] = B[:, 2, 2] = 1.0
    for k, (i, j) in enumerate(((0, 1), (1, 2), (2, 0))):  # rotation in the (i, j) plane
        B[:, i, 3 + k], B[:, j, 3 + k] = -c[:, j], c[:, i]
    return B.reshape(3 * n, 6)


@dataclass
class CGStats:
    iterations: int = 0  # CG iterations, all solves
    solves: int = 0
    setups: int = 0  # AMG hierarchies built


class CGSolver(LinearSolver):
    """Preconditioned CG to a relative residual ``rtol``; Jacobi or AMG preconditioner.

    points: rest positions (n, d), for the AMG's rigid-body near-null space (optional).
    rebuild_growth: the AMG hierarchy is kept across factorisations until a solve needs more
    than this factor times the iterations of the first solve after the last rebuild; 1.0 or less
    rebuilds it every time.
    """

    def __init__(
        self,
        preconditioner: str = "jacobi",
        rtol: float = 1e-8,
        maxiter: int = 5000,
        points: np.ndarray | None = None,
        rebuild_growth: float = 2.0,
    ):
        self.preconditioner = preconditioner
        self.name = f"cg+{preconditioner}"
        self.rtol = rtol
        self.maxiter = maxiter
        self.stats = CGStats()
        self._B = rigid_body_modes(points) if points is not None else None
        self.rebuild_growth = rebuild_growth
        self._M = None
        self._reference_iterations: int | None = None  # iterations right after a rebuild
        self.amg_matrix: sp.csr_matrix | None = None  # the hierarchy's matrix (checkpoints)

    def factorize(self, A: sp.csr_matrix) -> None:
        self._A = A
        if self.preconditioner == "amg":
            lagged = self._M is not None and self.rebuild_growth > 1.0
            if not lagged:
                self._build_amg()
        else:
            diag = A.diagonal()
            if np.any(diag <= 0):
                raise NotPositiveDefiniteError("non-positive diagonal entry")
            inv = 1.0 / diag
            self._M = spla.LinearOperator(A.shape, matvec=lambda v: inv * v, dtype=float)

    def _build_amg(self) -> None:
        import pyamg

        # coarse_solver="splu": pyamg's default ("pinv") forms a dense pseudo-inverse (seconds).
        # pyamg starts its spectral-radius estimates from numpy's global random generator: seed
        # it for the set-up (and restore the caller's state) so runs are bit-for-bit repeatable
        state = np.random.get_state()  # noqa: NPY002 (pyamg uses the legacy global)
        np.random.seed(AMG_SEED)  # noqa: NPY002
        try:
            ml = pyamg.smoothed_aggregation_solver(
                self._A, B=self._B, symmetry="symmetric", coarse_solver="splu"
            )
        finally:
            np.random.set_state(state)  # noqa: NPY002
        self._M = ml.aspreconditioner(cycle="V")
        self.amg_matrix = self._A
        self._reference_iterations = None
        self.stats.setups += 1

    def _cg(self, b: np.ndarray) -> tuple[np.ndarray, int, int]:
        count = [0]

        def callback(_):
            count[0] += 1

        x, info = spla.cg(
            self._A, b, rtol=self.rtol, maxiter=self.maxiter, M=self._M, callback=callback
        )
        return x, info, count[0]

    def solve(self, b: np.ndarray) -> np.ndarray:
        x, info, its = self._cg(b)
        if self.preconditioner == "amg":
            ref = self._reference_iterations
            stale = ref is not None and (info != 0 or its > self.rebuild_growth * max(ref, 5))
            if stale:  # the lagged hierarchy no longer fits this matrix: rebuild, solve again
                self.stats.iterations += its
                self._build_amg()
                x, info, its = self._cg(b)
            if self._reference_iterations is None:
                self._reference_iterations = its
        self.stats.iterations += its
        self.stats.solves += 1
        if info != 0 or not np.all(np.isfinite(x)):
            raise NotPositiveDefiniteError(f"CG did not converge (info={info})")
        return x


def make_linear_solver(
    name: str,
    n_dofs: int,
    dim: int,
    points: np.ndarray | None = None,
    volumetric_ratio: float = 0.0,
    quadratic: bool = False,
) -> tuple[LinearSolver, str]:
    """Build the solver called ``name`` (see ``LINEAR_SOLVERS``); returns (solver, reason).

    points: rest positions (n, d), used by AMG for the rigid-body near-null space.
    volumetric_ratio: the largest lambda / mu of the bodies; above NEARLY_INCOMPRESSIBLE_RATIO
    "auto" chooses a direct solver at any size. quadratic: a body has P2 elements; "auto" then
    chooses a direct solver too (smoothed aggregation on P2 nodes: a 6x6x6 P2 box at nu = 0.45
    took 79.6 s for a load step with AMG-CG, 8.1 s with SuperLU)."""
    if name not in LINEAR_SOLVERS:
        raise InputError(f"linear_solver must be one of {LINEAR_SOLVERS}, not {short(name)}")
    if name == "pardiso":
        if not has_pardiso():
            raise InputError(
                "linear_solver 'pardiso' needs pypardiso: pip install 'tissuesim[fast]'"
            )
        return PardisoSolver(), "requested"
    if name == "cholmod":
        if not has_cholmod():
            raise InputError(
                "linear_solver 'cholmod' needs scikit-sparse: apt-get install libsuitesparse-dev, "
                "then pip install 'tissuesim[cholmod]'"
            )
        return CholmodSolver(), "requested"
    if name == "splu":
        return SuperLUSolver(), "requested"
    if name == "cg":
        return CGSolver("jacobi"), "requested"
    if name == "amg":
        if not has_pyamg():
            raise InputError("linear_solver 'amg' needs pyamg: pip install 'tissuesim[amg]'")
        return CGSolver("amg", points=points), "requested"
    # auto (benchmarks/solvers.py): AMG-CG for large 3D; else a direct solver, PARDISO first in
    # 2D (fastest factorisation) and CHOLMOD first in 3D (PARDISO's 3D factorisation is slower).
    large_3d = dim == 3 and n_dofs > AMG_MIN_DOFS_3D
    why = ""
    if volumetric_ratio > NEARLY_INCOMPRESSIBLE_RATIO:
        why = (
            f"nearly incompressible (lambda/mu {volumetric_ratio:.3g} > "
            f"{NEARLY_INCOMPRESSIBLE_RATIO:g}: CG converges slowly there)"
        )
    elif quadratic:
        why = "quadratic elements (AMG-CG converges slowly on P2 nodes)"
    if why:
        for label, available, cls in (
            ("pardiso", has_pardiso, PardisoSolver),
            ("cholmod", has_cholmod, CholmodSolver),
        ):
            if available():
                return cls(), f"auto: {label}, {why}"
        return SuperLUSolver(), f"auto: SciPy SuperLU, {why}"
    # AMG needs the rigid-body modes (one FEM body's vertices) to beat a direct solver: on two
    # bodies in contact without them it took 20 s per Newton iteration at 48k DOFs, PARDISO
    # 0.3-0.8 s (docs/performance.md); without contact 0.9 s against 0.09 s
    if large_3d and has_pyamg() and points is not None:
        return CGSolver("amg", points=points), (
            f"auto: 3D with {n_dofs} DOFs > {AMG_MIN_DOFS_3D}, pyamg available"
        )
    direct = [("pardiso", has_pardiso, PardisoSolver), ("cholmod", has_cholmod, CholmodSolver)]
    if dim == 3:
        direct.reverse()
    for label, available, cls in direct:
        if available():
            return cls(), f"auto: {label} available, {dim}D with {n_dofs} DOFs"
    # without a fast direct solver, SuperLU's 3D fill makes CG faster from a few thousand DOFs
    # on; only where the rigid-body modes are known (FEM vertices): AMG needs them, and the
    # frames' and coupled systems' conditioning was not measured with CG
    if dim == 3 and points is not None and n_dofs > SPLU_MAX_DOFS_3D:
        if has_pyamg():
            return CGSolver("amg", points=points), (
                f"auto: 3D with {n_dofs} DOFs > {SPLU_MAX_DOFS_3D}, no pypardiso or "
                "scikit-sparse, pyamg available (AMG-CG beats SuperLU there)"
            )
        return CGSolver("jacobi"), (
            f"auto: 3D with {n_dofs} DOFs > {SPLU_MAX_DOFS_3D}, no pypardiso, scikit-sparse or "
            "pyamg (Jacobi-CG beats SuperLU there)"
        )
    if large_3d and has_pyamg():  # several bodies, no direct solver: AMG without the modes
        return CGSolver("amg"), (
            f"auto: 3D with {n_dofs} DOFs > {AMG_MIN_DOFS_3D} (several bodies), no pypardiso "
            "or scikit-sparse, pyamg available"
        )
    if large_3d:
        return CGSolver("jacobi"), f"auto: 3D with {n_dofs} DOFs > {AMG_MIN_DOFS_3D}, no pyamg"
    return SuperLUSolver(), f"auto: no pypardiso or scikit-sparse, SciPy SuperLU for {n_dofs} DOFs"
