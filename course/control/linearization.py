r"""Linearisation of any MuJoCo model about a state: ``A``, ``B`` of one simulation step.

As in MuJoCo's LQR tutorial, the Jacobians are MuJoCo's own finite differences of
``mj_step``, ``mujoco.mjd_transitionFD``: one step from the state perturbed along each
coordinate in turn (both ways with ``centered``), so they are the Jacobians of exactly the
step the simulation takes — integrator, contacts, actuators and all — with no equation
written by hand::

    δx_{t+1} ≈ A δx_t + B δu_t,      x = (dq, qvel, act),  u = ctrl

``dq`` is the position in MuJoCo's *tangent* space (``nv`` entries, not ``nq``): for hinge and
slide joints the change of ``qpos``, for ball and free joints a rotation vector
(``mj_differentiatePos``). So ``x`` has ``2 nv + na`` entries and ``A`` is
``(2nv + na, 2nv + na)``, ``B`` is ``(2nv + na, nu)``. :func:`state_difference` turns two
``(qpos, qvel)`` into that ``δx``, the error an LQR feedback ``u = ū - K δx`` acts on.

mujoco is imported when a function here is first called (``import course.control`` does not
load it): ``pip install 'course-kinematics[physics]'``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .._validate import as_array, as_positive


def import_mujoco() -> Any:
    """The ``mujoco`` module, imported on first use; an ImportError that says how to get it."""
    try:
        import mujoco  # type: ignore[import-untyped]  # (no stubs shipped)
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("course.control.linearization needs MuJoCo: pip install "
                          "'course-kinematics[physics]' (or pip install 'mujoco>=3.1')") from exc
    return mujoco


@dataclass(frozen=True)
class Linearization:
    """``δx_{t+1} ≈ A δx_t + B δu_t`` about one state and control of a MuJoCo model.

    Attributes
    ----------
    A : ndarray, shape (2 nv + na, 2 nv + na)
        Rows and columns ordered ``(dq, qvel, act)``.
    B : ndarray, shape (2 nv + na, nu)
    dt : float
        The model's time step (``opt.timestep``), s.
    nv, na, nu : int
        Degrees of freedom, actuator activations, controls.
    eps : float
        The finite-difference step.
    centered : bool
        Central differences (error ``O(eps²)``) or forward (``O(eps)``, half the steps).
    """

    A: Array
    B: Array
    dt: float
    nv: int
    na: int
    nu: int
    eps: float
    centered: bool

    @property
    def n_states(self) -> int:
        return 2 * self.nv + self.na


def _check_model(model: Any) -> None:
    if not all(hasattr(model, a) for a in ("nq", "nv", "nu", "na", "opt")):
        raise ValueError(f"model: expected a mujoco.MjModel, got {type(model).__name__}")


def _vector(value: ArrayLike | None, name: str, size: int, default: Array) -> Array:
    if value is None:
        return np.array(default, dtype=np.float64)
    a = as_array(value, name)
    if a.shape != (size,):
        raise ValueError(f"{name}: expected shape ({size},) for this model, got {a.shape}")
    return a


def linearize(model: Any, qpos: ArrayLike, qvel: ArrayLike | None = None,
              ctrl: ArrayLike | None = None, *, act: ArrayLike | None = None,
              eps: float = 1e-6, centered: bool = True) -> Linearization:
    """``A``, ``B`` of one ``mj_step`` of ``model`` about ``(qpos, qvel, act)`` and ``ctrl``.

    Parameters
    ----------
    model : mujoco.MjModel
    qpos : array_like, shape (nq,)
    qvel : array_like, shape (nv,), optional
        Zero when omitted.
    ctrl : array_like, shape (nu,), optional
        Zero when omitted. For a balance about a pose, the control that holds it (e.g. the
        gravity-compensating torques of inverse dynamics), so the pose is an equilibrium.
    act : array_like, shape (na,), optional
        Actuator activations; zero when omitted (most models have ``na = 0``).
    eps : float
        The perturbation, in each coordinate's own unit (rad, m, rad/s, control units).
    centered : bool

    Works on a fresh ``MjData``: nothing of the caller's is changed.
    """
    mujoco = import_mujoco()
    _check_model(model)
    data = mujoco.MjData(model)
    data.qpos[:] = _vector(qpos, "qpos", model.nq, model.qpos0)
    data.qvel[:] = _vector(qvel, "qvel", model.nv, np.zeros(model.nv))
    data.ctrl[:] = _vector(ctrl, "ctrl", model.nu, np.zeros(model.nu))
    data.act[:] = _vector(act, "act", model.na, np.zeros(model.na))
    h = as_positive(eps, "eps")
    mujoco.mj_forward(model, data)
    n = 2 * model.nv + model.na
    A = np.zeros((n, n))
    B = np.zeros((n, model.nu))
    mujoco.mjd_transitionFD(model, data, h, bool(centered), A, B, None, None)
    return Linearization(A=A, B=B, dt=float(model.opt.timestep), nv=int(model.nv),
                         na=int(model.na), nu=int(model.nu), eps=h, centered=bool(centered))


def state_difference(model: Any, qpos: ArrayLike, qvel: ArrayLike, qpos_ref: ArrayLike,
                     qvel_ref: ArrayLike) -> Array:
    """``δx = (qpos ⊖ qpos_ref, qvel - qvel_ref)``, ``(2 nv,)``: the state error in the
    coordinates of :func:`linearize`'s ``A`` (``⊖`` is ``mj_differentiatePos``, the
    tangent-space difference, a rotation vector for ball and free joints)."""
    mujoco = import_mujoco()
    _check_model(model)
    zeros_q, zeros_v = np.zeros(model.nq), np.zeros(model.nv)
    q = _vector(qpos, "qpos", model.nq, zeros_q)
    q_ref = _vector(qpos_ref, "qpos_ref", model.nq, zeros_q)
    v = _vector(qvel, "qvel", model.nv, zeros_v)
    v_ref = _vector(qvel_ref, "qvel_ref", model.nv, zeros_v)
    dq = np.zeros(model.nv)
    mujoco.mj_differentiatePos(model, dq, 1.0, q_ref, q)
    return np.asarray(np.concatenate([dq, v - v_ref]), dtype=np.float64)
