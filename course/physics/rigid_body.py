r"""Rigid bodies 刚体: state, inertia, torque, time integration and penalty contact (lecture 8).

A rigid body has mass ``m`` and a body-frame inertia tensor ``I₀ (3, 3)`` about its centre of
mass. Its state is the centre-of-mass position ``x``, linear velocity ``v``, orientation
``q`` (a unit quaternion, ``R`` its matrix) and angular momentum ``L`` (world frame). Then

.. math:: I = R I_0 R^T,\qquad \omega = I^{-1} L,\qquad \tau = \sum_i (p_i - x)\times f_i,
          \qquad T = \tfrac12 m\lVert v\rVert^2 + \tfrac12 L\cdot\omega,

and Newton–Euler's equations are ``m v̇ = f``, ``ẋ = v``, ``L̇ = τ``, ``Ṙ = [ω]× R`` (or
``q̇ = ½ [0, ω] ⊗ q``). The state stores ``L``, not ``ω``: a free body keeps ``L`` exactly,
and ``ω`` is always ``I⁻¹ L`` with the inertia of the orientation the state has, so after a
step ``ω_{n+1} = I_{n+1}⁻¹ L_{n+1}`` uses the updated orientation's world inertia.

One step of size ``h`` (:func:`step_rigid`), forces ``f_n, τ_n`` taken at the start state:

- explicit Euler 显式欧拉: ``v⁺ = v + h f/m``, ``x⁺ = x + h v``, ``L⁺ = L + h τ``, the
  orientation turned by ``ω_n = I_n⁻¹ L_n``;
- symplectic Euler 辛欧拉: ``v⁺ = v + h f/m``, ``x⁺ = x + h v⁺``, ``L⁺ = L + h τ``, the
  orientation turned by ``I_n⁻¹ L⁺`` (the updated momentum, the start orientation's inertia).

The orientation update (``rotation``), each with the ``ω`` its method gives:

- ``"quaternion"``: ``q⁺ = q + (h/2) [0, ω] ⊗ q``, then renormalised (:func:`quat_euler_step`);
- ``"matrix"``: ``R⁺ = R + h [ω]× R``, then re-orthonormalised by the polar decomposition
  (:func:`matrix_euler_step`);
- ``"exact"``: ``q⁺ = exp(h ω / 2) ⊗ q``, the rotation by exactly ``h‖ω‖`` about ``ω``; it
  needs no repair (:func:`quat_exp_step`). The two Euler updates turn about the same axis by
  ``2 atan(h‖ω‖/2)`` and ``atan(h‖ω‖)`` once repaired.

All three hold ``ω`` fixed over the step, so all three are first order: a free body's energy
grows by ``O(h²)`` per step (``O(h)`` over a fixed time; measured in the tests).

Contact with the ground ``y = 0`` is a penalty spring–damper at each of the body's contact
points (:class:`Ground`, :func:`contact_forces`). Everything broadcasts over leading
dimensions of the state (many bodies of the same shape at once).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .._validate import as_array, as_positive, as_time_step, unit
from ..rotations import _kernels
from ..rotations.axis_angle import quat_from_rotvec
from ..rotations.quaternion import matrix_from_quat, quat_from_matrix
from .mass_spring import GRAVITY

Integrator = Literal["explicit", "symplectic"]
INTEGRATORS: tuple[str, ...] = ("explicit", "symplectic")
Rotation = Literal["exact", "quaternion", "matrix"]
ROTATION_UPDATES: tuple[str, ...] = ("exact", "quaternion", "matrix")

#: A state's ``q`` may be this far from unit length (rounding, float32 input), no farther.
UNIT_TOL = 1e-6

# How far from symmetric (relative to its largest entry) an inertia tensor may be.
_SYMMETRY_TOL = 1e-9

#: Applied forces: ``state -> (f (..., 3), τ (..., 3))``, world frame, ``τ`` about ``x``.
Applied = Callable[["RigidState"], tuple[Array, Array]]


# -- input -------------------------------------------------------------------------------------


def _inertia(inertia: ArrayLike, name: str = "inertia") -> Array:
    """``inertia`` checked to be a physical inertia tensor: symmetric, positive definite, and
    its principal moments obey the triangle inequality ``I₁ + I₂ ≥ I₃``."""
    I0 = as_array(inertia, name, (3, 3))
    if I0.shape != (3, 3):
        raise ValueError(f"{name}: expected one body-frame tensor of shape (3, 3), got {I0.shape}")
    asym = float(np.abs(I0 - I0.T).max())
    if asym > _SYMMETRY_TOL * float(np.abs(I0).max()):
        raise ValueError(f"{name}: not symmetric (I - Iᵀ has entries up to {asym:.3g}); an "
                         f"inertia tensor is symmetric")
    moments = np.linalg.eigvalsh(I0)
    if moments[0] <= 0:
        raise ValueError(f"{name}: not positive definite (principal moments {moments}); every "
                         f"moment of inertia of a body with mass is positive")
    if moments[2] > (moments[0] + moments[1]) * (1 + _SYMMETRY_TOL):
        raise ValueError(f"{name}: principal moments {moments} break the triangle inequality "
                         f"I₁ + I₂ ≥ I₃, which every mass distribution obeys")
    return I0


def _unit_quat(q: ArrayLike, name: str = "q") -> Array:
    a = as_array(q, name, (4,))
    err = np.abs(np.linalg.norm(a, axis=-1) - 1.0)
    if np.any(err > UNIT_TOL):
        i = np.unravel_index(int(np.argmax(err)), err.shape)
        at = f" at index {tuple(map(int, i))}" if err.ndim else ""
        norm = float(np.linalg.norm(a[i]))
        raise ValueError(f"{name}: not a unit quaternion{at} (‖q‖ = {norm:.6g}); an "
                         f"orientation is a unit quaternion (course.rotations.quat_normalize)")
    return a


def _choice(value: str, name: str, options: tuple[str, ...]) -> None:
    if value not in options:
        raise ValueError(f"{name}: must be one of {options}, got {value!r}")


# -- bodies ------------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True, eq=False)
class RigidBody:
    """A rigid body's constant properties, checked on construction.

    Parameters
    ----------
    mass : ``m > 0`` (kg).
    inertia : (3, 3) body-frame inertia tensor ``I₀`` about the centre of mass (kg m²).
    points : (P, 3) contact points in the body frame (m), e.g. a box's 8 corners.
    """

    mass: float
    inertia: Array
    points: Array = field(default_factory=lambda: np.zeros((0, 3)))

    def __post_init__(self) -> None:
        # frozen: the checked, converted values are set past the dataclass's guard
        object.__setattr__(self, "mass", as_positive(self.mass, "mass"))
        object.__setattr__(self, "inertia", _inertia(self.inertia))
        points = as_array(self.points, "points", (3,))
        if points.ndim != 2:
            raise ValueError(f"points: expected shape (P, 3), got {points.shape}")
        object.__setattr__(self, "points", points)

    @cached_property
    def inertia_inv(self) -> Array:
        """(3, 3) ``I₀⁻¹``."""
        return np.asarray(np.linalg.inv(self.inertia), dtype=np.float64)

    def state(self, *, x: ArrayLike = (0.0, 0.0, 0.0), v: ArrayLike = (0.0, 0.0, 0.0),
              q: ArrayLike = (1.0, 0.0, 0.0, 0.0), omega: ArrayLike | None = None,
              L: ArrayLike | None = None) -> RigidState:
        """A state of this body, its spin given as ``ω`` (world frame; ``L = I ω``) or ``L``
        (neither: at rest). Arrays broadcast over leading dimensions."""
        if omega is not None and L is not None:
            raise ValueError("omega, L: give the angular velocity or the momentum, not both")
        q = _unit_quat(q)
        if omega is not None:
            w = as_array(omega, "omega", (3,))
            L = np.einsum("...ij,...j->...i", world_inertia(matrix_from_quat(q), self.inertia),
                          w)
        return RigidState.create(x=x, v=v, q=q, L=(0.0, 0.0, 0.0) if L is None else L)


@dataclass(frozen=True, kw_only=True, eq=False)
class RigidState:
    """Position ``x``, velocity ``v`` (..., 3), orientation ``q`` (..., 4, unit, body to
    world) and angular momentum ``L`` (..., 3, world frame, about ``x``), of one leading
    shape. Build one with :meth:`create` (or :meth:`RigidBody.state`), which checks them."""

    x: Array
    v: Array
    q: Array
    L: Array

    @classmethod
    def create(cls, *, x: ArrayLike, v: ArrayLike, q: ArrayLike, L: ArrayLike) -> RigidState:
        """Check the arrays (a bad one raises ``ValueError`` naming it; ``q`` must be unit)
        and broadcast them to one leading shape."""
        arrays = {"x": as_array(x, "x", (3,)), "v": as_array(v, "v", (3,)), "q": _unit_quat(q),
                  "L": as_array(L, "L", (3,))}
        try:
            lead = np.broadcast_shapes(*(a.shape[:-1] for a in arrays.values()))
        except ValueError:
            shapes = ", ".join(f"{k} {a.shape}" for k, a in arrays.items())
            raise ValueError(f"x, v, q, L: leading shapes do not broadcast: {shapes}") from None
        return cls(**{k: np.broadcast_to(a, lead + a.shape[-1:]).copy()
                      for k, a in arrays.items()})

    @property
    def R(self) -> Array:
        """(..., 3, 3) the orientation as a rotation matrix."""
        return _matrix(self.q)

    def omega(self, body: RigidBody) -> Array:
        """(..., 3) world angular velocity ``ω = I⁻¹ L``."""
        return _omega(self.L, self.R, body.inertia_inv)


def _matrix(q: Array) -> Array:
    """Rotation matrices of unit quaternions, unchecked (the state's were checked; the public
    matrix_from_quat checks again at every step): the columns are the turned axes."""
    return np.swapaxes(_kernels.quat_rotate(q[..., None, :], np.eye(3)), -1, -2)


# -- inertia, angular velocity, torque, energy -------------------------------------------------


def world_inertia(R: ArrayLike, inertia: ArrayLike) -> Array:
    """World-frame inertia ``I = R I₀ Rᵀ``.

    Parameters
    ----------
    R : (..., 3, 3) orientations (body to world).
    inertia : (..., 3, 3) body-frame inertia ``I₀``; broadcasts against ``R``.

    Returns
    -------
    (..., 3, 3)
    """
    R = as_array(R, "R", (3, 3))
    out: Array = R @ as_array(inertia, "inertia", (3, 3)) @ np.swapaxes(R, -1, -2)
    return out


def _omega(L: Array, R: Array, I0_inv: Array) -> Array:
    """``I⁻¹ L = R I₀⁻¹ Rᵀ L``, turned into the body frame and back (no world-frame solve)."""
    body = np.einsum("...ji,...j->...i", R, L)
    out: Array = np.einsum("...ij,...j->...i", R, body @ I0_inv.T)
    return out


def angular_velocity(L: ArrayLike, R: ArrayLike, inertia: ArrayLike) -> Array:
    """World angular velocity ``ω = I⁻¹ L = R I₀⁻¹ Rᵀ L``.

    Parameters
    ----------
    L : (..., 3) angular momentum (world frame).
    R : (..., 3, 3) orientations.
    inertia : (3, 3) body-frame inertia ``I₀``.

    Returns
    -------
    (..., 3)
    """
    inv = np.asarray(np.linalg.inv(_inertia(inertia)), dtype=np.float64)
    return _omega(as_array(L, "L", (3,)), as_array(R, "R", (3, 3)), inv)


def point_torque(p: ArrayLike, x: ArrayLike, f: ArrayLike) -> Array:
    """Torque about ``x`` of a force ``f`` applied at the point ``p``: ``τ = (p − x) × f``.

    Parameters
    ----------
    p, x, f : (..., 3) world frame; broadcast together.

    Returns
    -------
    (..., 3)
    """
    out: Array = np.cross(as_array(p, "p", (3,)) - as_array(x, "x", (3,)), as_array(f, "f", (3,)))
    return out


def kinetic_energy(mass: float, inertia: ArrayLike, v: ArrayLike, L: ArrayLike,
                   R: ArrayLike) -> Array:
    """``T = ½ m‖v‖² + ½ L·ω`` with ``ω = I⁻¹ L``.

    Parameters
    ----------
    mass : ``m > 0``.
    inertia : (3, 3) body-frame inertia ``I₀``.
    v, L : (..., 3) velocity and angular momentum.
    R : (..., 3, 3) orientations.

    Returns
    -------
    (...)
    """
    m = as_positive(mass, "mass")
    v = as_array(v, "v", (3,))
    L = as_array(L, "L", (3,))
    omega = angular_velocity(L, R, inertia)
    out: Array = 0.5 * m * np.sum(v * v, axis=-1) + 0.5 * np.sum(L * omega, axis=-1)
    return out


# -- ground contact ----------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class Ground:
    r"""The ground plane ``y = 0`` as a penalty spring–damper at each contact point.

    A point ``p`` below the plane with velocity ``ṗ`` is pushed up by
    ``f_y = max(0, −k p_y − d ṗ_y)`` (the ``max``: the ground only pushes), and, if
    ``friction > 0``, slowed along the plane by ``f_t = −friction · ṗ_t``: viscous
    tangential damping, a simplification of Coulomb friction (no cone ``‖f_t‖ ≤ μ f_y``, no
    sticking; a body slides to a stop instead of holding on a slope).

    Parameters
    ----------
    k : stiffness per contact point (N/m), > 0.
    d : damping per contact point (N s/m), >= 0.
    friction : tangential damping per contact point (N s/m), >= 0.
    """

    k: float
    d: float = 0.0
    friction: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "k", as_positive(self.k, "k"))
        object.__setattr__(self, "d", as_positive(self.d, "d", allow_zero=True))
        object.__setattr__(self, "friction", as_positive(self.friction, "friction",
                                                       allow_zero=True))


def _contact(body: RigidBody, x: Array, v: Array, R: Array, omega: Array,
             ground: Ground) -> tuple[Array, Array]:
    """Lever arms ``r = R r₀ (..., P, 3)`` and contact forces ``(..., P, 3)``."""
    r = np.einsum("...ij,pj->...pi", R, body.points)
    p = x[..., None, :] + r
    p_dot = v[..., None, :] + np.cross(omega[..., None, :], r)
    below = p[..., 1] < 0
    f = np.where(below[..., None], -ground.friction * p_dot, 0.0)
    # the normal force replaces the y column, which leaves the friction tangential
    f[..., 1] = np.where(below, np.maximum(0.0, -ground.k * p[..., 1] - ground.d * p_dot[..., 1]),
                         0.0)
    return r, f


def contact_forces(body: RigidBody, state: RigidState, ground: Ground) -> tuple[Array, Array]:
    """The world positions of the body's contact points and the ground's force on each.

    Returns
    -------
    p : (..., P, 3) contact points ``x + R r₀``.
    f : (..., P, 3) forces (0 above the plane; see :class:`Ground`).
    """
    r, f = _contact(body, state.x, state.v, state.R, state.omega(body), ground)
    return state.x[..., None, :] + r, f


class RigidEnergy(NamedTuple):
    """A state's energy (J), each (...): kinetic translational ``½ m‖v‖²`` and rotational
    ``½ L·ω``, gravitational ``−m g·x`` and the contact springs' ``Σ ½ k (p_y)²`` below
    the plane."""

    translational: Array
    rotational: Array
    gravity: Array
    contact: Array

    @property
    def total(self) -> Array:
        total: Array = self.translational + self.rotational + self.gravity + self.contact
        return total


def rigid_energy(body: RigidBody, state: RigidState, gravity: ArrayLike = GRAVITY,
                 ground: Ground | None = None) -> RigidEnergy:
    """The energy of ``state`` (the contact term is 0 without ``ground``)."""
    g = as_array(gravity, "gravity", (3,))
    contact = np.zeros(state.x.shape[:-1])
    if ground is not None and len(body.points):
        y = state.x[..., None, 1] + np.einsum("...j,pj->...p", state.R[..., 1, :], body.points)
        contact = 0.5 * ground.k * np.sum(np.minimum(y, 0.0) ** 2, axis=-1)
    return RigidEnergy(0.5 * body.mass * np.sum(state.v**2, axis=-1),
                       0.5 * np.sum(state.L * state.omega(body), axis=-1),
                       -body.mass * (state.x @ g), contact)


# -- orientation updates -----------------------------------------------------------------------


def _quat_euler(q: Array, omega: Array, h: float) -> Array:
    pure = np.concatenate([np.zeros(omega.shape[:-1] + (1,)), omega], axis=-1)
    return unit(q + 0.5 * h * _kernels.quat_mul(pure, q))


def quat_euler_step(q: ArrayLike, omega: ArrayLike, h: float) -> Array:
    """``q⁺ = q + (h/2) [0, ω] ⊗ q``, renormalised (forward Euler on ``q̇ = ½ [0, ω] ⊗ q``).

    Parameters
    ----------
    q : (..., 4) unit quaternions.
    omega : (..., 3) world angular velocity; broadcasts against ``q``.
    h : time step, > 0.

    Returns
    -------
    (..., 4) unit quaternions.
    """
    return _quat_euler(_unit_quat(q), as_array(omega, "omega", (3,)), as_time_step(h))


def _polar(R: Array) -> Array:
    U, _, Vt = np.linalg.svd(R)
    U[..., :, 2] *= np.where(np.linalg.det(U @ Vt) < 0, -1.0, 1.0)[..., None]
    out: Array = U @ Vt
    return out


def orthonormalize(R: ArrayLike) -> Array:
    """The rotation nearest to ``R`` (Frobenius norm): the polar factor ``U Vᵀ`` of
    ``R = U Σ Vᵀ``, with the last column of ``U`` flipped if that would be a reflection.

    Parameters
    ----------
    R : (..., 3, 3)

    Returns
    -------
    (..., 3, 3) rotation matrices.
    """
    return _polar(as_array(R, "R", (3, 3)))


def _matrix_euler(R: Array, omega: Array, h: float) -> Array:
    return _polar(R + h * _kernels.skew(omega) @ R)


def matrix_euler_step(R: ArrayLike, omega: ArrayLike, h: float) -> Array:
    """``R⁺ = R + h [ω]× R``, re-orthonormalised by :func:`orthonormalize` (forward Euler on
    ``Ṙ = [ω]× R``).

    Parameters
    ----------
    R : (..., 3, 3) rotation matrices.
    omega : (..., 3) world angular velocity; broadcasts against ``R``.
    h : time step, > 0.

    Returns
    -------
    (..., 3, 3) rotation matrices.
    """
    return _matrix_euler(as_array(R, "R", (3, 3)), as_array(omega, "omega", (3,)), as_time_step(h))


def _quat_exp(q: Array, omega: Array, h: float) -> Array:
    # exp of the pure quaternion (0, hω/2) is the rotation-vector quaternion of hω
    return _kernels.quat_mul(quat_from_rotvec(h * omega), q)


def quat_exp_step(q: ArrayLike, omega: ArrayLike, h: float) -> Array:
    """``q⁺ = exp(h ω / 2) ⊗ q``: the exact rotation by ``h‖ω‖`` about ``ω`` (for ``ω``
    constant over the step); unit up to rounding, with nothing to repair.

    Parameters
    ----------
    q : (..., 4) unit quaternions.
    omega : (..., 3) world angular velocity; broadcasts against ``q``.
    h : time step, > 0.

    Returns
    -------
    (..., 4) unit quaternions.
    """
    return _quat_exp(_unit_quat(q), as_array(omega, "omega", (3,)), as_time_step(h))


def _turn(rotation: str, q: Array, R: Array, omega: Array, h: float) -> Array:
    if rotation == "quaternion":
        return _quat_euler(q, omega, h)
    if rotation == "matrix":
        return quat_from_matrix(_matrix_euler(R, omega, h))
    return _quat_exp(q, omega, h)


# -- stepping ----------------------------------------------------------------------------------


class _Setup(NamedTuple):
    """A step's checked options."""

    h: float
    method: str
    rotation: str
    gravity: Array
    ground: Ground | None
    applied: Applied | None


