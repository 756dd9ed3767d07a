r"""The linear inverted pendulum 线性倒立摆 (LIP) and the capture point 捕获点 (lecture 11).

Kajita's linear inverted pendulum: the whole body is a point mass at the centre of mass
:math:`c`, kept at a constant height :math:`h` above the ground by a massless telescopic leg
whose foot is the ZMP (centre of pressure) :math:`p`. With the height constant, the
horizontal motion is linear and each horizontal axis is independent:

.. math::

    \ddot c = \omega_0^2\,(c - p), \qquad \omega_0 = \sqrt{g / h},

with :math:`h` the COM's height *above the ground under the foot* (the plane of :math:`p`),
not the hip height or a leg length. Everything here is that equation solved in closed form:

* the motion (:func:`lip_state`): :math:`c(t) = p + (c_0 - p)\cosh\omega_0 t +
  \frac{\dot c_0}{\omega_0}\sinh\omega_0 t`, :math:`\dot c(t) = (c_0 - p)\,\omega_0\sinh
  \omega_0 t + \dot c_0\cosh\omega_0 t`;
* the orbital energy (:func:`orbital_energy`), conserved along it:
  :math:`E = \tfrac12\dot c^2 - \tfrac12\omega_0^2 (c - p)^2` (per unit mass, per axis; the
  COM passes over the foot if :math:`E > 0`, stops over it if :math:`E = 0` while moving
  towards it, and falls back if :math:`E < 0`);
* the capture point (Pratt et al. 2006; :func:`capture_point`): :math:`\xi = c +
  \dot c/\omega_0`, the point on the ground where the foot must be for the pendulum to come to
  rest over it. It diverges from the foot, :math:`\dot\xi = \omega_0(\xi - p)`, so
  :math:`\xi(t) = p + (\xi_0 - p)\,e^{\omega_0 t}` (:func:`capture_point_at`), and a step
  taken after :math:`t` seconds must land at that point to stop (:func:`step_to_stop`);
* when the COM reaches a given point (:func:`time_to_reach`).

Conventions: y up, so the ground plane is x–z and :math:`g = 9.81` (the magnitude of gravity
``(0, -9.81, 0)``). Every function works per horizontal axis and broadcasts its arguments
elementwise (numpy broadcasting over all dimensions): pass scalars or ``(...,)`` arrays for
the 1-D pendulum (sagittal plane), ``(..., 2)`` arrays of ``(x, z)`` ground-plane
coordinates for the 2-D one (and, for several times, ``t[:, None]`` against a ``(2,)``
state). Units are the caller's, consistent: meters with ``g = 9.81`` and seconds. A
non-finite argument or a non-positive ``omega0`` / ``height`` is a ``ValueError`` naming the
argument.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._typing import Array
from .._validate import as_array, as_positive

#: The magnitude of gravity in m/s^2 (y-up: gravity is ``(0, -G, 0)``).
G = 9.81


def _positive(x: ArrayLike, name: str) -> Array:
    """``x`` as a finite float array, every entry above zero; a ValueError naming ``name``."""
    a = as_array(x, name)
    if not np.all(a > 0):
        bad = a if a.ndim == 0 else a[~(a > 0)].flat[0]
        raise ValueError(f"{name}: must be positive, got {float(bad)!r}")
    return a


def _broadcast(where: str, **args: Array) -> None:
    """A ValueError naming every argument and its shape if they do not broadcast."""
    try:
        np.broadcast_shapes(*(a.shape for a in args.values()))
    except ValueError:
        listing = ", ".join(f"{k} has shape {a.shape}" for k, a in args.items())
        raise ValueError(f"{where}: the arguments do not broadcast together: {listing}") from None


def natural_frequency(height: ArrayLike, g: float = G) -> Array:
    r""":math:`\omega_0 = \sqrt{g / h}`, in 1/s.

    Parameters
    ----------
    height : array_like, shape (...)
        :math:`h`, the COM's height above the ground plane of the ZMP (meters; positive).
        Not the hip height, the leg length or the COM's y coordinate on a floor that is not
        at ``y = 0``: the height above the floor.
    g : float
        Gravity's magnitude, in the units of ``height`` per second squared.

    Returns
    -------
    ndarray, shape (...)
    """
    h = _positive(height, "height")
    out: Array = np.sqrt(as_positive(g, "g") / h)
    return out


def lip_acceleration(c: ArrayLike, p: ArrayLike, omega0: ArrayLike) -> Array:
    r""":math:`\ddot c = \omega_0^2 (c - p)`: the COM accelerates *away* from the foot.

    Parameters
    ----------
    c, p : array_like, shape (...) or (..., 2)
        COM and ZMP (foot) positions on the ground plane.
    omega0 : array_like
        :math:`\omega_0` (1/s, positive), broadcast with them.

    Returns
    -------
    ndarray, the broadcast shape
    """
    ca, pa, w = as_array(c, "c"), as_array(p, "p"), _positive(omega0, "omega0")
    _broadcast("lip_acceleration", c=ca, p=pa, omega0=w)
    out: Array = w**2 * (ca - pa)
    return out


def lip_state(t: ArrayLike, c0: ArrayLike, cdot0: ArrayLike, p: ArrayLike,
              omega0: ArrayLike) -> tuple[Array, Array]:
    r"""The LIP's COM position and velocity at time ``t``, in closed form.

    .. math::

        c(t) = p + (c_0 - p)\cosh\omega_0 t + \frac{\dot c_0}{\omega_0}\sinh\omega_0 t,
        \qquad
        \dot c(t) = (c_0 - p)\,\omega_0\sinh\omega_0 t + \dot c_0\cosh\omega_0 t

    with the foot fixed at ``p`` from time 0 (negative ``t`` runs the pendulum backwards).
    Computed as :math:`c - p = \tfrac12(\xi_0 - p)e^{\omega_0 t} + \tfrac12(c_0 - \dot c_0/
    \omega_0 - p)e^{-\omega_0 t}`, the same function without the cancellation of
    :math:`\cosh - \sinh` when the foot is at the capture point.

    Parameters
    ----------
    t : array_like
        Seconds since the state ``(c0, cdot0)``.
    c0, cdot0 : array_like, shape (...) or (..., 2)
        COM position and velocity at ``t = 0`` (ground-plane coordinates).
    p : array_like
        The ZMP (foot) position, fixed.
    omega0 : array_like
        :math:`\omega_0 = \sqrt{g/h}` (1/s, positive; :func:`natural_frequency`).

    All broadcast elementwise: for ``T`` times of a 2-D state pass ``t[:, None]``.

    Returns
    -------
    c, cdot : ndarray, the broadcast shape
    """
    ta, ca, va, pa = (as_array(t, "t"), as_array(c0, "c0"), as_array(cdot0, "cdot0"),
                      as_array(p, "p"))
    w = _positive(omega0, "omega0")
    _broadcast("lip_state", t=ta, c0=ca, cdot0=va, p=pa, omega0=w)
    # Evaluated as its divergent and convergent parts, c - p = a e^{wt} + b e^{-wt} with
    # a = (xi - p) / 2, b = (c0 - cdot0 / w - p) / 2: the same function, but a captured
    # pendulum (xi = p, a = 0) then decays to the foot without cosh - sinh cancelling.
    grow, decay = np.exp(w * ta), np.exp(-w * ta)
    a = 0.5 * (ca + va / w - pa)
    b = 0.5 * (ca - va / w - pa)
    c: Array = pa + a * grow + b * decay
    cdot: Array = w * (a * grow - b * decay)
    return c, cdot


def orbital_energy(c: ArrayLike, cdot: ArrayLike, p: ArrayLike, omega0: ArrayLike) -> Array:
    r"""Orbital energy :math:`E = \tfrac12\dot c^2 - \tfrac12\omega_0^2(c - p)^2` (Kajita).

    Per unit mass and per axis (m²/s² with meters and seconds), constant along
    :func:`lip_state`. Its sign says what the COM does while the foot stays at ``p``:
    ``E > 0`` it passes over the foot (with speed :math:`\sqrt{2E}` there) if it moves
    towards it; ``E = 0`` and moving towards the foot, it comes to rest over it; ``E < 0``,
    it stops short and falls back.

    Parameters
    ----------
    c, cdot, p : array_like, shape (...) or (..., 2)
        COM position, COM velocity, ZMP (foot) position. On the ground plane each axis has
        its own energy: a ``(..., 2)`` input gives ``(..., 2)`` energies.
    omega0 : array_like
        :math:`\omega_0` (1/s, positive).

    Returns
    -------
    ndarray, the broadcast shape
    """
    ca, va, pa = as_array(c, "c"), as_array(cdot, "cdot"), as_array(p, "p")
    w = _positive(omega0, "omega0")
    _broadcast("orbital_energy", c=ca, cdot=va, p=pa, omega0=w)
    out: Array = 0.5 * va**2 - 0.5 * w**2 * (ca - pa) ** 2
    return out


def capture_point(c: ArrayLike, cdot: ArrayLike, omega0: ArrayLike) -> Array:
    r"""The capture point :math:`\xi = c + \dot c / \omega_0` (Pratt et al. 2006).

    The instantaneous capture point: with the foot (ZMP) placed at :math:`\xi` now, the LIP
    comes to rest over it (:math:`c \to \xi`, :math:`\dot c \to 0` as :math:`t \to \infty`),
    its orbital energy about :math:`\xi` being zero. Also the divergent component of motion:
    :math:`\dot\xi = \omega_0(\xi - p)`.

    Parameters
    ----------
    c, cdot : array_like, shape (...) or (..., 2)
        COM position and velocity on the ground plane.
    omega0 : array_like
        :math:`\omega_0` (1/s, positive). Dividing by it, not multiplying: :math:`\dot c /
        \omega_0` is a length.

    Returns
    -------
    ndarray, the broadcast shape
    """
    ca, va = as_array(c, "c"), as_array(cdot, "cdot")
    w = _positive(omega0, "omega0")
    _broadcast("capture_point", c=ca, cdot=va, omega0=w)
    out: Array = ca + va / w
    return out


def capture_point_at(t: ArrayLike, c0: ArrayLike, cdot0: ArrayLike, p: ArrayLike,
                     omega0: ArrayLike) -> Array:
    r"""The capture point after ``t`` seconds on the foot ``p``:
    :math:`\xi(t) = p + (\xi_0 - p)\,e^{\omega_0 t}`.

    Equal to :func:`capture_point` of :func:`lip_state` at ``t``: the capture point runs away
    from the foot exponentially (it is still only while it is on the foot).

    Parameters
    ----------
    t : array_like
        Seconds.
    c0, cdot0, p : array_like, shape (...) or (..., 2)
        COM position and velocity at ``t = 0``; the foot, fixed.
    omega0 : array_like
        :math:`\omega_0` (1/s, positive).

    Returns
    -------
    ndarray, the broadcast shape
    """
    ta, ca, va, pa = (as_array(t, "t"), as_array(c0, "c0"), as_array(cdot0, "cdot0"),
                      as_array(p, "p"))
    w = _positive(omega0, "omega0")
    _broadcast("capture_point_at", t=ta, c0=ca, cdot0=va, p=pa, omega0=w)
    out: Array = pa + (ca + va / w - pa) * np.exp(w * ta)
    return out


def step_to_stop(c: ArrayLike, cdot: ArrayLike, omega0: ArrayLike, *,
                 p: ArrayLike | None = None, after: ArrayLike = 0.0) -> Array:
    r"""Where to put the next foot so that the LIP stops over it (in one step).

    Stepping now (``after = 0``): the capture point :math:`\xi = c + \dot c/\omega_0`. Stepping
    after ``after`` seconds more on the current foot ``p``: the capture point then,
    :math:`p + (\xi - p)\,e^{\omega_0 t}` (:func:`capture_point_at`). After the step the ZMP
    is at the new foot; the COM converges to it, :math:`c(t) \to` the new foot and
    :math:`\dot c(t) \to 0`.

    Parameters
    ----------
    c, cdot : array_like, shape (...) or (..., 2)
        The COM's position and velocity now, on the ground plane (1-D: the sagittal axis;
        2-D: ``(x, z)``).
    omega0 : array_like
        :math:`\omega_0` (1/s, positive).
    p : array_like, optional
        The current foot (ZMP); needed only when ``after`` is not 0.
    after : array_like
        Seconds before the new foot lands (non-negative).

    Returns
    -------
    ndarray, the broadcast shape
        The foot position, in the coordinates of ``c``.
    """
    ta = as_array(after, "after")
    if not np.all(ta >= 0):
        raise ValueError(f"after: seconds before the step, non-negative, got {after!r}")
    if p is None:
        if np.any(ta != 0):
            raise ValueError("p: the current foot is needed to step after a delay "
                             f"(after = {after!r})")
        return capture_point(c, cdot, omega0)
    return capture_point_at(ta, c, cdot, p, omega0)


def time_to_reach(c0: ArrayLike, cdot0: ArrayLike, p: ArrayLike, omega0: ArrayLike,
                  target: ArrayLike) -> Array:
    r"""The first time :math:`t \ge 0` at which the LIP's COM is at ``target``; ``inf`` if never.

    Per axis (1-D): with :math:`u = e^{\omega_0 t}`, :func:`lip_state` is
    :math:`c(t) - p = \tfrac12(\xi_0 - p)\,u + \tfrac12(c_0 - \dot c_0/\omega_0 - p)\,u^{-1}`,
    a quadratic in :math:`u`; the answer is the smallest root :math:`u \ge 1`, as
    :math:`t = \ln u / \omega_0`. ``inf`` when the COM never gets there: it turns back before
    it (negative orbital energy about the target's side), moves away from it, or only tends
    to it (captured exactly at the foot, :math:`t \to \infty`).

    Parameters
    ----------
    c0, cdot0, p : array_like, shape (...)
        COM position and velocity at ``t = 0``, the foot (fixed), one axis (pass each axis
        of a 2-D pendulum separately: the two axes reach their targets at different times).
    omega0 : array_like
        :math:`\omega_0` (1/s, positive).
    target : array_like
        The position to reach.

    Returns
    -------
    ndarray, the broadcast shape
        Seconds (``0`` where ``c0 == target``).
    """
    ca, va, pa, xa = (as_array(c0, "c0"), as_array(cdot0, "cdot0"), as_array(p, "p"),
                      as_array(target, "target"))
    w = _positive(omega0, "omega0")
    _broadcast("time_to_reach", c0=ca, cdot0=va, p=pa, omega0=w, target=xa)
    a = 0.5 * (ca + va / w - pa)  # coefficient of u
    b = 0.5 * (ca - va / w - pa)  # coefficient of 1/u
    d = xa - pa
    # a u^2 - d u + b = 0, roots by the cancellation-free pair q / a and b / q
    disc = d * d - 4.0 * a * b
    with np.errstate(divide="ignore", invalid="ignore"):
        q = 0.5 * (d + np.where(d >= 0, 1.0, -1.0) * np.sqrt(np.maximum(disc, 0.0)))
        roots = np.stack(np.broadcast_arrays(q / a, b / q))
    tol = 1e-12
    ok = np.isfinite(roots) & (roots >= 1.0 - tol) & (disc >= 0)[None]
    u = np.where(ok, np.maximum(roots, 1.0), np.inf).min(axis=0)
    exact = ca == xa  # already there: t = 0 even when the roots lose it to rounding
    t: Array = np.where(exact, 0.0, np.log(u) / w)
    return t


__all__ = [
    "G",
    "capture_point",
    "capture_point_at",
    "lip_acceleration",
    "lip_state",
    "natural_frequency",
    "orbital_energy",
    "step_to_stop",
    "time_to_reach",
]
