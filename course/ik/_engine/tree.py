r"""The part of a skeleton an IK solve moves: the joints on the paths from the fixed joint to the
end effectors, re-rooted at the fixed joint, with the lecture's forward kinematics on it.

Re-rooting at joint ``k`` (the lecture's "root at the foot") walks each path edge either *down*
the original tree (``p -> c``) or *up* it (``c -> p``):

.. math::
    \text{down:}\quad Q_c = Q_p R_c,\qquad p_c = p_p + Q_p l_c \\
    \text{up:}\quad Q_p = Q_c R_c^{-1},\qquad p_p = p_c - Q_p l_c

Every path node ``u`` other than the fixed joint is *driven* by one local rotation (its *edge
rotation*): ``R_u`` going down, ``R_c`` (the rotation of the child it came from) going up. So
the variables of the solve are exactly those local rotations; going down the rotation turns
the subtree about ``p_u`` itself, going up about the node it came from, ``p_c``.

What stays fixed at ``k``: if every effector lies below ``k`` the *parent frame* of ``k`` is
fixed and ``R_k`` is a variable (for ``k = 0`` the world frame: the usual chain IK where the
base joint turns); otherwise ``k``'s own global orientation ``Q_k`` is held (the planted foot)
and ``R_k`` drives the way up.

Ball joints get three columns per joint: the increment is a rotation vector
:math:`\delta = (\delta_x, \delta_y, \delta_z)` about the *world* axes applied to the driven
node's global orientation, :math:`Q_u \leftarrow \exp([\delta]_\times) Q_u`, so the column for
world axis :math:`a` is :math:`a \times (e - r_i)` (no Euler gimbal lock). Hinge joints get one
column :math:`a_i \times (e - r_i)` with :math:`a_i` the hinge axis in world space (the axis is
fixed in the parent's frame, :math:`a_i = Q_{parent} \hat a`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from course._typing import Array
from course.fk import tree_path
from course.rotations import matrix_from_quat, quat_from_matrix
from course.rotations._kernels import (
    TINY,
    best_rotation,
    cross,
    dot,
    matrix_from_rotvec,
    matvec,
    norm,
    orthonormalize,
    rotvec_from_matrix,
)

from .components import Limit, limit
from .ops import ARRAYS, Ops
from .reach import reach_points

# A joint as :func:`build_model` takes it: a hinge's axis (3,), None for a ball (or universal)
# joint, False for a fixed joint.
JointAxis = Sequence[float] | Array | bool | None


@dataclass
class TreeModel:
    """Path joints re-rooted at the fixed joint; see the module docstring.

    Node arrays have one entry per path joint in traversal order (node 0 is the fixed joint);
    column arrays one entry per Jacobian column.
    """

    joints: NDArray[np.int_]  # (N,) skeleton joint of each node
    parent: NDArray[np.int_]  # (N,) re-rooted parent node, -1 for node 0
    up: NDArray[np.bool_]  # (N,) edge walked up the original tree
    edge_joint: NDArray[np.int_]  # (N,) joint whose local rotation drives the node (-1: none)
    bone: Array  # (N, 3) the offset l of the node's edge (zero for node 0)
    anchor_parent: bool  # parent frame of the fixed joint held (else Q_k held)
    effectors: NDArray[np.int_]  # (E,) effector nodes
    rot_effectors: NDArray[np.int_]  # (E_r,) nodes with an orientation target
    var_nodes: NDArray[np.int_]  # (V,) driven node of each variable
    var_sign: Array  # (V,) +1 down, -1 up
    var_frame: NDArray[np.int_]  # (V,) node whose orientation holds the joint axis (N: base)
    var_pivot: NDArray[np.int_]  # (V,) node the variable turns about
    hinge: NDArray[np.bool_]  # (V,) one column (hinge) or three (ball)
    col_var: NDArray[np.int_]  # (C,)
    col_axis: Array  # (C, 3) axis in the frame of col_frame
    col_frame: NDArray[np.int_]  # (C,) node index, N = base frame, N + 1 = world
    pos_mask: Array  # (E, C) 1 where effector position depends on the column
    rot_mask: Array  # (E_r, C)
    levels: list[NDArray[np.int_]] = field(repr=False)
    ancestors: Array = field(repr=False)  # (N, N) 1 where w is on the path to u (w != 0)
    descendant: NDArray[np.bool_] = field(repr=False)  # (N, N) [d, u]: u at or below d
    # For fitting rotations to wanted positions: the nodes whose offsets from the pivot a
    # node's orientation M_u fixes, as M_u @ fit_local (padded with node 0, weight 0).
    fit_nodes: NDArray[np.int_] = field(repr=False)  # (N, K)
    fit_local: Array = field(repr=False)  # (N, K, 3)
    fit_weight: Array = field(repr=False)  # (N, K)
    pivot: NDArray[np.int_] = field(repr=False)  # (N,) node each node's edge turns about
    # For fitting a hinge: every node its edge moves (padded with node 0, weight 0).
    moved_nodes: NDArray[np.int_] = field(repr=False)  # (N, K2)
    moved_weight: Array = field(repr=False)  # (N, K2)

    def __post_init__(self) -> None:
        self.any_up = bool(self.up.any())
        # Levels are contiguous runs of nodes (sorted by depth); index them by slices and a
        # single parent where possible, which is much cheaper than fancy indexing.
        self.level_slices = []
        for lvl in self.levels[1:]:
            nodes = slice(int(lvl[0]), int(lvl[-1]) + 1)
            par = self.parent[lvl]
            single = np.all(par == par[0])
            self.level_slices.append((nodes, slice(par[0], par[0] + 1) if single else par))
        # The path's bones can at most line up (sum of lengths); at least, the longest bone
        # less all the others (0 if they can cover it).
        lengths = norm(self.bone)
        on_path = self.descendant[:, self.effectors].T  # (E, N) nodes on each effector's path
        self.reach_far = on_path @ lengths
        longest = (on_path * lengths).max(axis=1, initial=0.0)
        self.reach_near = np.maximum(0.0, 2 * longest - self.reach_far)
        # Rounding slack of the reach test, relative to the longest path (of any size).
        self.reach_slack = 1e-9 * float(self.reach_far.max(initial=0.0))
        # The solve's length scale: its longest path to any effector (orientation targets
        # included), floored so a chain of zero bones still has one.
        to_any = self.descendant[:, np.concatenate([self.effectors, self.rot_effectors])].T
        self.length_scale = max(float((to_any @ lengths).max(initial=0.0)), 1e-9)
        self.unit_weights = np.ones(self.n_cols)  # every column weighted 1 (shared, read-only)
        self.unit_weights.flags.writeable = False
        self.no_limits = (None,) * len(self.var_nodes)  # every variable free
        hinge_cols = self.hinge[self.col_var]
        self.hinge_vars = np.flatnonzero(self.hinge)
        self.ball_vars = np.flatnonzero(~self.hinge)
        self.hinge_cols = np.flatnonzero(hinge_cols)
        self.ball_cols = np.flatnonzero(~hinge_cols)  # three consecutive per ball variable
        K = np.zeros((len(self.hinge_vars), 3, 3))
        a = self.col_axis[self.hinge_cols]
        K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -a[:, 2], a[:, 1], -a[:, 0]
        self.hinge_K = K - np.swapaxes(K, -1, -2)  # [a]_x, for Rodrigues with a fixed axis
        self.hinge_K2 = self.hinge_K @ self.hinge_K

    @property
    def n_nodes(self) -> int:
        return len(self.joints)

    @property
    def n_cols(self) -> int:
        return len(self.col_var)

    # -- forward kinematics on the path -------------------------------------------------------

    def forward(self, Rn: Array, base: Array, p0: Array) -> tuple[Array, Array]:
        r"""Global orientations and positions of the path nodes.

        Parameters
        ----------
        Rn : ndarray, shape (B, N, 3, 3)
            Edge rotation of every node (identity where ``edge_joint`` is -1).
        base : ndarray, shape (B, 3, 3)
            Held frame: the parent frame of the fixed joint, or ``Q_k`` itself.
        p0 : ndarray, shape (B, 3)
            Position of the fixed joint.

        Returns
        -------
        M : ndarray, shape (B, N, 3, 3)
        p : ndarray, shape (B, N, 3)
        """
        if self.any_up:
            F = Rn.copy()
            F[:, self.up] = np.swapaxes(Rn[:, self.up], -1, -2)
            # Offsets in the re-rooted parent's frame: l (down) or -R_c^{-1} l_c (up).
            G = np.broadcast_to(self.bone, Rn.shape[:2] + (3,)).copy()
            G[:, self.up] = -matvec(F[:, self.up], G[:, self.up])
        else:
            F, G = Rn, self.bone
        # Node-major storage makes each level's product one contiguous batched matmul.
        Ft = np.ascontiguousarray(np.moveaxis(F, 1, 0))
        Mt = np.empty_like(Ft)
        np.matmul(base, Ft[0], out=Mt[0])
        for nodes, par in self.level_slices:
            Mt[nodes] = Mt[par] @ Ft[nodes]
        M = np.moveaxis(Mt, 0, 1)
        D = matvec(M[:, self.parent[1:]], G[..., 1:, :])
        p = p0[:, None, :] + self.ancestors[:, 1:] @ D
        return M, p

    # -- Jacobian --------------------------------------------------------------------------------

    def world_axes(self, M: Array, base: Array) -> Array:
        r"""World axis of every column, shape (B, C, 3): :math:`Q_{parent}\,\hat a` for a hinge,
        the coordinate axes for a ball."""
        B = M.shape[0]
        w = np.empty((B, self.n_cols, 3))
        if len(self.hinge_cols):
            frames = np.concatenate([M, base[:, None]], 1)[:, self.col_frame[self.hinge_cols]]
            w[:, self.hinge_cols] = matvec(frames, self.col_axis[self.hinge_cols])
        w[:, self.ball_cols] = self.col_axis[self.ball_cols]
        return w

    def jacobian(self, M: Array, p: Array, base: Array) -> Array:
        r"""Analytic Jacobian, rows: 3 per effector position then 3 per orientation target.

        Column for world axis :math:`a` of the variable turning about :math:`r_i`:
        :math:`\partial e / \partial\theta = a \times (e - r_i)` for a position,
        :math:`a` for an orientation (angular velocity).

        Returns
        -------
        ndarray, shape (B, 3 E + 3 E_r, C)
        """
        w = self.world_axes(M, base)
        r = p[:, self.effectors][:, :, None, :] - p[:, self.var_pivot[self.col_var]][:, None]
        Jp = cross(w[:, None], r) * self.pos_mask[None, :, :, None]  # (B, E, C, 3)
        B = M.shape[0]
        Jp = np.swapaxes(Jp, -1, -2).reshape(B, -1, self.n_cols)
        if len(self.rot_effectors):
            Jr = w[:, None] * self.rot_mask[None, :, :, None]
            Jp = np.concatenate([Jp, np.swapaxes(Jr, -1, -2).reshape(B, -1, self.n_cols)], 1)
        return Jp

    def var_axes(self) -> Array:
        """Hinge axis (in the parent frame) of every variable, (V, 3) (zeros for balls)."""
        axes = np.zeros((len(self.var_nodes), 3))
        first = np.searchsorted(self.col_var, np.arange(len(self.var_nodes)))
        axes[self.hinge] = self.col_axis[first[self.hinge]]
        return axes

    def step(self, Rn: Array, M: Array, base: Array, delta: Array) -> Array:
        r"""Apply the increments ``delta`` (B, C) to the edge rotations.

        A world-space turn of the driven node by the rotation vector :math:`\delta` is the
        local update :math:`R \leftarrow \exp(s\,[F^{-1}\delta]_\times)\,R`, with :math:`F`
        the frame the joint's axes live in (its original parent) and :math:`s = -1` going up.
        A hinge turned by :math:`\delta` about its world axis :math:`F\hat a` is
        :math:`R \leftarrow \exp(s\delta[\hat a]_\times) R` (Rodrigues with the fixed
        :math:`[\hat a]_\times`).
        """
        out: Array = Rn.copy()
        if len(self.hinge_vars):
            nodes = self.var_nodes[self.hinge_vars]
            th = (delta[:, self.hinge_cols] * self.var_sign[self.hinge_vars])[..., None, None]
            turn = np.eye(3) + np.sin(th) * self.hinge_K + (1.0 - np.cos(th)) * self.hinge_K2
            out[:, nodes] = turn @ Rn[:, nodes]
        if len(self.ball_vars):
            nodes = self.var_nodes[self.ball_vars]
            frames = np.concatenate([M, base[:, None]], 1)[:, self.var_frame[self.ball_vars]]
            world = delta[:, self.ball_cols].reshape(len(delta), -1, 3)
            local = matvec(np.swapaxes(frames, -1, -2), world) * self.var_sign[self.ball_vars,
                                                                                None]
            out[:, nodes] = matrix_from_rotvec(local) @ Rn[:, nodes]
        return out


def build_model(
    parents: NDArray[np.int_],
    offsets: Array,
    hinge_axes: Sequence[JointAxis],
    root: int,
    effectors: Sequence[int],
    rot_effectors: Sequence[int] = (),
) -> TreeModel:
    """Build the :class:`TreeModel` of the paths from ``root`` to ``effectors``.

    Parameters
    ----------
    parents : int ndarray, shape (J,)
    offsets : ndarray, shape (J, 3)
    hinge_axes : list of (3,) unit vectors, None or False, length J
        Hinge axis of each joint in its parent's frame; None for a ball joint (and a
        universal joint, solved as a ball); False for a fixed joint (never a variable).
    root : int
        The fixed joint.
    effectors, rot_effectors : list of int
        Joints with a position target, and (a subset or others) with an orientation target.
    """
    parents = np.asarray(parents)
    joints, node, parent, up, edge_joint, bone, depth = _reroot(parents, offsets, root,
                                                                [*effectors, *rot_effectors])
    descendant, ancestors = _descendants(parent)
    eff = np.array([node[e] for e in effectors], dtype=int)
    reff = np.array([node[e] for e in rot_effectors], dtype=int)
    levels = [np.flatnonzero(np.array([depth[int(j)] for j in joints]) == k)
              for k in range(max(depth.values()) + 1)]
    return TreeModel(
        joints=joints, parent=parent, up=up, edge_joint=edge_joint, bone=bone,
        anchor_parent=not up.any(), effectors=eff, rot_effectors=reff,
        **_variables(hinge_axes, parent, up, edge_joint, descendant, eff, reff),
        levels=levels, ancestors=ancestors, descendant=descendant,
        **_fit_tables(parent, up, bone, descendant),
    )


def _reroot(parents: NDArray[np.int_], offsets: Array, root: int, targets: list[int]
            ) -> tuple[NDArray[np.int_], dict[int, int], NDArray[np.int_], NDArray[np.bool_],
                       NDArray[np.int_], Array, dict[int, int]]:
    """The path nodes re-rooted at ``root``, by depth: their joints, the node of each joint,
    re-rooted parents, which edges go up the tree, the joint driving each node, its bone and
    each joint's depth."""
    order: dict[int, int] = {root: -1}  # joint -> re-rooted parent joint
    for e in targets:
        path = tree_path(parents, root, e)
        for a, b in zip(path[:-1], path[1:], strict=True):
            order.setdefault(b, a)
    depth = {root: 0}
    for j in sorted(order, key=lambda j: len(tree_path(parents, root, j))):
        if j != root:
            depth[j] = depth[order[j]] + 1
    joints = np.array(sorted(order, key=lambda j: (depth[j], j)), dtype=int)
    node = {int(j): i for i, j in enumerate(joints)}
    N = len(joints)
    parent = np.array([node[order[j]] if order[j] >= 0 else -1 for j in joints], dtype=int)
    up = np.array([order[j] >= 0 and parents[order[j]] == j for j in joints], dtype=bool)
    anchor_parent = not up.any()
    edge_joint = np.empty(N, dtype=int)
    bone = np.zeros((N, 3))
    for i, j in enumerate(joints):
        if i == 0:
            edge_joint[i] = root if anchor_parent else -1
        elif up[i]:
            edge_joint[i] = order[j]
            bone[i] = offsets[order[j]]
        else:
            edge_joint[i] = j
            bone[i] = offsets[j]
    return joints, node, parent, up, edge_joint, bone, depth