def _setup(h: float, method: str, rotation: str, gravity: ArrayLike, ground: Ground | None,
           applied: Applied | None) -> _Setup:
    _choice(method, "method", INTEGRATORS)
    _choice(rotation, "rotation", ROTATION_UPDATES)
    if ground is not None and not isinstance(ground, Ground):
        raise ValueError(f"ground: expected a Ground or None, got {type(ground).__name__}")
    return _Setup(as_time_step(h), method, rotation, as_array(gravity, "gravity", (3,)), ground,
                  applied)


def _wrench(body: RigidBody, s: RigidState, R: Array, omega: Array,
            setup: _Setup) -> tuple[Array, Array]:
    """Total force and torque about ``x``: gravity, ground contact and applied forces."""
    f = np.broadcast_to(body.mass * setup.gravity, s.x.shape).copy()
    tau = np.zeros_like(f)
    if setup.ground is not None and len(body.points):
        r, fc = _contact(body, s.x, s.v, R, omega, setup.ground)
        f += fc.sum(axis=-2)
        tau += np.cross(r, fc).sum(axis=-2)
    if setup.applied is not None:
        fa, ta = setup.applied(s)
        f += as_array(fa, "applied force", (3,))
        tau += as_array(ta, "applied torque", (3,))
    return f, tau


