r"""Mass–spring systems 质点弹簧系统: springs, energy, and three time integrators.

The state is particle positions ``x (N, 3)`` and velocities ``v (N, 3)``, with masses
``m (N,)``; spring ``s`` joins particles ``i_s, j_s`` with stiffness ``k_s`` and rest length
``L_s``. Its energy, with ``d = x_i - x_j`` and ``l = ‖d‖``, is

.. math:: U_s(x) = \tfrac12 k_s (l - L_s)^2 ,

and gravity ``g = (0, -9.81, 0)`` (y up) pulls every particle with ``m_i g``. Fixed particles
never move (their velocity is 0). The integrators, time step ``h``, ``f(x) = -∇U(x) + M g``:

- explicit Euler 显式欧拉: ``x⁺ = x + h v``, ``v⁺ = v + h M⁻¹ f(x)``;
- symplectic Euler 辛欧拉: ``v⁺ = v + h M⁻¹ f(x)``, ``x⁺ = x + h v⁺``;
- implicit Euler 隐式欧拉: ``x⁺ = x + h v⁺``, ``v⁺ = v + h M⁻¹ f(x⁺)``, solved as the
  minimisation (see :func:`implicit_euler_step`)

  .. math:: x^+ = \arg\min_x E(x) = \frac{1}{2h^2}\lVert x - y\rVert_M^2 + U(x),\qquad
            y = x + h v + h^2 M^{-1} f_{ext},

  by Newton's method 牛顿法 with a backtracking line search 线搜索.

Everything is vectorised over springs. The Newton matrix is a ``scipy.sparse`` CSR matrix:
its COO triplets are sorted into CSR order once per system, and each Newton iteration only
sums the new values into place. scipy is imported only when a step needs it.

:func:`implicit_euler_step` is the assignment's interface (flat arrays in, ``(x, v)`` out);
:func:`implicit_euler_gradient` measures how optimal any answer is; :func:`step` and
:func:`simulate` take a checked :class:`SpringSystem` and report Newton's statistics.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any, Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validate import as_time_step

if TYPE_CHECKING:
    from collections.abc import Callable

    from scipy.sparse import csr_matrix

    from .._typing import BoolArray

Array = NDArray[np.float64]

#: Gravity in m/s², y up.
GRAVITY: tuple[float, float, float] = (0.0, -9.81, 0.0)

Method = Literal["explicit", "symplectic", "implicit"]
METHODS: tuple[str, ...] = ("explicit", "symplectic", "implicit")
PDFix = Literal["auto", "always", "never"]
PD_FIXES: tuple[str, ...] = ("auto", "always", "never")

# Below this length a spring has no direction; clamping l keeps d / l finite (the force of a
# collapsed spring is then 0 instead of NaN).
_TINY = 1e-12


# -- input -------------------------------------------------------------------------------------


def _floats(a: ArrayLike, name: str, shape: tuple[int | None, ...]) -> Array:
    """``a`` as finite float64 of ``shape`` (None: any length), or an error naming ``name``."""
    try:
        out = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: expected numbers, got {type(a).__name__} ({exc})") from None
    if out.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, out.shape,
                                                                              strict=True)):
        want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"{name}: expected shape {want}, got {out.shape}")
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{name}: contains NaN or infinity")
    return out


def _positions(x: ArrayLike, n: int | None, name: str) -> Array:
    return _floats(x, name, (n, 3))


def _fixed_indices(fixed: ArrayLike | None, n: int) -> NDArray[np.intp]:
    """Sorted unique particle indices from an index list or a boolean mask ``(N,)``."""
    if fixed is None:
        return np.empty(0, dtype=np.intp)
    f = np.asarray(fixed)
    if f.dtype == bool:
        if f.shape != (n,):
            raise ValueError(f"fixed: a boolean mask must have shape ({n},), got {f.shape}")
        return np.flatnonzero(f)
    if f.size == 0:
        return np.empty(0, dtype=np.intp)
    if f.ndim != 1 or not np.issubdtype(f.dtype, np.integer):
        raise ValueError(f"fixed: expected particle indices (F,) or a mask ({n},), got "
                         f"{f.dtype} of shape {f.shape}")
    bad = (f < 0) | (f >= n)
    if bad.any():
        raise ValueError(f"fixed: index {int(f[bad][0])} is not a particle (there are {n})")
    return np.unique(f).astype(np.intp)


@dataclass(frozen=True, eq=False)
class SpringSystem:
    r"""Particles joined by springs, checked once; the integrators take one of these.

    Parameters
    ----------
    masses : (N,) particle masses ``m_i > 0`` (kg).
    springs : (S, 2) particle index pairs ``(i_s, j_s)``, ``i_s != j_s``.
    rest : (S,) rest lengths ``L_s >= 0``.
    k : stiffness ``k_s > 0``, a scalar or (S,).
    fixed : particle indices (F,) or a boolean mask (N,) of fixed points, or None.
    gravity : (3,) gravitational acceleration ``g``; default ``(0, -9.81, 0)``.

    Build one with :meth:`create`, which checks every argument.
    """

    masses: Array
    springs: NDArray[np.intp]
    rest: Array
    k: Array
    fixed: NDArray[np.intp] = field(default_factory=lambda: np.empty(0, dtype=np.intp))
    gravity: Array = field(default_factory=lambda: np.array(GRAVITY))

    @classmethod
    def create(cls, masses: ArrayLike, springs: ArrayLike, rest: ArrayLike, k: ArrayLike,
               fixed: ArrayLike | None = None, gravity: ArrayLike = GRAVITY) -> SpringSystem:
        """Check and convert every argument (a bad one raises ``ValueError`` naming it)."""
        m = _floats(masses, "masses", (None,))
        if np.any(m <= 0):
            i = int(np.flatnonzero(m <= 0)[0])
            raise ValueError(f"masses: must be positive, masses[{i}] = {m[i]}")
        n = m.size
        s = np.asarray(springs)
        if s.ndim != 2 or s.shape[1] != 2 or not (
                s.size == 0 or np.issubdtype(s.dtype, np.integer)):
            raise ValueError(f"springs: expected integer index pairs (S, 2), got {s.dtype} "
                             f"of shape {s.shape}")
        s = s.astype(np.intp).reshape(-1, 2)
        missing = (s < 0) | (s >= n)
        if missing.any():
            row = int(np.argwhere(missing)[0, 0])
            raise ValueError(f"springs: springs[{row}] = {s[row].tolist()} references a missing "
                             f"particle (there are {n})")
        loops = s[:, 0] == s[:, 1]
        if loops.any():
            row = int(np.flatnonzero(loops)[0])
            raise ValueError(f"springs: springs[{row}] joins particle {s[row, 0]} to itself")
        r = _floats(rest, "rest", (len(s),))
        if np.any(r < 0):
            raise ValueError(f"rest: rest lengths must be >= 0, got {r.min()}")
        kk = _floats(k, "k", ()) if np.ndim(k) == 0 else _floats(k, "k", (len(s),))
        if np.any(kk <= 0):
            raise ValueError(f"k: stiffness must be positive, got {np.min(kk)}")
        return cls(m, s, r, np.broadcast_to(kk, (len(s),)).copy(), _fixed_indices(fixed, n),
                   _floats(gravity, "gravity", (3,)))

    @property
    def n_particles(self) -> int:
        return self.masses.size

    @property
    def free(self) -> NDArray[np.bool_]:
        """(N,) True for the particles that move."""
        free = np.ones(self.n_particles, dtype=bool)
        free[self.fixed] = False
        return free

    # -- springs -------------------------------------------------------------------------------

    def _geometry(self, x: Array) -> tuple[Array, Array]:
        """``d = x_i - x_j (S, 3)`` and ``l = ‖d‖ (S,)`` (clamped away from 0)."""
        d = x[self.springs[:, 0]] - x[self.springs[:, 1]]
        return d, np.maximum(np.linalg.norm(d, axis=1), _TINY)

    def spring_energy(self, x: ArrayLike) -> float:
        r"""``U(x) = Σ_s ½ k_s (‖x_i - x_j‖ - L_s)²``."""
        _, length = self._geometry(_positions(x, self.n_particles, "x"))
        return float(0.5 * np.sum(self.k * (length - self.rest) ** 2))

    def spring_gradient(self, x: ArrayLike) -> Array:
        r"""``∇U (N, 3)``: particle ``i`` of spring ``s`` gets ``k_s (1 - L_s/l) d``, ``j`` the
        opposite (the spring force is ``-∇U``)."""
        x = _positions(x, self.n_particles, "x")
        d, length = self._geometry(x)
        gs = (self.k * (1.0 - self.rest / length))[:, None] * d
        return _scatter(self.springs, gs, -gs, self.n_particles)

    def spring_hessian_blocks(
        self, x: ArrayLike, psd: bool = False
    ) -> tuple[Array, BoolArray]:
        r"""Per-spring 3×3 blocks ``H_s (S, 3, 3)`` of ``∇²U`` and how many were projected.

        With ``d̂ = d / l`` and ``c = 1 - L/l``,

        .. math:: H_s = k_s\left[(1 - L_s/l)\,I + (L_s/l)\,\hat d\hat d^T\right]
                      = k_s\left[c\,I + (1 - c)\,\hat d\hat d^T\right],

        and the spring contributes ``[[H_s, -H_s], [-H_s, H_s]]`` to rows/columns ``(i, j)``.
        Its eigenvalues are ``k_s`` along ``d̂`` and ``k_s c`` (twice) across it: negative for a
        compressed spring (``l < L``). ``psd=True`` projects each block onto the positive
        semi-definite cone by clamping ``c`` to ``max(c, 0)`` (the nearest PSD block; the
        6×6 spring block ``[[1, -1], [-1, 1]] ⊗ H_s`` is then PSD too).

        Returns
        -------
        blocks : (S, 3, 3)
        projected : (S,) bool, True where a block was clamped.
        """
        x = _positions(x, self.n_particles, "x")
        d, length = self._geometry(x)
        c = 1.0 - self.rest / length
        projected: BoolArray = (c < 0) if psd else np.zeros(c.shape, dtype=bool)
        if psd:
            c = np.maximum(c, 0.0)
        dh = d / length[:, None]
        blocks = self.k[:, None, None] * (
            c[:, None, None] * np.eye(3) + (1.0 - c)[:, None, None] * dh[:, :, None] * dh[:, None]
        )
        return blocks, projected

    def spring_hessian(self, x: ArrayLike, psd: bool = False) -> csr_matrix:
        """``∇²U`` as a sparse ``(3N, 3N)`` matrix (all particles, fixed ones included)."""
        blocks, _ = self.spring_hessian_blocks(x, psd)
        pattern = _Pattern(self.springs, np.arange(self.n_particles))
        return pattern.matrix(blocks, np.zeros(pattern.size))

    @cached_property
    def _free_pattern(self) -> tuple[NDArray[np.intp], _Pattern]:
        """Each particle's index among the free ones (-1 if fixed), and the pattern of the
        implicit step's Newton matrix over the free coordinates."""
        free = self.free
        dof = np.where(free, np.cumsum(free) - 1, -1)
        return dof, _Pattern(self.springs, dof)

    # -- energy --------------------------------------------------------------------------------

    def forces(self, x: ArrayLike) -> Array:
        """Total force ``f(x) = -∇U(x) + m g``, ``(N, 3)``."""
        return -self.spring_gradient(x) + self.masses[:, None] * self.gravity

    def energy(self, x: ArrayLike, v: ArrayLike) -> Energy:
        """Kinetic ``½ Σ m‖v‖²``, spring ``U`` and gravitational ``-Σ m g·x`` energy."""
        x = _positions(x, self.n_particles, "x")
        v = _positions(v, self.n_particles, "v")
        return Energy(float(0.5 * np.sum(self.masses * np.sum(v * v, axis=1))),
                      self.spring_energy(x), float(-np.sum(self.masses * (x @ self.gravity))))