def _descendants(parent: NDArray[np.int_]) -> tuple[NDArray[np.bool_], Array]:
    """``descendant[w, u]``: u at or below w; ``ancestors[u, w]``: 1 where w (not node 0) is
    on the path to u."""
    N = len(parent)
    descendant = np.zeros((N, N), dtype=bool)
    ancestors = np.zeros((N, N))
    for u in range(N):
        w = u
        while w >= 0:
            descendant[w, u] = True
            if w > 0:
                ancestors[u, w] = 1.0
            w = parent[w]
    return descendant, ancestors


def _variables(hinge_axes: Sequence[JointAxis], parent: NDArray[np.int_], up: NDArray[np.bool_],
               edge_joint: NDArray[np.int_], descendant: NDArray[np.bool_],
               eff: NDArray[np.int_], reff: NDArray[np.int_]) -> dict[str, Any]:
    """The variables (the edge rotations that move an effector) and their Jacobian columns,
    as :class:`TreeModel` fields."""
    N = len(parent)
    # A variable matters if it moves an effector: going down it turns the nodes strictly
    # below it about itself; going up it moves the node itself (about the node it came from).
    var_nodes: list[int] = []
    var_sign: list[float] = []
    var_frame: list[int] = []
    var_pivot: list[int] = []
    hinge: list[bool] = []
    col_var: list[int] = []
    col_axis: list[Array] = []
    col_frame: list[int] = []
    for u in range(N):
        if edge_joint[u] < 0 or hinge_axes[edge_joint[u]] is False:
            continue
        below = descendant[u].copy()
        if not up[u]:
            below[u] = False
        if not (below[eff].any() or descendant[u, reff].any()):
            continue
        v = len(var_nodes)
        var_nodes.append(u)
        var_sign.append(-1.0 if up[u] else 1.0)
        frame = u if up[u] else (parent[u] if u > 0 else N)
        var_frame.append(frame)
        var_pivot.append(parent[u] if up[u] else u)
        axis = hinge_axes[edge_joint[u]]
        hinge.append(axis is not None)
        if axis is not None:
            col_var.append(v)
            col_axis.append(np.asarray(axis, dtype=float))
            col_frame.append(frame)
        else:
            for a in np.eye(3):
                col_var.append(v)
                col_axis.append(a)
                col_frame.append(N + 1)
    var_nodes_a = np.array(var_nodes, dtype=int)
    col_var_a = np.array(col_var, dtype=int)
    driven = var_nodes_a[col_var_a] if len(col_var_a) else np.zeros(0, dtype=int)
    pos_mask = np.zeros((len(eff), len(col_var)))
    for i, e in enumerate(eff):
        for c, d in enumerate(driven):
            pos_mask[i, c] = descendant[d, e] and (up[d] or d != e)
    rot_mask = np.array([[float(descendant[d, e]) for d in driven] for e in reff]).reshape(
        len(reff), len(driven))

    return dict(var_nodes=var_nodes_a, var_sign=np.array(var_sign),
                var_frame=np.array(var_frame, int), var_pivot=np.array(var_pivot, dtype=int),
                hinge=np.array(hinge, dtype=bool), col_var=col_var_a,
                col_axis=np.array(col_axis).reshape(-1, 3),
                col_frame=np.array(col_frame, dtype=int), pos_mask=pos_mask, rot_mask=rot_mask)