def _advance(body: RigidBody, s: RigidState, setup: _Setup) -> tuple[Array, Array, Array, Array]:
    """The next ``x, v, q, L``, unchecked (:func:`simulate_rigid` looks for a blow-up first)."""
    h = setup.h
    R = s.R
    omega = _omega(s.L, R, body.inertia_inv)
    f, tau = _wrench(body, s, R, omega, setup)
    v = s.v + h * f / body.mass
    L = s.L + h * tau
    if setup.method == "symplectic":
        x = s.x + h * v
        omega = _omega(L, R, body.inertia_inv)
    else:
        x = s.x + h * s.v
    return x, v, _turn(setup.rotation, s.q, R, omega, h), L


def step_rigid(body: RigidBody, state: RigidState, h: float, *,
               method: Integrator = "symplectic", rotation: Rotation = "exact",
               gravity: ArrayLike = GRAVITY, ground: Ground | None = None,
               applied: Applied | None = None) -> RigidState:
    """Advance ``state`` by one time step ``h`` (the module doc has the equations).

    Parameters
    ----------
    body : the body's mass, inertia and contact points.
    state : the state at step n.
    h : time step (s), > 0.
    method : ``"explicit"`` or ``"symplectic"`` Euler.
    rotation : the orientation update, ``"exact"``, ``"quaternion"`` or ``"matrix"``.
    gravity : (3,) acceleration, default ``(0, -9.81, 0)``; ``(0, 0, 0)`` for a free body.
    ground : penalty contact with ``y = 0`` at ``body.points``, or None.
    applied : more forces, ``state -> (f, τ)`` (world frame, ``τ`` about ``x``; use
        :func:`point_torque` for a force at a point), or None.

    Returns
    -------
    RigidState at step n + 1.
    """
    state = RigidState.create(x=state.x, v=state.v, q=state.q, L=state.L)
    x, v, q, L = _advance(body, state, _setup(h, method, rotation, gravity, ground, applied))
    return RigidState(x=x, v=v, q=q, L=L)


