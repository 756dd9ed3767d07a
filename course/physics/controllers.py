r"""Controllers 控制器 of the simulated character: what a
:class:`~course.physics.simulation.Simulation` asks for its torques.

A controller supplies only torques, :math:`\tau = \pi(q, \dot q, t)`:
:meth:`Controller.torques` (the interface is defined next to the loop that calls it,
:class:`course.physics.simulation.Controller`, and re-exported here) gets the simulation (its
``model`` and ``data`` after ``mj_step1``: kinematics, COM and Jacobians of the current
state) and the time, and returns generalized forces ``(nv,)``; the simulation zeroes the
root's six (never actuated), clips every component to its ``torque_limit`` and applies them
through ``qfrc_applied``. ``reset(sim)`` (once per run) and ``before_frame(sim)`` (once per
frame) are optional hooks. Pushes, the held root, the fall and divergence tests, recording
and ``on_frame`` are the simulation's.

Here the joint-space laws, one class each:

* :class:`PD` — :math:`\tau = k_p(\bar q \ominus q) - k_d\dot q` per ball joint, to a fixed
  pose or to a clip's next frame;
* :class:`StablePD` — Tan, Liu and Turk (2011): the position term at :math:`q + h\dot q`,
  the damping implicit (MuJoCo's joint damping with the ``implicitfast`` integrator).

The balance controllers (the ankle strategy, Jacobian transpose on the COM) build on
:class:`PD` in :mod:`course.physics.balance`, next to the COM Jacobians they use. A new one
subclasses :class:`Controller` (or :class:`PD`)::

    class Zero(Controller):
        def torques(self, sim, t):
            return np.zeros(sim.model.nv)

    Simulation(character, qpos, frame_time=1 / 60).run(Zero(), n_frames=61)
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .._validate import as_array, as_positive
from .model import import_mujoco
from .simulation import Controller, Simulation


class PD(Controller):
    r"""Joint PD: :math:`\tau = k_p(\bar q \ominus q) - k_d\dot q` per ball joint.

    :math:`\bar q \ominus q = \log(q^{-1}\bar q)` is the rotation vector from the current to
    the target local rotation in the joint's own frame (``mj_differentiatePos``).

    Parameters
    ----------
    target : array_like, shape (nq,) or (F, nq)
        The pose held (one ``qpos``), or one per frame: the steps of frame ``i`` aim at row
        ``i`` (a clip's *next* frame, held between frames), so ``F`` covers the frames run.
    kp, kd : float
        Gains, N m/rad and N m s/rad, the same for every joint; non-negative.
    """

    def __init__(self, target: ArrayLike, kp: float, kd: float) -> None:
        self.target = as_array(target, "target")
        if self.target.ndim not in (1, 2):
            raise ValueError(f"target: one qpos (nq,) or one per frame (F, nq), got shape "
                             f"{self.target.shape}")
        self.kp = as_positive(kp, "kp", allow_zero=True)
        self.kd = as_positive(kd, "kd", allow_zero=True)
        self._kd_explicit = self.kd

    def reset(self, sim: Simulation) -> None:
        """Check the target against ``sim.model``; allocate the work arrays."""
        nq = sim.model.nq
        if self.target.shape[-1] != nq:
            raise ValueError(f"target: qpos of {nq} numbers expected (nq), got shape "
                             f"{self.target.shape}")
        self._mj = import_mujoco()
        self._err = np.zeros(sim.model.nv)
        self._tau = np.zeros(sim.model.nv)

    def goal(self, sim: Simulation) -> Array:
        """The target ``qpos`` of the step in progress (row ``sim.frame`` of a per-frame
        target)."""
        return self.target if self.target.ndim == 1 else self.target[sim.frame]

    def position(self, sim: Simulation) -> Array:
        """The ``qpos`` the position error is measured at: the current one."""
        out: Array = sim.data.qpos
        return out

    def torques(self, sim: Simulation, t: float) -> Array:
        """:math:`k_p(\\bar q \\ominus q) - k_d\\dot q` (the root's entries are ignored)."""
        tau = self._tau
        self._mj.mj_differentiatePos(sim.model, self._err, 1.0, self.position(sim),
                                     self.goal(sim))
        np.multiply(self._err, self.kp, out=tau)
        tau -= self._kd_explicit * sim.data.qvel
        return tau


class StablePD(PD):
    r"""Stable PD (Tan, Liu and Turk 2011): :math:`\tau = k_p(\bar q \ominus (q + h\dot q))
    - k_d(\dot q + h\ddot q)`.

    The position term is evaluated at ``q + h q̇`` (``mj_integratePos``); the damping term at
    the next velocity is MuJoCo's own implicit joint damping (:meth:`reset` sets
    ``dof_damping = kd`` on the actuated DOFs and the ``implicitfast`` integrator), which is
    exactly ``-kd q̇_{n+1}``, so no mass-matrix solve is written here. Parameters as
    :class:`PD`.
    """

    def __init__(self, target: ArrayLike, kp: float, kd: float) -> None:
        super().__init__(target, kp, kd)
        self._kd_explicit = 0.0  # the damping is the integrator's

    def reset(self, sim: Simulation) -> None:
        """As :class:`PD`, and the implicit damping on ``sim.model``."""
        super().reset(sim)
        sim.model.opt.integrator = self._mj.mjtIntegrator.mjINT_IMPLICITFAST
        sim.model.dof_damping[sim.actuated] = self.kd
        self._predicted = np.zeros(sim.model.nq)

    def position(self, sim: Simulation) -> Array:
        """``q + h q̇``."""
        q = self._predicted
        q[:] = sim.data.qpos
        self._mj.mj_integratePos(sim.model, q, sim.data.qvel, sim.h)
        return q


__all__ = ["PD", "Controller", "StablePD"]