class Energy(NamedTuple):
    """The energy of a state (joules); ``total`` is what a conservative system keeps."""

    kinetic: float
    spring: float
    gravity: float

    @property
    def total(self) -> float:
        return self.kinetic + self.spring + self.gravity


@dataclass(frozen=True)
class NewtonStats:
    """How one implicit step's Newton solve went.

    iterations : Newton iterations (Hessian solves) taken.
    backtracks : line-search halvings of the step, summed over the iterations.
    gradient_norm : ``‖∇E‖₂`` over the free coordinates at the returned ``x``.
    converged : ``gradient_norm <= threshold``.
    threshold : the absolute stopping threshold ``tol · f`` (N), ``f`` the force scale: the
        norm of the free particles' weights ``(m_i g)``, or of the first gradient if larger;
        never below the rounding error of ``∇E`` itself (``100 ε`` times the size of its
        terms, ``‖m‖ |x| / h²`` and ``‖k‖ |x|``), which it can reach when both are ~0.
    pd_fixes : iterations whose Hessian was not positive definite and was fixed (its spring
        blocks projected to PSD, see :func:`step`'s ``pd_fix``).
    projected : spring blocks clamped by those fixes, summed over the iterations.
    fallbacks : iterations whose direction was not a descent direction (possible only with
        ``pd_fix="never"``), replaced by ``-∇E``.
    history : ``‖∇E‖₂`` before the first iteration and after each one (iterations + 1 values).
    """

    iterations: int
    backtracks: int
    gradient_norm: float
    converged: bool
    threshold: float
    pd_fixes: int
    projected: int
    fallbacks: int
    history: tuple[float, ...] = ()