@dataclass(frozen=True, kw_only=True, eq=False)
class RigidTrajectory:
    """What :func:`simulate_rigid` recorded: ``x, v, L`` (T + 1, ..., 3), ``q`` (T + 1, ..., 4),
    the start included (fewer rows if it exploded), and ``energy`` per recorded state;
    ``exploded_at`` is the step at which the state became non-finite or ``x`` moved farther
    than ``blowup`` from its start, else None."""

    body: RigidBody
    h: float
    x: Array
    v: Array
    q: Array
    L: Array
    energy: RigidEnergy
    exploded_at: int | None

    @property
    def t(self) -> Array:
        """(T + 1,) the recorded times."""
        t: Array = self.h * np.arange(len(self.x), dtype=np.float64)
        return t

    @property
    def omega(self) -> Array:
        """(T + 1, ..., 3) world angular velocity ``ω = I⁻¹ L``."""
        return _omega(self.L, _matrix(self.q), self.body.inertia_inv)

    @property
    def omega_body(self) -> Array:
        """(T + 1, ..., 3) body-frame angular velocity ``I₀⁻¹ Rᵀ L`` (what Euler's equations
        ``I₀ ω̇ = (I₀ ω) × ω`` evolve)."""
        body_L = np.einsum("...ji,...j->...i", _matrix(self.q), self.L)
        out: Array = body_L @ self.body.inertia_inv.T
        return out


