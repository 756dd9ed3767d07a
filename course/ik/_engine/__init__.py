"""The engines :func:`course.ik.solve` runs the lecture's methods on (not for students).

* :mod:`.tree` — the general engine's model: the paths from the fixed joint to the effectors of
  any skeleton, re-rooted there, with its forward kinematics, Jacobian, limits and fitting on
  rotation matrices batched over problems; :mod:`.tree_solvers` runs every method on it.
* :mod:`.chain` — the fast path's model: one serial chain to one position target, on
  quaternion and vector *components* (Python floats for one problem, ``(B,)`` arrays for a
  batch, :mod:`.ops`); :mod:`.chain_solvers` runs CCD, FABRIK and the Jacobian methods on it.
* :mod:`course.rotations._kernels` (the unchecked vector, quaternion and matrix kernels),
  :mod:`.components` (the IK step kernels on components, and the joint-limit projection),
  :mod:`.history` (the iteration driver and its bookkeeping) and :mod:`.request` (a
  validated solve) are shared by both.

The contract between the two tiers: every solver of either engine is a
:class:`~.history.Solver`, ``(run, options) -> Solution``: ``run`` the engine's run record
(:class:`~.chain_solvers.ChainRun`, the tree's :class:`~.tree.Problem`), ``options`` the
method's typed record of :mod:`.request` (:class:`~.request.JacobianOptions`,
:class:`~.request.CCDOptions`, ...), and :class:`~.history.Solution` the one record of a run
(final state, :class:`~.history.History`, recorded states). An iterative method supplies its
step to :func:`~.history.iterate`, the one driver (history, stopping, recording) of both
engines, from the engine's start (:func:`~.chain_solvers.chain_start`,
:func:`~.tree_solvers.tree_start`: forward kinematics, the bent start).
:func:`~.chain_solvers.solve_on_chain` / :func:`~.tree_solvers.solve_on_tree` run a solver on
a :class:`~.request.Request`. Which method runs on which engine is the method's record in
:mod:`course.ik.methods`. The
engines import the lecture modules' maths (the Jacobian steps, the two-link triangle); those
import nothing from here; the kernels they share live in :mod:`course.rotations._kernels`.
"""