class NotConvergedWarning(RuntimeWarning):
    """An implicit step's Newton solve stopped (``max_iter``, or a non-finite gradient)
    before ``‖∇E‖`` reached its threshold: the positions returned are not the implicit Euler
    answer. Said by :func:`implicit_euler_step` and :func:`simulate`, which return no
    :class:`NewtonStats` of their own; :func:`step` returns them (``stats.converged``)."""

    @classmethod
    def about(cls, where: str, stats: NewtonStats, which: str = "",
              more: str = "course.physics.step returns its NewtonStats") -> NotConvergedWarning:
        """The warning for ``stats``, said by ``where`` of step ``which``; ``more`` says
        where to find the statistics."""
        return cls(f"{where}: Newton's method stopped{which} after {stats.iterations} "
                   f"iterations with ‖∇E‖ = {stats.gradient_norm:.3g} N, above its stopping "
                   f"threshold {stats.threshold:.3g} N (tol × the force scale): not the "
                   f"implicit Euler answer. Raise max_iter, or take a smaller h; {more}.")


class StepResult(NamedTuple):
    """One step's positions and velocities at n + 1, ``(N, 3)`` each, and Newton's report."""

    x: Array
    v: Array
    stats: NewtonStats | None  # None for the explicit methods


def _scatter(pairs: NDArray[np.intp], at_i: Array, at_j: Array, n: int) -> Array:
    """Sum per-spring vectors into particles: ``out[i_s] += at_i[s]``, ``out[j_s] += at_j[s]``."""
    idx = pairs.T.ravel()
    vals = np.concatenate([at_i, at_j])
    return np.stack([np.bincount(idx, vals[:, c], minlength=n) for c in range(3)], axis=1)