def simulate_rigid(body: RigidBody, state: RigidState, h: float, n_steps: int, *,
                   method: Integrator = "symplectic", rotation: Rotation = "exact",
                   gravity: ArrayLike = GRAVITY, ground: Ground | None = None,
                   applied: Applied | None = None, blowup: float = 1e3) -> RigidTrajectory:
    """Run ``n_steps`` of :func:`step_rigid` (same arguments), recording states and energies;
    stop early when the state stops being finite or ``x`` moves more than ``blowup`` (m)
    from where it started (:attr:`RigidTrajectory.exploded_at`)."""
    setup = _setup(h, method, rotation, gravity, ground, applied)
    if int(n_steps) != n_steps or n_steps < 0:
        raise ValueError(f"n_steps: must be a non-negative integer, got {n_steps!r}")
    state = RigidState.create(x=state.x, v=state.v, q=state.q, L=state.L)
    rows = [(state.x, state.v, state.q, state.L)]
    s, exploded = state, None
    with np.errstate(over="ignore", invalid="ignore"):
        for n in range(1, int(n_steps) + 1):
            new = _advance(body, s, setup)
            if not (all(np.all(np.isfinite(a)) for a in new)
                    and np.abs(new[0] - state.x).max() <= blowup):
                exploded = n
                break
            rows.append(new)
            s = RigidState(x=new[0], v=new[1], q=new[2], L=new[3])
    x, v, q, L = (np.stack(column) for column in zip(*rows, strict=True))
    e = rigid_energy(body, RigidState(x=x, v=v, q=q, L=L), setup.gravity, ground)
    return RigidTrajectory(body=body, h=setup.h, x=x, v=v, q=q, L=L, energy=e,
                           exploded_at=exploded)