def _fit_tables(parent: NDArray[np.int_], up: NDArray[np.bool_], bone: Array,
                descendant: NDArray[np.bool_]) -> dict[str, Any]:
    """What :meth:`Problem.fit` needs per node, as :class:`TreeModel` fields."""
    N = len(parent)
    # Down node u: its down children c sit at M_u l_c from u. Up node u: u itself at
    # -M_u l_u from the node it came from, and its down children c at M_u (l_c - l_u).
    fits = []
    for u in range(N):
        kids = [c for c in range(1, N) if parent[c] == u and not up[c]]
        if up[u]:
            fits.append([(u, -bone[u])] + [(c, bone[c] - bone[u]) for c in kids])
        else:
            fits.append([(c, bone[c]) for c in kids])
    K = max(1, max(len(f) for f in fits))
    fit_nodes = np.zeros((N, K), dtype=int)
    fit_local = np.zeros((N, K, 3))
    fit_weight = np.zeros((N, K))
    for u, f in enumerate(fits):
        for i, (c, vec) in enumerate(f):
            fit_nodes[u, i], fit_local[u, i], fit_weight[u, i] = c, vec, 1.0
    pivot = np.array([parent[u] if up[u] else u for u in range(N)], dtype=int)
    # Going down an edge turns the nodes strictly below it, going up the node itself too.
    moved = [[w for w in range(N) if descendant[u, w] and (w != u or up[u])] for u in range(N)]
    K2 = max(1, max(len(x) for x in moved))
    moved_nodes = np.zeros((N, K2), dtype=int)
    moved_weight = np.zeros((N, K2))
    for u, x in enumerate(moved):
        moved_nodes[u, :len(x)], moved_weight[u, :len(x)] = x, 1.0

    return dict(fit_nodes=fit_nodes, fit_local=fit_local, fit_weight=fit_weight, pivot=pivot,
                moved_nodes=moved_nodes, moved_weight=moved_weight)