class _Pattern:
    """The sparsity pattern of ``diag + Σ_s [[H,-H],[-H,H]]``, worked out once per system.

    Particle ``p`` owns rows ``3 dof[p] + (0, 1, 2)``; particles with ``dof[p] < 0`` (fixed
    points) are eliminated: their rows and columns are dropped. The COO triplets of every
    spring's four 3×3 blocks are sorted into CSR order here, so each Newton iteration only
    sums values into place (one ``bincount``) instead of re-sorting ~36 S indices.
    """

    def __init__(self, pairs: NDArray[np.intp], dof: NDArray[np.intp]) -> None:
        from scipy.sparse import csr_matrix

        a, b = dof[pairs[:, 0]], dof[pairs[:, 1]]
        # the four blocks of each spring: (a, a) +H, (b, b) +H, (a, b) -H, (b, a) -H
        rp, cp = np.stack([a, b, a, b], axis=1), np.stack([a, b, b, a], axis=1)  # (S, 4)
        self.keep = (rp >= 0) & (cp >= 0)
        self.size = 3 * int(dof.max(initial=-1) + 1)
        r3 = np.arange(3)
        rows = 3 * rp[self.keep][:, None, None] + r3[None, :, None]
        cols = 3 * cp[self.keep][:, None, None] + r3[None, None, :]
        # where each kept entry's value comes from in the flattened blocks (S * 9), and its sign
        spring = np.broadcast_to(np.arange(len(pairs))[:, None], rp.shape)[self.keep]
        self.source = (9 * spring[:, None] + np.arange(9)).ravel()
        self.sign = np.repeat(np.where(np.nonzero(self.keep)[1] < 2, 1.0, -1.0), 9)
        diag = np.arange(self.size)
        keys = np.concatenate([(rows * self.size + cols).ravel(), diag * (self.size + 1)])
        unique, self.slot = np.unique(keys, return_inverse=True)
        self.n_values = unique.size
        indptr = np.searchsorted(unique // self.size, np.arange(self.size + 1))
        self._csr: Callable[[Array], csr_matrix] = lambda data: csr_matrix(
            (data, unique % self.size, indptr), shape=(self.size, self.size))

    def matrix(self, blocks: Array, diagonal: Array) -> csr_matrix:
        """The matrix for per-spring blocks ``(S, 3, 3)`` and a diagonal ``(size,)``."""
        values = np.concatenate([blocks.ravel()[self.source] * self.sign, diagonal])
        # numpy's stub types bincount as integer even with float weights (it returns float64).
        sums = np.bincount(self.slot, values, minlength=self.n_values)
        return self._csr(sums)  # type: ignore[arg-type]


# -- the implicit step's objective ---------------------------------------------------------------


def _inertial_target(system: SpringSystem, x: Array, v: Array, h: float) -> Array:
    """``y = x + h v + h² M⁻¹ f_ext`` (gravity is the only external force, so ``M⁻¹ f_ext = g``)."""
    return x + h * v + h * h * system.gravity


def _objective(system: SpringSystem, x: Array, y: Array, h: float) -> float:
    r = x - y
    return float(0.5 * np.sum(system.masses * np.sum(r * r, axis=1)) / h**2
                 + system.spring_energy(x))


def _gradient(system: SpringSystem, x: Array, y: Array, h: float) -> Array:
    """``∇E(x) = M (x - y) / h² + ∇U(x)``, with the rows of fixed particles set to 0."""
    g = system.masses[:, None] * (x - y) / h**2 + system.spring_gradient(x)
    g[system.fixed] = 0.0
    return g


def _state(system: SpringSystem, x: ArrayLike, v: ArrayLike) -> tuple[Array, Array]:
    n = system.n_particles
    return _positions(x, n, "x"), _positions(v, n, "v")


# -- the three integrators --------------------------------------------------------------------


def _explicit(system: SpringSystem, x: Array, v: Array, h: float, symplectic: bool) -> StepResult:
    a = system.forces(x) / system.masses[:, None]
    v_new = v + h * a
    x_new = x + h * (v_new if symplectic else v)
    x_new[system.fixed] = x[system.fixed]
    v_new[system.fixed] = 0.0
    return StepResult(x_new, v_new, None)


def _pcg(H: Any, b: Array, rtol: float, precondition: Array) -> tuple[Array, bool]:
    """Solve ``H p = b`` by Jacobi-preconditioned conjugate gradients, stopping early when a
    direction of non-positive curvature ``dᵀHd <= 0`` shows that ``H`` is not positive
    definite. Returns ``(p, positive_definite_so_far)``."""
    p = np.zeros_like(b)
    r = b.copy()
    z = r / precondition
    d, rz, stop = z.copy(), float(r @ z), rtol * float(np.linalg.norm(b))
    for _ in range(4 * b.size):
        Hd = H @ d
        curvature = float(d @ Hd)
        if not curvature > 0:
            return p, False
        a = rz / curvature
        p += a * d
        r -= a * Hd
        if np.linalg.norm(r) <= stop:
            break
        z = r / precondition
        rz, rz_old = float(r @ z), rz
        d = z + (rz / rz_old) * d
    return p, True


def _newton_direction(system: SpringSystem, x: Array, g: Array, mass_diag: Array, *,
                      pd_fix: str, solver: str, forcing: float) -> tuple[Array, int]:
    """The Newton direction ``p``, ``∇²E p = -∇E``, and how many spring blocks were projected
    to make ``∇²E`` positive definite (0 if the true Hessian was used)."""
    from scipy.sparse.linalg import spsolve

    _, pattern = system._free_pattern

    def solve(psd: bool) -> tuple[Array, bool, int]:
        blocks, clamped = system.spring_hessian_blocks(x, psd=psd)
        H = pattern.matrix(blocks, mass_diag)
        if solver == "cg":
            p, pd = _pcg(H, -g, forcing, np.maximum(H.diagonal(), mass_diag))
        else:
            p = spsolve(H.tocsc(), -g, permc_spec="MMD_AT_PLUS_A")
            # an LU factorisation does not reveal the inertia: check the direction instead
            pd = bool(g @ p < 0 and p @ (H @ p) > 0)
        return p, pd, int(clamped.sum())

    p, pd, projected = solve(pd_fix == "always")
    if not pd and pd_fix == "auto":
        p, _, projected = solve(True)
    return p, projected


def _newton(system: SpringSystem, x: Array, v: Array, h: float, *, tol: float, max_iter: int,
            line_search: bool, pd_fix: str, solver: str) -> StepResult:
    n, free = system.n_particles, system.free
    y = _inertial_target(system, x, v, h)
    x_k = y.copy()  # start at the inertial position (what a step without springs would give)
    x_k[system.fixed] = x[system.fixed]
    mass_diag = np.repeat(system.masses[free], 3) / h**2
    g = _gradient(system, x_k, y, h)[free].ravel()
    # the force scale tol is relative to: the free particles' weight (or the first gradient)
    scale = max(float(np.linalg.norm(system.masses[free])) * float(np.linalg.norm(
        system.gravity)), float(np.linalg.norm(g)), 1e-300)
    # ... and never below what rounding lets ‖∇E‖ reach: without gravity, near rest, the
    # scale above tends to 0 and Newton would chase rounding noise to max_iter (and report
    # no convergence). ∇E sums terms M x / h² and k d, each rounded to ε of its size; 100 ε
    # leaves room for the sums over many springs.
    size = max(float(np.abs(x).max(initial=0.0)), float(np.abs(y).max(initial=0.0)))
    threshold = max(tol * scale, 100 * np.finfo(float).eps * size * (
        float(np.linalg.norm(system.masses[free])) / h**2 + float(np.linalg.norm(system.k))))
    backtracks = projected = pd_fixes = fallbacks = iterations = 0
    e_k = _objective(system, x_k, y, h)
    history = [float(np.linalg.norm(g))]
    while np.linalg.norm(g) > threshold and iterations < max_iter:
        # inexact Newton (CG): solve to a relative residual of 1% (looser costs more Newton
        # iterations than it saves, measured on 30x30 and 50x50 cloths), tighter near the
        # answer so that convergence stays superlinear
        forcing = min(0.01, float(np.sqrt(np.linalg.norm(g) / scale)))
        p, clamped = _newton_direction(system, x_k, g, mass_diag, pd_fix=pd_fix, solver=solver,
                                       forcing=forcing)
        projected += clamped
        pd_fixes += clamped > 0
        slope = float(g @ p)
        if not np.isfinite(slope) or slope >= 0:  # not a descent direction: take the gradient
            p, slope = -g, -float(g @ g)
            fallbacks += 1
        step = np.zeros((n, 3))
        step[free] = p.reshape(-1, 3)
        alpha = 1.0
        e_new = _objective(system, x_k + step, y, h)
        if line_search:
            # Armijo: E(x + αp) <= E(x) + c α ∇E·p, halving α; the 1e-14 |E| allowance stops
            # rounding in E from rejecting the tiny last steps near the minimum
            while (not e_new <= e_k + 1e-4 * alpha * slope + 1e-14 * abs(e_k)
                   and alpha > 2.0**-30):
                alpha *= 0.5
                backtracks += 1
                e_new = _objective(system, x_k + alpha * step, y, h)
        x_k, e_k = x_k + alpha * step, e_new
        iterations += 1
        g = _gradient(system, x_k, y, h)[free].ravel()
        history.append(float(np.linalg.norm(g)))
        if not np.all(np.isfinite(g)):
            break
    g_norm = float(np.linalg.norm(g))
    v_new = (x_k - x) / h
    v_new[system.fixed] = 0.0
    stats = NewtonStats(iterations, backtracks, g_norm, bool(g_norm <= threshold), threshold,
                        pd_fixes, projected, fallbacks, tuple(history))
    return StepResult(x_k, v_new, stats)


def step(system: SpringSystem, x: ArrayLike, v: ArrayLike, h: float, method: Method = "implicit",
         *, tol: float = 1e-6, max_iter: int = 50, line_search: bool = True,
         pd_fix: PDFix = "auto", solver: Literal["direct", "cg"] = "cg") -> StepResult:
    r"""Advance ``(x, v)`` by one time step ``h`` with ``method`` (see the module doc).

    Parameters
    ----------
    system : the particles and springs.
    x, v : (N, 3) positions and velocities at step n.
    h : time step (s), > 0.
    method : ``"explicit"``, ``"symplectic"`` or ``"implicit"``.
    tol : implicit only: Newton stops when ``‖∇E‖₂ <= tol · f`` over the free coordinates,
        ``f`` a force scale (:class:`NewtonStats`' ``threshold``, with its rounding floor): a
        relative tolerance.
    max_iter : implicit only: at most this many Newton iterations.
    line_search : implicit only: backtrack (Armijo) instead of always taking the full step.
    pd_fix : implicit only, the positive-definite fix. ``∇²E = M/h² + Σ H_s`` stops being
        positive definite only when compressed springs' negative curvature ``k (1 - L/l)``
        outweighs ``m/h²``; then its Newton step may go uphill. The fix projects every
        spring block to PSD (:meth:`SpringSystem.spring_hessian_blocks`), which makes
        ``∇²E`` positive definite (``M/h² > 0`` plus PSD blocks), is local (no global shift
        ``αI`` to search for, no extra factorisation) and leaves stretched springs exact.
        But it changes the Hessian of every compressed spring, and Newton then converges
        only linearly (measured in ``notebooks/12_mass_spring``), so ``"auto"`` uses the true
        Hessian and projects only when the solve finds it indefinite (CG meets a direction of
        non-positive curvature; with the direct solver: the step is not a descent direction
        of positive curvature). ``"always"`` projects at every iteration, ``"never"`` never
        (a non-descent step is then replaced by ``-∇E``).
    solver : implicit only: ``"cg"``, conjugate gradients with a Jacobi preconditioner, as
        precise as each Newton iteration needs (inexact Newton), or ``"direct"``, a sparse
        LU factorisation (SuperLU, symmetric ordering). CG is several times faster on a
        50×50 cloth (``benchmarks/mass_spring.py``).

    Returns
    -------
    StepResult ``(x, v, stats)``; ``stats`` is a :class:`NewtonStats` for the implicit method.
    """
    if method not in METHODS:
        raise ValueError(f"method: must be one of {METHODS}, got {method!r}")
    if pd_fix not in PD_FIXES:
        raise ValueError(f"pd_fix: must be one of {PD_FIXES}, got {pd_fix!r}")
    if solver not in ("direct", "cg"):
        raise ValueError(f"solver: must be 'direct' or 'cg', got {solver!r}")
    h = as_time_step(h)
    x, v = _state(system, x, v)
    if method == "implicit":
        if not tol > 0 or max_iter < 1:
            raise ValueError(f"tol and max_iter: must be positive, got {tol}, {max_iter}")
        return _newton(system, x, v, h, tol=tol, max_iter=max_iter, line_search=line_search,
                       pd_fix=pd_fix, solver=solver)
    return _explicit(system, x, v, h, symplectic=method == "symplectic")


# -- the flat functions (the assignment's interface) ------------------------------------------


def explicit_euler_step(x: ArrayLike, v: ArrayLike, masses: ArrayLike, springs: ArrayLike,
                        rest: ArrayLike, k: ArrayLike, h: float, fixed: ArrayLike | None = None,
                        gravity: ArrayLike = GRAVITY) -> tuple[Array, Array]:
    r"""One explicit Euler step: ``x⁺ = x + h v``, ``v⁺ = v + h M⁻¹ f(x)``; returns ``(x⁺, v⁺)``.

    Arguments as in :func:`implicit_euler_step`. Unstable once ``h`` exceeds about
    ``2/ω`` for the stiffest mode ``ω = √(k/m)``; even below, it gains energy every step.
    """
    system = SpringSystem.create(masses, springs, rest, k, fixed, gravity)
    x_new, v_new, _ = step(system, x, v, h, "explicit")
    return x_new, v_new


def symplectic_euler_step(x: ArrayLike, v: ArrayLike, masses: ArrayLike, springs: ArrayLike,
                          rest: ArrayLike, k: ArrayLike, h: float,
                          fixed: ArrayLike | None = None,
                          gravity: ArrayLike = GRAVITY) -> tuple[Array, Array]:
    r"""One symplectic Euler step: ``v⁺ = v + h M⁻¹ f(x)``, ``x⁺ = x + h v⁺``.

    Arguments as in :func:`implicit_euler_step`. Its energy oscillates but stays bounded
    while ``h < 2/ω``.
    """
    system = SpringSystem.create(masses, springs, rest, k, fixed, gravity)
    x_new, v_new, _ = step(system, x, v, h, "symplectic")
    return x_new, v_new


def implicit_euler_step(x: ArrayLike, v: ArrayLike, masses: ArrayLike, springs: ArrayLike,
                        rest: ArrayLike, k: ArrayLike, h: float, fixed: ArrayLike | None = None,
                        gravity: ArrayLike = GRAVITY, **options: Any) -> tuple[Array, Array]:
    r"""One implicit Euler step 隐式欧拉, solved by Newton's method 牛顿法 with a line search.

    Implicit Euler asks for ``x⁺ = x + h v⁺`` and ``v⁺ = v + h M⁻¹ f(x⁺)``: the force at the
    *end* of the step. Eliminating ``v⁺``, ``M (x⁺ - y) / h² = -∇U(x⁺)``, which is the
    condition ``∇E(x⁺) = 0`` for

    .. math:: E(x) = \frac{1}{2h^2}(x - y)^T M (x - y) + U(x),\qquad
              y = x_n + h v_n + h^2 M^{-1} f_{ext},\qquad
              U(x) = \sum_s \tfrac12 k_s (\lVert x_i - x_j\rVert - L_s)^2 ,

    so the step is ``x⁺ = argmin E``. Newton's method repeats ``x ← x + α Δx`` with

    .. math:: \nabla^2 E(x)\,\Delta x = -\nabla E(x),\qquad
              \nabla E = \frac{M(x - y)}{h^2} + \nabla U,\qquad
              \nabla^2 E = \frac{M}{h^2} + \sum_s H_s ,

    where spring ``s`` contributes ``∂U/∂x_i = k (1 - L/‖d‖) d`` (``d = x_i - x_j``, the
    opposite to ``x_j``) and the block ``H_s = k [(1 - L/‖d‖) I + (L/‖d‖) d̂ d̂ᵀ]`` at
    ``(i,i), (j,j)`` (and ``-H_s`` at ``(i,j), (j,i)``). A compressed spring
    (``‖d‖ < L``) makes ``1 - L/‖d‖`` negative and ``H_s`` indefinite; when that makes
    ``∇²E`` indefinite, each block is projected to PSD (the coefficient clamped at 0) and
    the system solved again (``pd_fix``, see :func:`step`); ``α`` starts at 1 and is
    halved until Armijo's condition ``E(x + αΔx) <= E(x) + 10⁻⁴ α ∇E·Δx`` holds. Fixed points
    are eliminated: their rows and columns are dropped and they stay at ``x_n``. Finally
    ``v⁺ = (x⁺ - x_n) / h``.

    Parameters
    ----------
    x, v : (N, 3) positions ``x_n`` and velocities ``v_n``.
    masses : (N,) masses ``m_i > 0``.
    springs : (S, 2) particle index pairs.
    rest : (S,) rest lengths ``L_s``.
    k : stiffness, a scalar or (S,).
    h : time step, > 0.
    fixed : indices (F,) or a mask (N,) of particles that do not move, or None.
    gravity : (3,) acceleration, default ``(0, -9.81, 0)``.
    **options : ``tol``, ``max_iter``, ``line_search``, ``pd_fix``, ``solver`` of :func:`step`.

    Returns
    -------
    x, v : (N, 3) positions and velocities at step n + 1. Check a step's optimality with
    :func:`implicit_euler_gradient` (it is ``≈ 0`` at the answer).

    Warns
    -----
    NotConvergedWarning
        If Newton's method stopped before converging (its numbers in the message; a stiff
        system with a large ``h`` can need more than the default 50 iterations).
    """
    system = SpringSystem.create(masses, springs, rest, k, fixed, gravity)
    x_new, v_new, stats = step(system, x, v, h, "implicit", **options)
    assert stats is not None  # the implicit method reports
    if not stats.converged:
        warnings.warn(NotConvergedWarning.about("implicit_euler_step", stats), stacklevel=2)
    return x_new, v_new


def implicit_euler_objective(x_new: ArrayLike, x: ArrayLike, v: ArrayLike, masses: ArrayLike,
                             springs: ArrayLike, rest: ArrayLike, k: ArrayLike, h: float,
                             fixed: ArrayLike | None = None,
                             gravity: ArrayLike = GRAVITY) -> float:
    r"""The implicit step's objective ``E(x_new) = ‖x_new - y‖²_M / (2h²) + U(x_new)``.

    Arguments as in :func:`implicit_euler_step`; ``x_new (N, 3)`` is the candidate ``x⁺``.
    """
    system = SpringSystem.create(masses, springs, rest, k, fixed, gravity)
    x, v = _state(system, x, v)
    h = as_time_step(h)
    return _objective(system, _positions(x_new, system.n_particles, "x_new"),
                      _inertial_target(system, x, v, h), h)


def implicit_euler_gradient(x_new: ArrayLike, x: ArrayLike, v: ArrayLike, masses: ArrayLike,
                            springs: ArrayLike, rest: ArrayLike, k: ArrayLike, h: float,
                            fixed: ArrayLike | None = None,
                            gravity: ArrayLike = GRAVITY) -> Array:
    r"""``∇E(x_new) = M (x_new - y) / h² + ∇U(x_new)``, ``(N, 3)``, fixed rows set to 0.

    An exact implicit Euler step makes it 0; its norm measures how optimal a step is.
    Arguments as in :func:`implicit_euler_objective`.
    """
    system = SpringSystem.create(masses, springs, rest, k, fixed, gravity)
    x, v = _state(system, x, v)
    h = as_time_step(h)
    return _gradient(system, _positions(x_new, system.n_particles, "x_new"),
                     _inertial_target(system, x, v, h), h)


# -- many steps -------------------------------------------------------------------------------


@dataclass(frozen=True)
class Trajectory:
    """What :func:`simulate` recorded.

    positions, velocities : (T + 1, N, 3), the start included (fewer rows if it exploded).
    energy : (T + 1, 3) kinetic, spring and gravitational energy per recorded state.
    stats : per implicit step, its :class:`NewtonStats` (empty for the explicit methods).
    exploded_at : the step at which the state became non-finite or flew beyond ``blowup``
        times the system's size, else None.
    """

    positions: Array
    velocities: Array
    energy: Array
    stats: list[NewtonStats]
    exploded_at: int | None

    @property
    def total_energy(self) -> Array:
        total: Array = self.energy.sum(axis=1)
        return total

    @property
    def unconverged(self) -> list[int]:
        """The implicit steps (numbered from 1) whose Newton solve did not converge."""
        return [n for n, s in enumerate(self.stats, 1) if not s.converged]


def simulate(system: SpringSystem, x: ArrayLike, v: ArrayLike, h: float, n_steps: int,
             method: Method = "implicit", *, blowup: float = 1e3,
             **options: Any) -> Trajectory:
    """Run ``n_steps`` steps of :func:`step`, recording states and energies; stops early when
    the simulation explodes (a non-finite state, or a particle farther than ``blowup`` sizes
    from the start's centre). Warns once (:class:`NotConvergedWarning`) if any implicit
    step's Newton solve did not converge (:attr:`Trajectory.unconverged` lists them)."""
    x, v = _state(system, x, v)
    if int(n_steps) != n_steps or n_steps < 0:
        raise ValueError(f"n_steps: must be a non-negative integer, got {n_steps!r}")
    center = x.mean(axis=0)
    size = max(float(np.ptp(x, axis=0).max()), float(system.rest.max(initial=0.0)), 1e-9)
    xs, vs, energies, stats = [x], [v], [system.energy(x, v)], []
    exploded = None
    with np.errstate(over="ignore", invalid="ignore"):
        for n in range(1, int(n_steps) + 1):
            x, v, s = step(system, x, v, h, method, **options)
            if s is not None:
                stats.append(s)
            if not (np.all(np.isfinite(x)) and np.all(np.isfinite(v))
                    and np.abs(x - center).max() <= blowup * size):
                exploded = n
                break
            xs.append(x)
            vs.append(v)
            energies.append(system.energy(x, v))
    run = Trajectory(np.stack(xs), np.stack(vs), np.array(energies), stats, exploded)
    if run.unconverged:
        first = run.unconverged[0]
        warnings.warn(NotConvergedWarning.about(
            "simulate", stats[first - 1], f" in step {first}", f"{len(run.unconverged)} of "
            f"{len(stats)} steps did not converge (the run's unconverged and stats)"),
            stacklevel=2)
    return run