# -- common bodies -----------------------------------------------------------------------------


def box_inertia(mass: float, half_extents: ArrayLike) -> Array:
    """Inertia of a solid box about its centre, ``I₀ = m/3 diag(b²+c², a²+c², a²+b²)`` for
    half-extents ``(a, b, c)`` along the body axes.

    Returns
    -------
    (3, 3)
    """
    m = as_positive(mass, "mass")
    a, b, c = _half_extents(half_extents) ** 2
    return m / 3.0 * np.diag([b + c, a + c, a + b])


def _half_extents(half_extents: ArrayLike) -> Array:
    e = as_array(half_extents, "half_extents", (3,))
    if e.shape != (3,) or np.any(e <= 0):
        raise ValueError(f"half_extents: expected three positive lengths, got {e.tolist()}")
    return e


def box_corners(half_extents: ArrayLike) -> Array:
    """The 8 corners ``(±a, ±b, ±c)`` of a box, (8, 3), body frame."""
    signs = np.array(np.meshgrid([-1.0, 1.0], [-1.0, 1.0], [-1.0, 1.0], indexing="ij"))
    corners: Array = signs.reshape(3, 8).T * _half_extents(half_extents)
    return corners


def box(mass: float, half_extents: ArrayLike) -> RigidBody:
    """A solid box with its 8 corners as contact points."""
    return RigidBody(mass=mass, inertia=box_inertia(mass, half_extents),
                     points=box_corners(half_extents))