# The turn (radians) of every joint that first bends a straight path aimed along its own line.
BEND = 0.05


def bend_increment(hinge: NDArray[np.bool_], u: Array) -> Array:
    r"""Per-column increments, shape (B, C), that bend a straight path of direction ``u``
    (B, 3, unit): every ball joint turns by :data:`BEND` about the world axis
    :math:`\hat u \times e_k` perpendicular to the line (:math:`e_k` the coordinate axis of
    ``u``'s smallest component), every hinge by :data:`BEND` about its own axis.

    Why: along a straight path every Jacobian column :math:`a\times(e - r_i)` is perpendicular
    to the line, so a target on the line gets no step (:math:`J^T\Delta e = 0`); FABRIK's
    points and CCD's turns stay on the line too. Practical IK leaves such a singular pose by a
    small perturbation; this one is deterministic, so a solve is repeatable.
    """
    perp = cross(u, np.eye(3)[np.argmin(np.abs(u), axis=-1)])
    perp = perp / np.maximum(norm(perp), TINY)[..., None]
    cols = [np.full((len(u), 1), BEND) if h else BEND * perp for h in hinge]
    return np.concatenate(cols, axis=1) if cols else np.zeros((len(u), 0))


def bend_direction(p: Array, effectors: NDArray[np.int_], on_path: NDArray[np.bool_],
                   targets: Array, far: Array, slack: float,
                   tol: float) -> tuple[Array, NDArray[np.bool_]] | None:
    """Which problems (B,) to bend, and along which line (B, 3, unit): those where some
    effector's path is straight and its target lies on that line (within ``tol``), not yet
    reached and not beyond the stretched path's tip (where the straight pose is already the
    best one); None when no problem needs it. Both engines ask this once per solve.

    Parameters
    ----------
    p : ndarray, shape (B, N, 3)
        Node positions, ``p[:, 0]`` the fixed joint.
    effectors : int ndarray, shape (E,)
        The effector nodes.
    on_path : bool ndarray, shape (E, N)
        The nodes on each effector's path (the effector included).
    targets : ndarray, shape (B, E, 3)
    far : ndarray, shape (E,)
        The length of each effector's path; ``slack`` the rounding allowed on a length.
    """
    root = p[:, :1]
    tips = p[:, effectors]  # (B, E, 3)
    axis = tips - root
    length = norm(axis)
    u = axis / np.maximum(length, TINY)[..., None]
    off = norm(cross(p[:, None] - root[:, None], u[:, :, None]))  # (B, E, N)
    straight = np.where(on_path, off, 0.0).max(axis=-1, initial=0.0) <= slack
    rel = targets - root
    stretched = (length >= far - slack) & (dot(rel, u) >= length)
    need = (straight & (length > TINY) & (norm(cross(rel, u)) <= tol)
            & (norm(targets - tips) >= tol) & ~stretched)  # (B, E)
    if not need.any():
        return None
    first = np.argmax(need, axis=1)
    return u[np.arange(len(u)), first], need.any(axis=1)


