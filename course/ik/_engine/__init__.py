"""The engines :func:`course.ik.solve` runs the lecture's methods on (not for students).

* :mod:`.tree` — the general engine's model: the paths from the fixed joint to the effectors of
  any skeleton, re-rooted there, with its forward kinematics, Jacobian, limits and fitting on
  rotation matrices batched over problems; :mod:`.tree_solvers` runs every method on it.
* :mod:`.chain` — the fast path's model: one serial chain to one position target, on
  quaternion and vector *components* (Python floats for one problem, ``(B,)`` arrays for a
  batch, :mod:`.ops`); :mod:`.chain_solvers` runs CCD, FABRIK and the Jacobian methods on it.
* :mod:`course.rotations._kernels` (the unchecked vector, quaternion and matrix kernels),
  :mod:`.components` (the IK step kernels on components, and the joint-limit projection),
  :mod:`.history` (convergence bookkeeping) and :mod:`.request` (a validated solve) are
  shared by both.

The contract between the two tiers: a chain solver is a
:class:`~.chain_solvers.ChainSolver`, ``(ChainRun, options) -> ChainSolved``; a tree solver a
:class:`~.tree_solvers.TreeSolver`, ``(Problem, tol, max_iter, record, options) ->
TreeSolved``; ``options`` is the method's typed record of :mod:`.request`
(:class:`~.request.JacobianOptions`, :class:`~.request.CCDOptions`, ...), and
:func:`~.chain_solvers.solve_on_chain` / :func:`~.tree_solvers.solve_on_tree` run one on a
:class:`~.request.Request`. Which method runs on which engine is the method's record in
:mod:`course.ik.methods`. The
engines import the lecture modules' maths (the Jacobian steps, the two-link triangle); those
import nothing from here; the kernels they share live in :mod:`course.rotations._kernels`.
"""