def parallel_axis(mass: float, inertia: ArrayLike, offset: ArrayLike) -> Array:
    """Inertia about a point ``−offset`` from the centre of mass (Steiner):
    ``I₀ + m (‖d‖² E − d dᵀ)`` with ``d`` = ``offset``, (3, 3)."""
    d = as_array(offset, "offset", (3,))
    return as_array(inertia, "inertia", (3, 3)) + as_positive(mass, "mass") * (
        (d @ d) * np.eye(3) - np.outer(d, d))


def t_handle(mass: float = 0.2, bar_half_length: float = 0.06, stem_length: float = 0.1,
             half_thickness: float = 0.008) -> RigidBody:
    """A T-handle (the Dzhanibekov wing nut): a bar along x through the origin and a stem
    along +y from the bar's middle, both square in cross-section, of uniform density.

    The body frame is at the centre of mass; x, y, z are principal axes (the shape is
    mirror-symmetric in x and z). With the defaults the moments are ordered ``I_y < I_x <
    I_z``: x, the bar's axis, is the intermediate one. The contact points are both boxes'
    corners.
    """
    a = as_positive(bar_half_length, "bar_half_length")
    l_stem = as_positive(stem_length, "stem_length")
    t = as_positive(half_thickness, "half_thickness")
    bar = np.array([a, t, t])
    stem = np.array([t, l_stem / 2, t])
    # the stem starts at the bar's top face; mass split by volume
    centres = np.array([[0.0, 0.0, 0.0], [0.0, t + l_stem / 2, 0.0]])
    volumes = np.array([np.prod(bar), np.prod(stem)])
    masses = as_positive(mass, "mass") * volumes / volumes.sum()
    com = masses @ centres / masses.sum()
    inertia = np.sum([parallel_axis(mi, box_inertia(mi, e), c - com)
                      for mi, e, c in zip(masses, (bar, stem), centres, strict=True)], axis=0)
    points = np.concatenate([box_corners(bar) + centres[0], box_corners(stem) + centres[1]])
    return RigidBody(mass=mass, inertia=inertia, points=points - com)