def outside_shell(d: Any, far: Any, near: Any, slack: float) -> Any:
    """Whether distances ``d`` from the fixed joint lie outside the shell ``[near, far]`` an
    effector can reach, give or take ``slack`` (floats or arrays)."""
    return (d > far + slack) | (d < near - slack)


def unreachable_targets(model: TreeModel, target_pos: Array, p0: Array) -> NDArray[np.bool_]:
    """(B,) some position target (B, E, 3) lies outside the shell its effector can reach from
    the fixed joint at ``p0`` (B, 3)."""
    d = norm(target_pos - p0[:, None])
    out: NDArray[np.bool_] = outside_shell(d, model.reach_far, model.reach_near,
                                           model.reach_slack).any(axis=1)
    return out


@dataclass
class Problem:
    """One model with a batch of ``B`` starting poses and targets, ready to iterate: the tree
    engine's run record (:class:`~course.ik._engine.history.Run`).

    Attributes
    ----------
    Rn : ndarray, shape (B, N, 3, 3)
        Edge rotations of the nodes (the variables live at ``model.var_nodes``).
    base, p0 : ndarray, shapes (B, 3, 3), (B, 3)
        Held frame and position of the fixed joint.
    target_pos : ndarray, shape (B, E, 3)
    target_rot : ndarray, shape (B, E_r, 3, 3)
    col_weight : ndarray, shape (C,)
        The regulariser's per-column weight ``W`` (1: normal, larger: the joint moves less).
    limits : tuple of Limit or None, length V
        Each variable's limit (:class:`~course.ik._engine.components.Limit`; None: free).
    pos_weight, rot_weight : ndarray, shapes (E,), (E_r,)
        The targets' relative weights (largest 1).
    tol, max_iter, record
        As :func:`course.ik.solve` takes them.
    done : bool or ndarray of bool, shape (B,)
        Problems whose start is already their best pose (:meth:`reach_start`): the solvers'
        :class:`~course.ik._engine.history.History` stops them at once.
    """

    model: TreeModel
    Rn: Array
    base: Array
    p0: Array
    target_pos: Array
    target_rot: Array
    col_weight: Array
    limits: tuple[Limit | None, ...]
    pos_weight: Array
    rot_weight: Array
    tol: float
    max_iter: int
    record: bool
    done: Any = False

    def __post_init__(self) -> None:
        w = np.concatenate([self.pos_weight, self.rot_weight])
        # Each target's three error rows scaled by the square root of its weight (None: all 1).
        self.row_weight = None if np.all(w == 1.0) else np.repeat(np.sqrt(w), 3)

    @property
    def batch(self) -> int:
        return len(self.Rn)

    @property
    def ops(self) -> Ops:
        """A batch in arrays (:data:`~course.ik._engine.ops.ARRAYS`), always."""
        return ARRAYS

    def forward(self, Rn: Array) -> tuple[Array, Array]:
        return self.model.forward(Rn, self.base, self.p0)

    def error(self, M: Array, p: Array) -> tuple[Array, Array]:
        r"""Error vector :math:`\Delta e` (B, 3E + 3E_r) and the largest effector error (B,).

        Orientation errors are the world rotation vector of :math:`Q_t Q^{-1}` (radians); each
        target's rows of :math:`\Delta e` are scaled by the square root of its weight (the
        largest error is not).
        """
        m = self.model
        e = self.target_pos - p[:, m.effectors]
        size = norm(e)
        if len(m.rot_effectors):
            r = rotvec_from_matrix(self.target_rot @ np.swapaxes(M[:, m.rot_effectors], -1, -2))
            e = np.concatenate([e, r], 1)
            size = np.concatenate([size, norm(r)], 1)
        e = e.reshape(self.batch, -1)
        return e if self.row_weight is None else e * self.row_weight, size.max(axis=1)

    def unreachable(self) -> NDArray[np.bool_]:
        """(B,) some position target lies outside the shell its effector can reach."""
        return unreachable_targets(self.model, self.target_pos, self.p0)

    def bend_if_straight(self, Rn: Array, tol: float) -> Array:
        """Edge rotations bent by :func:`bend_increment` (then projected into the limits) in
        the problems :func:`bend_direction` finds straight at a target on their line; the
        others unchanged."""
        m = self.model
        M, p = self.forward(Rn)
        bend = bend_direction(p, m.effectors, m.descendant[:, m.effectors].T, self.target_pos,
                              m.reach_far, m.reach_slack, tol)
        if bend is None:
            return Rn
        u, need = bend
        delta = np.where(need[:, None], bend_increment(m.hinge, u), 0.0)
        return self.project(m.step(Rn, M, self.base, delta))

    def reach_start(self, Rn: Array, tol: float,
                    axis: Array | None) -> tuple[Array, NDArray[np.bool_]]:
        """Edge rotations of a serial chain put on the reach-aware start
        (:func:`~course.ik._engine.reach.reach_points`: bent evenly in a plane to the target's
        distance, aimed at it, projected into the limits) in the problems whose target lies at
        or near its full reach, and which those are (B,); the others unchanged. Without limits
        a stretched start is the answer: :attr:`done` marks it. ``axis`` is the common hinge
        axis (in the joints' frames) of a chain of hinges, None for balls; the caller checks
        the chain (:attr:`~course.ik._engine.chain.SerialChain.bendable`)."""
        _, p = self.forward(Rn)
        normal = None if axis is None else matvec(self.base, axis)
        start = reach_points(p, self.target_pos[:, 0], normal, tol)
        if start is None:
            return Rn, np.zeros(self.batch, dtype=bool)
        wanted, need, straight = start
        if not self.limited:
            self.done = straight
        return np.where(need[:, None, None, None], self.fit(Rn, wanted, subtree=False), Rn), need

    def project(self, Rn: Array) -> Array:
        """Edge rotations with every variable projected into its limits."""
        m = self.model
        if not self.limited:
            return Rn
        Rn = Rn.copy()
        Rn[:, m.var_nodes] = self._limit(Rn[:, m.var_nodes], np.arange(len(m.var_nodes)))
        return Rn

    def fit(self, Rn: Array, wanted: Array, subtree: bool = True) -> Array:
        r"""Edge rotations that put the path nodes as close as possible to ``wanted`` positions.

        Walks the levels from the fixed joint out. At each node the orientation carried over
        from its parent, :math:`M_u = M_{parent} F_u`, is turned about the node's pivot by the
        rotation that best maps the current offsets of the nodes it places onto the wanted
        ones: the shortest arc for one offset (so the bone keeps its previous twist), Kabsch
        for several (a branching joint). A hinge cannot aim a bone at a point off its plane:
        it takes the turn about its axis that brings every node it moves (the whole subtree,
        not only its child) closest to the wanted positions, least squares; with
        ``subtree=False`` the nodes it places alone (the two-link solution's points are exact,
        and a turn that also weighs the end would leave the middle joint off its point).
        Hinge ranges and ball limits are enforced on the way, so later levels see the
        constrained pose.

        Parameters
        ----------
        Rn : ndarray, shape (B, N, 3, 3)
        wanted : ndarray, shape (B, N, 3)
        subtree : bool
            A hinge fits every node it moves (FABRIK), or only the ones it places.

        Returns
        -------
        ndarray, shape (B, N, 3, 3)
            New edge rotations; a node that places nothing keeps its own.
        """
        m = self.model
        B = Rn.shape[0]
        var_of = np.full(m.n_nodes, -1)
        var_of[m.var_nodes] = np.arange(len(m.var_nodes))
        up = m.up
        F = Rn.copy()
        F[:, up] = np.swapaxes(Rn[:, up], -1, -2)
        if subtree and m.hinge.any():  # the start: where each hinge's subtree hangs in its frame
            M_old, p_old = self.forward(Rn)
        M = np.empty_like(Rn)
        p = np.empty((B, m.n_nodes, 3))
        p[:, 0] = self.p0
        for k, lvl in enumerate(m.levels):
            if k == 0:
                Mpar = self.base[:, None]
            else:
                Mpar = M[:, m.parent[lvl]]
                G = np.broadcast_to(m.bone[lvl], (B, len(lvl), 3))
                p[:, lvl] = p[:, m.parent[lvl]] + matvec(Mpar, G)  # down nodes: final already
            Mc = Mpar @ F[:, lvl]
            sel = var_of[lvl] >= 0
            if sel.any():
                nodes, v = lvl[sel], var_of[lvl[sel]]
                Mv = Mc[:, sel]
                cur = matvec(Mv[:, :, None], m.fit_local[nodes])  # (B, n, K, 3)
                want = wanted[:, m.fit_nodes[nodes]] - p[:, m.pivot[nodes]][:, :, None]
                wt = m.fit_weight[nodes]
                R = best_rotation(cur, want, wt)
                hinge = m.hinge[v]
                if hinge.any():
                    frame = np.where(up[nodes][:, None, None], Mv, Mpar[:, sel])
                    axis = matvec(frame, m.var_axes()[v])  # (B, n, 3)
                    a = axis[:, :, None]
                    if subtree:
                        # The moved nodes' offsets from the pivot, in the node's frame (constant
                        # while it turns), carried by its new orientation; where they are wanted.
                        moved, piv = m.moved_nodes[nodes], m.pivot[nodes]
                        to_new = Mv @ np.swapaxes(M_old[:, nodes], -1, -2)
                        h_cur = matvec(to_new[:, :, None],
                                       p_old[:, moved] - p_old[:, piv][:, :, None])
                        h_want = wanted[:, moved] - p[:, piv][:, :, None]
                        h_wt = m.moved_weight[nodes]
                    else:
                        h_cur, h_want, h_wt = cur, want, wt
                    flat = h_cur - dot(h_cur, a)[..., None] * a
                    num = (dot(a, cross(flat, h_want)) * h_wt).sum(-1)
                    den = (dot(flat, h_want) * h_wt).sum(-1)
                    Rh = matrix_from_rotvec(axis * np.arctan2(num, den)[..., None])
                    R = np.where(hinge[:, None, None], Rh, R)
                Fv = orthonormalize(np.swapaxes(Mpar[:, sel], -1, -2) @ (R @ Mv))
                Rloc = np.where(up[nodes][:, None, None], np.swapaxes(Fv, -1, -2), Fv)
                Rloc = self._limit(Rloc, v)
                Fv = np.where(up[nodes][:, None, None], np.swapaxes(Rloc, -1, -2), Rloc)
                F[:, nodes] = Fv
                Mc[:, sel] = Mpar[:, sel] @ Fv
            M[:, lvl] = Mc
            if k and up[lvl].any():  # an up node hangs below its own frame: p_u = p_c - M_u l_c
                ups = lvl[up[lvl]]
                p[:, ups] = p[:, m.parent[ups]] - matvec(M[:, ups], m.bone[ups])
        out: Array = F.copy()
        out[:, up] = np.swapaxes(F[:, up], -1, -2)
        return out

    def fit_free(self, Rn: Array, wanted: Array) -> Array:
        r""":meth:`fit` for unconstrained ball joints, all joints at once.

        Each driven node's global orientation is turned by the rotation taking its current
        offsets onto the wanted ones, :math:`M_u' = \mathrm{arc}(M_u l, w_u - w_{pivot}) M_u`
        (Kabsch for several), and the local rotations follow as
        :math:`F_u = M_{parent}'^{-1} M_u'`. Exact when the wanted positions keep the bone
        lengths and every node places one bone (a FABRIK chain).
        """
        m = self.model
        M, _ = self.forward(Rn)
        d = m.var_nodes
        cur = matvec(M[:, d][:, :, None], m.fit_local[d])
        want = wanted[:, m.fit_nodes[d]] - wanted[:, m.pivot[d]][:, :, None]
        M = M.copy()
        M[:, d] = best_rotation(cur, want, m.fit_weight[d]) @ M[:, d]
        frames = np.concatenate([self.base[:, None], M], 1)[:, m.parent[d] + 1]
        F = orthonormalize(np.swapaxes(frames, -1, -2) @ M[:, d])
        out: Array = Rn.copy()
        out[:, d] = np.where(m.up[d][:, None, None], np.swapaxes(F, -1, -2), F)
        return out

    @property
    def limited(self) -> bool:
        """Some variable has a limit."""
        return any(lim is not None for lim in self.limits)

    def _limit(self, R: Array, v: NDArray[np.int_]) -> Array:
        """Local rotations ``R`` (B, n, 3, 3) of variables ``v`` projected into their limits,
        by the fast path's projection (:func:`~course.ik._engine.components.limit`, on the
        quaternions' components): a hinge's angle clipped, a ball's rotation angle capped, a
        swing–twist cone clamped."""
        todo = [(i, lim) for i, u in enumerate(v) if (lim := self.limits[int(u)]) is not None]
        if not todo:
            return R
        R = R.copy()
        for i, lim in todo:
            w, x, y, z = np.moveaxis(quat_from_matrix(R[:, i]), -1, 0)  # components (B,)
            R[:, i] = matrix_from_quat(np.stack(limit((w, x, y, z), lim, ARRAYS), -1))
        return R
