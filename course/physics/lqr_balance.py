r"""LQR balance 线性二次调节平衡 of the standing character, after MuJoCo's LQR tutorial.

MuJoCo's ``python/LQR.ipynb`` balances its humanoid on one leg in five steps; here they are on
the character of :func:`~course.physics.model.build_model`, standing on both feet in
:func:`~course.physics.balance.standing_pose` or, as the tutorial, on one leg in
:func:`one_leg_pose` (``design(character, stance=0)``: the other foot lifted, the COM over the
stance foot; the support point, the balance DOFs and the feet weighted are then the stance
leg's alone):

1. **B needs inputs.** The character has no actuators (its torques go through
   ``qfrc_applied``), so :func:`motor_model` compiles a copy of its MJCF with three motors per
   ball joint (``gear="1 0 0"``, ``"0 1 0"``, ``"0 0 1"``): ``ctrl`` is then exactly the
   joint's generalized force, the torque :class:`LQRBalance` returns, and the root has none.
2. **The equilibrium** (:func:`equilibrium`): inverse dynamics (``mj_inverse`` at
   ``qvel = qacc = 0``) gives the generalized forces that hold a pose, contact forces
   included. The tutorial searches the height at which the root needs the least vertical
   force; here the root's whole residual must vanish, since no joint torque can supply it, so
   Newton's method moves the root's height *and* tilts the body (two angles, about 2 mrad on
   the CMU skeleton) until the root's vertical force and horizontal moments are zero (1e-9):
   with soft contact the centre of pressure follows the feet's penetration, so a tiny tilt
   puts it under the COM. ``ctrl0`` is then ``qfrc_inverse`` of the joints, and
   ``(qpos0, 0, ctrl0)`` is a true equilibrium of the simulated dynamics.
3. **Linearisation** (:func:`design`): ``mujoco.mjd_transitionFD`` (centred, ``eps = 1e-6``)
   about ``(qpos0, 0, ctrl0)``, on the motor model **with the solver's tolerance set to 0**.
   With the model's tolerance (1e-8) the constraint solver, warm-started at the unperturbed
   solution, stops before it has moved: every contact-bearing column comes out wrong and
   ``B`` is *exactly zero* in contact (``tests/test_character_lqr.py`` shows both).
4. **The cost**: the tutorial's ``Q`` on positions, ``balance · (J_c - J_s)ᵀ(J_c - J_s)``
   with ``J_c`` the COM Jacobian and ``J_s`` the support point's (the mean of the standing
   feet's COM Jacobians), plus joint deviations weighted per group (the standing legs' and
   the spine's joints, the tutorial's "balance" DOFs, and the others; the root none),
   ``R = I`` (N m);
   velocities unweighted. ``feet`` adds a cost on the feet's motion (position and rotation
   of the foot and toe bodies), which the tutorial does not need.
5. **The gain**: ``scipy.linalg.solve_discrete_are`` and
   ``K = (R + BᵀPB)⁻¹ BᵀPA``; the control is ``u = ctrl0 - K δx``, ``δx`` from
   ``mj_differentiatePos`` (:class:`LQRBalance`). The floor leaves neutral modes (sliding
   and turning on the ground, eigenvalue 1) that no torque controls and ``Q`` does not see;
   the DARE solver refuses those, so it is solved for ``(√γ A, √γ B)`` with
   ``γ = 1 - 1e-4`` (a 16 s horizon at h = 1/600 s).

The simulation (:class:`~course.physics.simulation.Simulation`) runs the character's own
model, torques through ``qfrc_applied``, the root's six zeroed on every step; a
push is survived as in :func:`course.physics.balance.largest_push` (0.1 s on the root from
0.25 s, standing 1.5 s after it, COM above 60 % of its height; a run that diverges counts as a
fall). What it achieves, and why not more, is in ``docs/control.md`` ("LQR balance of the
character").
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._typing import Array
from .._validate import as_positive
from ..motion import Motion
from ..rotations._kernels import quat_conjugate, quat_from_rotvec, quat_mul
from .balance import bisect_push, foot_chains, leg_joints, standing_pose
from .model import Y_TO_Z_MATRIX, Character, import_mujoco, qpos_from_motion
from .simulation import Controller, Fall, Push, Recording, Simulation

#: The discount the DARE is solved with (module docstring, step 5).
DISCOUNT = 1.0 - 1e-4


def motor_xml(character: Character) -> str:
    """The character's MJCF with three motors per ball joint, one per axis of its frame
    (``gear`` a unit vector), so ``ctrl`` is the joints' generalized force (N m); the free
    root gets none."""
    model = character.model
    mujoco = import_mujoco()
    lines = []
    for j in range(model.njnt):
        if model.jnt_type[j] != mujoco.mjtJoint.mjJNT_BALL:
            continue
        name = model.joint(j).name
        for axis in ("1 0 0", "0 1 0", "0 0 1"):
            lines.append(f'    <motor joint="{name}" gear="{axis} 0 0 0"/>')
    actuators = "  <actuator>\n" + "\n".join(lines) + "\n  </actuator>\n</mujoco>"
    head, _, _ = character.xml.rpartition("</mujoco>")
    return head + actuators


def motor_model(character: Character, *, tolerance: float | None = 0.0) -> Any:
    """:func:`motor_xml` compiled (``nu = nv - 6``); ``tolerance`` the constraint solver's
    (0: every iteration run, what the finite differences need; None: the model's)."""
    model = import_mujoco().MjModel.from_xml_string(motor_xml(character))
    if tolerance is not None:
        model.opt.tolerance = float(tolerance)
    return model


@dataclass(frozen=True, eq=False)
class Equilibrium:
    """A standing pose that the joint torques ``ctrl`` hold with the root needing nothing.

    Attributes
    ----------
    qpos : ndarray, shape (nq,)
        The pose lowered into the soft floor and tilted (z-up).
    ctrl : ndarray, shape (nv - 6,)
        Joint torques (N m) of inverse dynamics at ``qvel = qacc = 0``.
    root_force : ndarray, shape (6,)
        What the root would still need (``qfrc_inverse[:6]``): zero to Newton's tolerance.
    height : float
        How far the root was lowered (m).
    tilt : ndarray, shape (2,)
        The body's tilt (rad, about the world x and y axes).
    tutorial_height, tutorial_root_force
        The tutorial's search alone (the height, on a 1e-6 m grid, whose vertical root force
        is smallest, no tilt): its offset (m) and the root forces it leaves (6,).
    """

    qpos: Array = field(repr=False)
    ctrl: Array = field(repr=False)
    root_force: Array
    height: float
    tilt: Array
    tutorial_height: float
    tutorial_root_force: Array


def one_leg_pose(character: Character, stance: int = 0, *, hip_flexion: float = 0.5,
                 knee_flexion: float = 1.0, tol: float = 1e-9) -> Motion:
    """A 1-frame pose standing on one foot, the other lifted, the COM above the stance foot.

    From :func:`~course.physics.balance.standing_pose`: the other leg's hip turned forward by
    ``hip_flexion`` and its knee bent back by ``knee_flexion`` (rad, about the skeleton's x
    axis; the defaults lift the foot by about 18 cm), then the stance leg alone leaned (the
    root turned about x and z, the trunk and the other leg turned back, the stance foot turned
    back so it stays flat where it stood) by Newton's method until the COM is straight above
    the stance foot's centre (the midpoint of ankle and tip) to ``tol`` (m): MuJoCo's
    tutorial humanoid stands on one leg the same way, its COM over the foot.
    :func:`equilibrium` then lowers and tilts it into the floor.

    Parameters
    ----------
    character : Character
    stance : int
        Which foot of :func:`~course.physics.balance.foot_chains` stands (0 or 1; on the CMU
        skeleton 0 is the left).
    hip_flexion, knee_flexion : float
        The lifted leg's hip and knee angles (rad).
    tol : float
        Newton's tolerance on the COM's horizontal offset (m).

    Returns
    -------
    Motion
        One frame, named ``"one leg"``.
    """
    mujoco = import_mujoco()
    if stance not in (0, 1):
        raise ValueError(f"stance: 0 or 1 (a foot of foot_chains), got {stance!r}")
    feet = foot_chains(character)
    skel = character.skeleton
    base = standing_pose(character)
    stand_chain = feet[stance]
    knee = int(skel.parents[feet[1 - stance][0]])
    hip = int(skel.parents[knee])
    leg = leg_joints(skel, stand_chain[0])
    others = [c for c in skel.children(0) if c not in leg]
    base_positions, base_rotations = base.forward_kinematics()
    data = mujoco.MjData(character.model)

    def make(lean: Array) -> tuple[Motion, Array]:
        local = base.local_rotations.copy()
        local[0, hip] = quat_mul(quat_from_rotvec(np.array([-hip_flexion, 0.0, 0.0])),
                                 local[0, hip])
        local[0, knee] = quat_mul(quat_from_rotvec(np.array([knee_flexion, 0.0, 0.0])),
                                  local[0, knee])
        turn = quat_from_rotvec(np.array([lean[0], 0.0, lean[1]]))
        local[0, 0] = quat_mul(local[0, 0], turn)
        for c in others:  # only the stance leg leans: the trunk and the other leg do not
            local[0, c] = quat_mul(quat_conjugate(turn), local[0, c])
        bare = Motion(skel, local.copy(), base.root_positions.copy(), base.frame_time)
        positions, rotations = bare.forward_kinematics()
        g_parent = rotations[0, skel.parents[stand_chain[0]]]
        for j in stand_chain[:-1]:  # the stance foot as it stood: flat
            local[0, j] = quat_mul(quat_conjugate(g_parent), base_rotations[0, j])
            g_parent = base_rotations[0, j]
        ankle = stand_chain[0]
        root = base.root_positions + base_positions[0, ankle] - positions[0, ankle]
        motion = Motion(skel, local, root, base.frame_time, name="one leg")
        data.qpos[:] = qpos_from_motion(character, motion)[0]
        mujoco.mj_kinematics(character.model, data)
        mujoco.mj_comPos(character.model, data)
        com = Y_TO_Z_MATRIX.T @ data.subtree_com[character.bodies[0]]
        p = motion.forward_kinematics()[0][0] * character.scale
        offset = com - (p[stand_chain[0]] + p[stand_chain[-1]]) / 2
        return motion, offset[[0, 2]]

    lean = _newton(lambda p: make(p)[1], np.zeros(2), tol=tol, step=1e-6, iterations=10)
    return make(lean)[0]


def _newton(residual: Callable[[Array], Array], p: Array, *, tol: float, step: float,
            iterations: int) -> Array:
    """Newton's method on a square ``residual(p)`` with a forward-difference Jacobian (steps
    of ``step``), until every entry is below ``tol`` or ``iterations`` have run."""
    for _ in range(iterations):
        r = residual(p)
        if np.abs(r).max() < tol:
            break
        jac = np.empty((len(r), len(p)))
        for k in range(len(p)):
            e = np.zeros(len(p))
            e[k] = step
            jac[:, k] = (residual(p + e) - r) / step
        p = p - np.linalg.solve(jac, r)
    return p


def equilibrium(character: Character, pose: Motion | None = None, *,
                model: Any = None, tol: float = 1e-9) -> Equilibrium:
    """The balanced equilibrium of ``pose`` (default :func:`standing_pose`), module docstring
    step 2: the tutorial's height search, then Newton on (height, tilt x, tilt y) until the
    root's vertical force and horizontal moments (world frame) are below ``tol`` (N, N m)."""
    mujoco = import_mujoco()
    model = motor_model(character) if model is None else model
    pose = standing_pose(character) if pose is None else pose
    q_pose = qpos_from_motion(character, pose[:1])[0]
    data = mujoco.MjData(model)
    root = character.bodies[0]

    def inverse(qpos: Array) -> Array:
        data.qpos[:] = qpos
        data.qvel[:] = 0.0
        mujoco.mj_forward(model, data)
        data.qacc[:] = 0.0
        mujoco.mj_inverse(model, data)
        out: Array = data.qfrc_inverse.copy()
        return out

    def make(p: Array) -> Array:
        q: Array = q_pose.copy()
        q[2] += p[0]
        turned = np.zeros(4)
        mujoco.mju_mulQuat(turned, quat_from_rotvec(np.array([p[1], p[2], 0.0])), q_pose[3:7])
        q[3:7] = turned
        return q

    def residual(p: Array) -> Array:
        f = inverse(make(p))
        moment = data.xmat[root].reshape(3, 3) @ f[3:6]  # the free joint's: body frame
        return np.array([f[2], moment[0], moment[1]])

    # the tutorial: the height whose vertical root force is smallest, on a 1e-6 m grid
    offsets = np.linspace(-0.002, 0.0, 2001)
    vertical = np.array([inverse(make(np.array([o, 0.0, 0.0])))[2] for o in offsets])
    best = float(offsets[int(np.argmin(np.abs(vertical)))])
    tutorial_force = inverse(make(np.array([best, 0.0, 0.0])))[:6]
    p = _newton(residual, np.array([best, 0.0, 0.0]), tol=tol, step=1e-7, iterations=30)
    qpos = make(p)
    f = inverse(qpos)
    return Equilibrium(qpos=qpos, ctrl=f[6:].copy(), root_force=f[:6].copy(),
                       height=float(p[0]), tilt=p[1:].copy(), tutorial_height=best,
                       tutorial_root_force=tutorial_force)


def support_feet(character: Character, stance: int | None = None) -> tuple[tuple[int, ...], ...]:
    """The feet that stand (chains of :func:`~course.physics.balance.foot_chains`): both, or
    foot ``stance`` (0 or 1) alone."""
    feet = foot_chains(character)
    if stance is None:
        return feet
    if stance not in (0, 1):
        raise ValueError(f"stance: None (both feet) or 0 or 1 (a foot of foot_chains), "
                         f"got {stance!r}")
    return (feet[stance],)


def balance_dofs(character: Character, stance: int | None = None) -> Array:
    """The tutorial's "balance" DOFs: every joint of the standing legs (hips to toes; both,
    or leg ``stance`` alone, as the tutorial's humanoid on one leg) and the spine up to the
    shoulders' parent (the root's children that are not legs, and theirs, while the chain
    does not branch)."""
    skel = character.skeleton
    legs = {j for chain in foot_chains(character) for j in _chain_up(character, chain[-1])}
    joints: set[int] = set()
    for chain in support_feet(character, stance):
        joints.update(_chain_up(character, chain[-1]))
    for c in skel.children(0):
        if c in legs:
            continue
        j = c
        while True:
            joints.add(j)
            kids = [k for k in skel.children(j) if character.bodies[k] >= 0]
            if len(kids) != 1:
                break
            j = kids[0]
    dofs = [character.dof_address[j] + k for j in sorted(joints) for k in range(3)]
    return np.array(sorted(dofs), dtype=np.intp)


def _chain_up(character: Character, joint: int) -> set[int]:
    """``joint`` and its ancestors below the root that are bodies."""
    skel = character.skeleton
    found: set[int] = set()
    while joint > 0:
        if character.bodies[joint] >= 0:
            found.add(joint)
        joint = int(skel.parents[joint])
    return found


@dataclass(frozen=True)
class Weights:
    """The cost of :func:`design` (module docstring, step 4).

    ``balance`` multiplies ``(J_c - J_s)ᵀ(J_c - J_s)`` (m⁻²), ``balance_joint`` and
    ``other_joint`` the squared joint deviations (rad⁻²), ``feet`` the feet's squared motion,
    ``velocity`` every squared velocity; ``scale`` multiplies the whole ``Q``; ``torque`` is
    ``R = torque · I`` (N⁻² m⁻²; the tutorial's humanoid has gears of about 100, so its
    ``R = I`` on ``ctrl`` is a cheaper torque than here). Only ``Q / R`` sets the gain:
    ``scale`` and ``1 / torque`` do the same. The defaults are the best of those measured
    (docs/control.md): the tutorial's three weights, ``Q`` ten times, feet 1e5, velocities 30.
    """

    balance: float = 1000.0
    balance_joint: float = 3.0
    other_joint: float = 0.3
    feet: float = 1e5
    velocity: float = 30.0
    scale: float = 10.0
    torque: float = 1.0


@dataclass(frozen=True, eq=False)
class LQRDesign:
    """Everything :class:`LQRBalance` needs, and how it was made.

    Attributes
    ----------
    equilibrium : Equilibrium
    A, B : ndarray
        ``(2nv, 2nv)``, ``(2nv, nv - 6)``: one step of h about the equilibrium.
    Q, R : ndarray
    K : ndarray, shape (nv - 6, 2nv)
        ``u = ctrl0 - K δx``.
    h : float
        The step linearised (s).
    spectral_radius : float
        Of ``A - BK`` (1 up to the floor's neutral modes).
    weights : Weights
    stance : int or None
        The standing foot (:func:`support_feet`), None for both.
    """

    equilibrium: Equilibrium
    A: Array = field(repr=False)
    B: Array = field(repr=False)
    Q: Array = field(repr=False)
    R: Array = field(repr=False)
    K: Array = field(repr=False)
    h: float
    spectral_radius: float
    weights: Weights
    stance: int | None = None


def balance_cost(character: Character, model: Any, qpos: Array,
                 weights: Weights = Weights(), stance: int | None = None) -> Array:
    """``Q (2nv, 2nv)`` of ``weights`` at ``qpos`` (module docstring, step 4), standing on
    both feet or on foot ``stance`` (:func:`support_feet`): the support point, the balance
    DOFs and the feet whose motion is weighted are the standing ones."""
    mujoco = import_mujoco()
    nv = model.nv
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_forward(model, data)
    jc = np.zeros((3, nv))
    mujoco.mj_jacSubtreeCom(model, data, jc, character.bodies[0])
    feet = support_feet(character, stance)
    js = np.zeros((3, nv))
    for chain in feet:
        jp = np.zeros((3, nv))
        mujoco.mj_jacBodyCom(model, data, jp, None, character.bodies[chain[0]])
        js += jp / len(feet)
    jd = jc - js
    joint = np.full(nv, weights.other_joint)
    joint[:6] = 0.0
    joint[balance_dofs(character, stance)] = weights.balance_joint
    qpos_cost = weights.balance * jd.T @ jd + np.diag(joint)
    if weights.feet > 0:
        for chain in feet:
            for j in chain:
                if character.bodies[j] < 0:
                    continue
                jp, jr = np.zeros((3, nv)), np.zeros((3, nv))
                mujoco.mj_jacBody(model, data, jp, jr, character.bodies[j])
                jf = np.vstack([jp, jr])
                qpos_cost += weights.feet * jf.T @ jf
    Q = np.zeros((2 * nv, 2 * nv))
    Q[:nv, :nv] = qpos_cost
    Q[nv:, nv:] = weights.velocity * np.eye(nv)
    out: Array = weights.scale * Q
    return out


def design(character: Character, pose: Motion | None = None, *, stance: int | None = None,
           weights: Weights = Weights(), h: float = 1.0 / 600.0,
           discount: float = DISCOUNT) -> LQRDesign:
    """The LQR balance of ``pose`` at the step ``h``: the module docstring's five steps.

    Parameters
    ----------
    character : Character
    pose : Motion, optional
        The pose to balance; default :func:`~course.physics.balance.standing_pose` on both
        feet, or :func:`one_leg_pose` on foot ``stance``.
    stance : int, optional
        None: standing on both feet; 0 or 1: on that foot of
        :func:`~course.physics.balance.foot_chains` alone (the tutorial's one leg), which sets
        the support point, the balance DOFs and the feet weighted in :func:`balance_cost`.
    weights : Weights
    h : float
        The simulation step linearised (s).
    discount : float
        Per step; the DARE is solved for ``(√γ A, √γ B)``.

    Returns
    -------
    LQRDesign
    """
    from ..control.linearization import linearize

    support_feet(character, stance)  # checks stance
    if pose is None and stance is not None:
        pose = one_leg_pose(character, stance)
    model = motor_model(character)
    model.opt.timestep = as_positive(h, "h")
    eq = equilibrium(character, pose, model=model)
    lin = linearize(model, eq.qpos, None, eq.ctrl, eps=1e-6, centered=True)
    return _solve(character, model, eq, lin.A, lin.B, weights, stance, discount)


def reweigh(character: Character, design: LQRDesign, weights: Weights, *,
            discount: float = DISCOUNT) -> LQRDesign:
    """``design`` with another cost: the same equilibrium and linearisation (``A``, ``B``:
    most of :func:`design`'s time), a new ``Q``, ``R`` and gain (steps 4 and 5 alone).

    Parameters
    ----------
    character : Character
        The one ``design`` was made for.
    design : LQRDesign
    weights : Weights
        The new cost.
    discount : float
        Per step, as :func:`design`'s.

    Returns
    -------
    LQRDesign
    """
    model = motor_model(character)
    model.opt.timestep = design.h
    return _solve(character, model, design.equilibrium, design.A, design.B, weights,
                  design.stance, discount)


def _solve(character: Character, model: Any, eq: Equilibrium, A: Array, B: Array,
           weights: Weights, stance: int | None, discount: float) -> LQRDesign:
    """Steps 4 and 5 of the module docstring about the linearisation ``(A, B)`` of ``eq``."""
    import scipy.linalg  # type: ignore[import-untyped]  # (no stubs shipped)

    Q = balance_cost(character, model, eq.qpos, weights, stance)
    R = as_positive(weights.torque, "weights.torque") * np.eye(model.nu)
    g = math.sqrt(discount)
    P = scipy.linalg.solve_discrete_are(g * A, g * B, Q, R)
    K = np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
    rho = float(np.abs(np.linalg.eigvals(A - B @ K)).max())
    return LQRDesign(equilibrium=eq, A=A, B=B, Q=Q, R=R, K=K, h=float(model.opt.timestep),
                     spectral_radius=rho, weights=weights, stance=stance)


class LQRBalance(Controller):
    r"""``u = ctrl0 - K δx`` on the joints, :math:`\delta x = (q \ominus \bar q, \dot q)`
    (``mj_differentiatePos``); the root's six entries are zero (the simulation zeroes them
    too)."""

    def __init__(self, design: LQRDesign) -> None:
        self.design = design
        self.qpos0 = design.equilibrium.qpos
        self.ctrl0 = design.equilibrium.ctrl
        self.K = design.K

    def reset(self, sim: Simulation) -> None:
        """Check the model's size; allocate the work arrays."""
        nv = sim.model.nv
        if self.K.shape != (nv - 6, 2 * nv):
            raise ValueError(f"design: K of shape {(nv - 6, 2 * nv)} expected for this model, "
                             f"got {self.K.shape}")
        self._mj = import_mujoco()
        self._dx = np.zeros(2 * nv)
        self._tau = np.zeros(nv)

    def torques(self, sim: Simulation, t: float) -> Array:
        """``ctrl0 - K δx`` on the joints, zero on the root."""
        nv = sim.model.nv
        dx = self._dx
        self._mj.mj_differentiatePos(sim.model, dx[:nv], 1.0, self.qpos0, sim.data.qpos)
        dx[nv:] = sim.data.qvel
        self._tau[6:] = self.ctrl0 - self.K @ dx
        return self._tau


def lqr_stand(character: Character, design: LQRDesign, *, duration: float = 3.0,
              push: Push | None = None, torque_limit: float = 400.0,
              frame_time: float = 1.0 / 60.0, fall_fraction: float = 0.6,
              stop_when_fallen: bool = True) -> Recording:
    """Simulate the character from the design's equilibrium under :class:`LQRBalance`, as
    :func:`course.physics.balance.stand` does its controllers (same step, frame, torque limit
    and fall test): :func:`lqr_simulation` run for ``duration`` seconds."""
    sim = lqr_simulation(character, design, push=push, torque_limit=torque_limit,
                         frame_time=frame_time, fall_fraction=fall_fraction,
                         stop_when_fallen=stop_when_fallen)
    return sim.run(LQRBalance(design), lqr_frames(duration, frame_time))


def lqr_frames(duration: float, frame_time: float = 1.0 / 60.0) -> int:
    """The frames :func:`lqr_stand` records for ``duration`` seconds, the first included."""
    return max(2, round(as_positive(duration, "duration") / frame_time) + 1)


def lqr_simulation(character: Character, design: LQRDesign, *, push: Push | None = None,
                   torque_limit: float = 400.0, frame_time: float = 1.0 / 60.0,
                   fall_fraction: float = 0.6, stop_when_fallen: bool = True,
                   stop_when_diverged: bool = False) -> Simulation:
    """The :class:`~course.physics.simulation.Simulation` :func:`lqr_stand` runs, not yet
    started (a live view steps it a frame at a time under ``LQRBalance(design)``): from the
    design's equilibrium at its step, with the COM fall test (below ``fall_fraction`` of its
    start height)."""
    return Simulation(character, design.equilibrium.qpos, frame_time=frame_time, h=design.h,
                      torque_limit=torque_limit, push=push,
                      fall=Fall("com", fraction=fall_fraction, stop=stop_when_fallen),
                      stop_when_diverged=stop_when_diverged, name="lqr stand")


def survived(record: Recording) -> bool:
    """Standing at the end: not fallen and not diverged."""
    return record.fall_time is None and not record.unstable


def lqr_largest_push(character: Character, design: LQRDesign, *,
                     direction: Sequence[float] | Array = (0.0, 0.0, 1.0),
                     duration: float = 0.1, start: float = 0.25, settle: float = 1.5,
                     tol: float = 5.0, max_force: float = 1e5,
                     torque_limit: float = 400.0) -> float:
    """The largest push (N, y-up ``direction``, on the root) the LQR balance survives:
    :func:`course.physics.balance.largest_push`'s protocol and search, a diverged run counted
    as a fall."""
    root = character.skeleton.names[0]

    def survives(force: Array) -> bool:
        run = lqr_stand(character, design, duration=start + duration + settle,
                        push=Push(root, force, start, duration), torque_limit=torque_limit)
        return survived(run)

    return bisect_push(survives, direction, tol=tol, max_force=max_force)


__all__ = [
    "DISCOUNT",
    "Equilibrium",
    "LQRBalance",
    "LQRDesign",
    "Weights",
    "balance_cost",
    "balance_dofs",
    "design",
    "equilibrium",
    "lqr_frames",
    "lqr_largest_push",
    "lqr_simulation",
    "lqr_stand",
    "motor_model",
    "motor_xml",
    "one_leg_pose",
    "reweigh",
    "support_feet",
    "survived",
]