def capsule_inertia(mass: float, radius: float, half_length: float) -> Array:
    r"""Inertia of a solid capsule (a cylinder of length ``H = 2 half_length`` capped by two
    hemispheres of radius ``r``) about its centre, its axis along y, of uniform density.

    With the mass split by volume into the cylinder's ``m_c`` and the two caps' ``m_s``,

    .. math:: I_y = m_c \frac{r^2}2 + m_s \frac{2r^2}5,\qquad
              I_x = I_z = m_c\left(\frac{H^2}{12} + \frac{r^2}4\right)
                    + m_s\left(\frac{2r^2}5 + \frac{H^2}4 + \frac{3Hr}8\right).

    Returns
    -------
    (3, 3)
    """
    m = as_positive(mass, "mass")
    r = as_positive(radius, "radius")
    H = 2.0 * as_positive(half_length, "half_length", allow_zero=True)
    v_cyl, v_caps = np.pi * r * r * H, 4.0 / 3.0 * np.pi * r**3
    m_c, m_s = m * v_cyl / (v_cyl + v_caps), m * v_caps / (v_cyl + v_caps)
    axial = m_c * r * r / 2 + m_s * 2 * r * r / 5
    across = m_c * (H * H / 12 + r * r / 4) + m_s * (2 * r * r / 5 + H * H / 4 + 3 * H * r / 8)
    return np.diag([across, axial, across])
