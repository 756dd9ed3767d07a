"""Mass–spring systems: derivatives against finite differences, closed forms, energy and
stability of the three integrators, Newton's optimality, the PD fix, the cloth, bad input."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from course.physics import (
    BEND,
    SHEAR,
    STRUCTURAL,
    NotConvergedWarning,
    SpringSystem,
    explicit_euler_step,
    grid_cloth,
    implicit_euler_gradient,
    implicit_euler_objective,
    implicit_euler_step,
    simulate,
    step,
    symplectic_euler_step,
)

NO_GRAVITY = (0.0, 0.0, 0.0)


def random_system(seed: int, n: int = 7, n_springs: int = 12, fixed=None, gravity=NO_GRAVITY):
    """Random particles and springs, rest lengths 0.5x to 1.5x the current length, so some
    springs are stretched and some compressed."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, 3))
    pairs = np.array([rng.choice(n, 2, replace=False) for _ in range(n_springs)])
    length = np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)
    rest = length * rng.uniform(0.5, 1.5, n_springs)
    system = SpringSystem.create(rng.uniform(0.5, 2.0, n), pairs, rest,
                                 rng.uniform(1.0, 20.0, n_springs), fixed, gravity)
    return system, x, rng.normal(size=(n, 3))


def central_gradient(f, x, eps=1e-6):
    g = np.zeros_like(x)
    for idx in np.ndindex(x.shape):
        e = np.zeros_like(x)
        e[idx] = eps
        g[idx] = (f(x + e) - f(x - e)) / (2 * eps)
    return g


def single_spring(k=100.0, m=1.0, rest=1.0, stretch=0.2):
    """Particle 0 fixed at the origin, particle 1 of mass m at rest + stretch along x."""
    system = SpringSystem.create([1.0, m], [[0, 1]], [rest], k, fixed=[0], gravity=NO_GRAVITY)
    x = np.array([[0.0, 0, 0], [rest + stretch, 0, 0]])
    return system, x, np.zeros((2, 3))


# -- derivatives --------------------------------------------------------------------------------


@settings(derandomize=True, max_examples=25, deadline=None)
@given(st.integers(0, 10_000))
def test_spring_gradient_matches_central_differences(seed):
    system, x, _ = random_system(seed)
    numeric = central_gradient(system.spring_energy, x)
    assert np.allclose(system.spring_gradient(x), numeric, atol=1e-6, rtol=1e-6)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_spring_hessian_matches_central_differences(seed):
    system, x, _ = random_system(seed)
    _, length = system._geometry(x)
    assert np.any(length < system.rest) and np.any(length > system.rest), "want both kinds"
    H = system.spring_hessian(x).toarray()
    numeric = np.zeros_like(H)
    for c in range(H.shape[1]):
        e = np.zeros(x.size)
        e[c] = 1e-6
        numeric[:, c] = (system.spring_gradient(x + e.reshape(x.shape))
                         - system.spring_gradient(x - e.reshape(x.shape))).ravel() / 2e-6
    assert np.allclose(H, numeric, atol=1e-5)
    assert np.allclose(H, H.T)


def test_implicit_objective_gradient_matches_central_differences():
    system, x, v = random_system(3, fixed=[1, 4], gravity=(0.0, -9.81, 0.0))
    args = (x, v, system.masses, system.springs, system.rest, system.k, 0.05, [1, 4],
            (0.0, -9.81, 0.0))
    x_new = x + 0.1 * np.random.default_rng(9).normal(size=x.shape)
    numeric = central_gradient(lambda z: implicit_euler_objective(z, *args), x_new)
    numeric[[1, 4]] = 0.0  # fixed rows are eliminated
    assert np.allclose(implicit_euler_gradient(x_new, *args), numeric, atol=1e-5, rtol=1e-7)


def test_psd_projection_clamps_only_compressed_springs():
    system, x, _ = random_system(4, n_springs=20)
    exact, none = system.spring_hessian_blocks(x)
    fixed, projected = system.spring_hessian_blocks(x, psd=True)
    _, length = system._geometry(x)
    assert not none.any()
    assert np.array_equal(projected, length < system.rest)
    assert np.allclose(fixed[~projected], exact[~projected])
    assert np.linalg.eigvalsh(exact[projected]).min() < 0  # compressed: indefinite
    assert np.linalg.eigvalsh(fixed).min() > -1e-9
    # the eigenvalues are k along the spring and max(k (1 - L/l), 0) across it
    c = np.maximum(1 - system.rest / length, 0)
    expected = np.sort(np.column_stack([system.k * c, system.k * c, system.k]), axis=1)
    assert np.allclose(np.linalg.eigvalsh(fixed), expected)
    assert np.linalg.eigvalsh(system.spring_hessian(x, psd=True).toarray()).min() > -1e-9


# -- closed forms -----------------------------------------------------------------------------


def test_symplectic_euler_period_matches_closed_form():
    k, m = 40.0, 0.5
    system, x, v = single_spring(k=k, m=m)
    period = 2 * np.pi * np.sqrt(m / k)
    h = period / 2000
    run = simulate(system, x, v, h, 8000, "symplectic")
    u = run.positions[:, 1, 0] - 1.0  # displacement from rest
    up = np.flatnonzero((u[:-1] < 0) & (u[1:] >= 0))
    t = (up + -u[up] / (u[up + 1] - u[up])) * h  # upward zero crossings, interpolated
    measured = np.diff(t).mean()
    assert len(up) >= 3
    assert measured == pytest.approx(period, rel=1e-3)


def test_implicit_step_of_a_linear_spring_matches_closed_form():
    # along the spring's axis, m (x⁺ - y) / h² + k (x⁺ - L) = 0
    k, m, h = 100.0, 1.0, 0.1
    system, x, _ = single_spring(k=k, m=m, stretch=0.3)
    v = np.array([[0.0, 0, 0], [0.5, 0, 0]])
    x_new, v_new, stats = step(system, x, v, h, tol=1e-12)
    y = x[1, 0] + h * v[1, 0]
    expected = (m * y / h**2 + k * 1.0) / (m / h**2 + k)
    assert x_new[1] == pytest.approx([expected, 0, 0], abs=1e-12)
    assert v_new[1] == pytest.approx((x_new[1] - x[1]) / h)
    assert stats.converged and stats.iterations <= 2  # a quadratic objective: one Newton step


# -- stability and energy -----------------------------------------------------------------------


def test_implicit_stable_where_explicit_diverges():
    system, x, v = single_spring(k=100.0, m=1.0)  # ω = 10 rad/s
    h = 0.3  # h ω = 3 > 2: beyond explicit (and symplectic) Euler's stability limit
    explicit = simulate(system, x, v, h, 400, "explicit")
    symplectic = simulate(system, x, v, h, 400, "symplectic")
    implicit = simulate(system, x, v, h, 400, "implicit")
    assert explicit.exploded_at is not None
    assert symplectic.exploded_at is not None
    assert implicit.exploded_at is None
    assert implicit.total_energy[-1] < implicit.total_energy[0]
    assert np.abs(implicit.positions[:, 1, 0] - 1.0).max() <= 0.2 + 1e-9


def test_cloth_implicit_stable_where_explicit_explodes():
    cloth = grid_cloth(8, 8, stiffness=2000.0)
    v = np.zeros_like(cloth.positions)
    explicit = simulate(cloth.system, cloth.positions, v, 1 / 60, 120, "explicit")
    implicit = simulate(cloth.system, cloth.positions, v, 1 / 60, 120, "implicit")
    assert explicit.exploded_at is not None and explicit.exploded_at < 120
    assert implicit.exploded_at is None
    assert all(s.converged for s in implicit.stats)


def test_energy_explicit_grows_implicit_decays_symplectic_bounded():
    system, x, v = single_spring(k=100.0, m=1.0)  # ω = 10
    h, n = 0.01, 1000  # h ω = 0.1, about 16 periods
    e0 = system.energy(x, v).total
    energy = {m: simulate(system, x, v, h, n, m).total_energy
              for m in ("explicit", "symplectic", "implicit")}
    assert energy["explicit"][-1] > 10 * e0  # grows by (1 + h²ω²) per step
    assert np.all(np.diff(energy["implicit"]) <= 1e-12)  # never gains energy
    assert energy["implicit"][-1] < 0.1 * e0
    drift = np.abs(energy["symplectic"] / e0 - 1)
    assert drift.max() < 0.06  # oscillates within O(h ω) of the start, no trend
    assert abs(energy["symplectic"][-200:].mean() / e0 - 1) < 0.06


def test_momentum_conserved_without_gravity_or_fixed_points():
    system, x, v = random_system(5)
    p0 = (system.masses[:, None] * v).sum(axis=0)
    for method in ("explicit", "symplectic", "implicit"):
        _, v_new, _ = step(system, x, v, 0.01, method, tol=1e-12)
        assert np.allclose((system.masses[:, None] * v_new).sum(axis=0), p0, atol=1e-9), method


# -- constraints and optimality -------------------------------------------------------------


@pytest.mark.parametrize("method", ["explicit", "symplectic", "implicit"])
def test_fixed_points_never_move(method):
    cloth = grid_cloth(6, 6)
    run = simulate(cloth.system, cloth.positions, np.zeros_like(cloth.positions), 1e-3, 30,
                   method)
    fixed = cloth.system.fixed
    assert len(fixed) == 2
    assert np.array_equal(run.positions[:, fixed], np.broadcast_to(
        cloth.positions[fixed], run.positions[:, fixed].shape))
    assert not run.velocities[:, fixed].any()
    assert np.abs(run.positions[-1] - cloth.positions).max() > 1e-4  # the rest did move


@pytest.mark.parametrize("solver", ["cg", "direct"])
def test_newton_step_is_optimal(solver):
    cloth = grid_cloth(7, 7)
    s = cloth.system
    rng = np.random.default_rng(11)
    x = cloth.positions + 0.02 * rng.normal(size=cloth.positions.shape)
    x[s.fixed] = cloth.positions[s.fixed]
    v = rng.normal(size=x.shape)
    v[s.fixed] = 0.0
    args = (s.masses, s.springs, s.rest, s.k, 1 / 30, s.fixed, s.gravity)
    x_new, v_new = implicit_euler_step(x, v, *args, tol=1e-10, solver=solver)
    g = implicit_euler_gradient(x_new, x, v, *args)
    weight = np.linalg.norm(s.masses[s.free]) * 9.81
    assert np.linalg.norm(g) <= 1e-9 * weight  # tol is relative to max(weight, first ‖∇E‖)
    assert np.allclose(v_new, (x_new - x) * 30)  # v⁺ = (x⁺ - x) / h
    # the minimiser: nudging it in any direction raises E
    e = implicit_euler_objective(x_new, x, v, *args)
    for _ in range(5):
        d = rng.normal(size=x.shape) * 1e-4
        d[s.fixed] = 0.0
        assert implicit_euler_objective(x_new + d, x, v, *args) > e


def test_solvers_agree_and_stats_are_consistent():
    cloth = grid_cloth(9, 9)
    v = np.zeros_like(cloth.positions)
    a = step(cloth.system, cloth.positions, v, 1 / 60, tol=1e-10, solver="cg")
    b = step(cloth.system, cloth.positions, v, 1 / 60, tol=1e-10, solver="direct")
    assert np.allclose(a.x, b.x, atol=1e-9)
    for r in (a, b):
        assert r.stats.converged and 1 <= r.stats.iterations <= 50
        assert r.stats.gradient_norm <= r.stats.threshold
        g = implicit_euler_gradient(r.x, cloth.positions, v, cloth.system.masses,
                                    cloth.system.springs, cloth.system.rest, cloth.system.k,
                                    1 / 60, cloth.system.fixed)
        assert np.linalg.norm(g) == pytest.approx(r.stats.gradient_norm, rel=1e-6, abs=1e-14)


def test_hanging_cloth_comes_to_rest_near_rest_length():
    cloth = grid_cloth(8, 8, plane="xy", stiffness=2000.0)
    run = simulate(cloth.system, cloth.positions, np.zeros_like(cloth.positions), 1 / 30, 200)
    assert run.exploded_at is None
    speed = np.linalg.norm(run.velocities[-1], axis=1)
    assert speed.max() < 1e-3
    x = run.positions[-1]
    s = cloth.system
    strain = np.linalg.norm(x[s.springs[:, 0]] - x[s.springs[:, 1]], axis=1) / s.rest - 1
    structural = cloth.kinds == STRUCTURAL
    assert np.abs(strain[structural]).max() < 0.05
    assert np.median(np.abs(strain[structural])) < 0.01
    assert x[:, 1].max() <= 1e-9  # hangs below its pins


def test_pd_fix_on_a_compressed_configuration():
    # four particles squeezed to a tenth of their springs' rest lengths; with a large h the
    # compressed springs' curvature k (1 - L/l) < 0 outweighs m/h² = 1: ∇²E is indefinite
    x = np.random.default_rng(0).normal(size=(4, 3)) * 0.1
    springs = [[0, 1], [1, 2], [2, 3], [0, 2], [1, 3]]
    system = SpringSystem.create(np.ones(4), springs, np.ones(5), [100, 50, 80, 30, 60],
                                 gravity=NO_GRAVITY)
    v = np.zeros((4, 3))

    def true_hessian(z):
        return system.spring_hessian(z).toarray() + np.eye(12)  # ∇²E = M/h² + ∇²U, h = 1

    assert np.linalg.eigvalsh(true_hessian(x)).min() < 0
    auto = step(system, x, v, 1.0, tol=1e-10)
    assert auto.stats.pd_fixes >= 1 and auto.stats.projected >= 1
    assert auto.stats.converged
    assert np.linalg.eigvalsh(true_hessian(auto.x)).min() > 0  # a true (local) minimum
    direct = step(system, x, v, 1.0, tol=1e-10, solver="direct")
    assert direct.stats.converged
    always = step(system, x, v, 1.0, tol=1e-10, pd_fix="always", max_iter=5)
    assert always.stats.iterations == 5 and always.stats.pd_fixes >= 1
    never = step(system, x, v, 1.0, tol=1e-10, pd_fix="never")
    assert never.stats.pd_fixes == 0 and never.stats.fallbacks >= 1  # an uphill Newton step


def test_line_search_never_raises_the_objective():
    cloth = grid_cloth(6, 6, stiffness=5000.0)
    s = cloth.system
    x = cloth.positions.copy()
    x[:, 1] += 0.3 * np.sin(7 * x[:, 0]) * np.cos(5 * x[:, 2])  # a crumpled start
    x[s.fixed] = cloth.positions[s.fixed]
    v = np.zeros_like(x)
    h = 0.2
    args = (s.masses, s.springs, s.rest, s.k, h, s.fixed, s.gravity)
    y = x + h * v + h * h * np.array(s.gravity)
    y[s.fixed] = x[s.fixed]
    with_search = step(s, x, v, h, tol=1e-9)
    assert with_search.stats.converged
    assert (implicit_euler_objective(with_search.x, x, v, *args)
            <= implicit_euler_objective(y, x, v, *args))


# -- the flat functions and the cloth builder -----------------------------------------------


def test_flat_functions_match_step():
    system, x, v = random_system(6, fixed=[0], gravity=(0.0, -9.81, 0.0))
    args = (system.masses, system.springs, system.rest, system.k, 0.02, [0], system.gravity)
    for fn, method in ((explicit_euler_step, "explicit"),
                       (symplectic_euler_step, "symplectic"),
                       (implicit_euler_step, "implicit")):
        x_new, v_new = fn(x, v, *args)
        ref = step(system, x, v, 0.02, method)
        assert np.allclose(x_new, ref.x) and np.allclose(v_new, ref.v), method


def stiff_cloth():
    """A stiff 3x3 cloth, jittered, stepped by a whole second: Newton needs ~60 iterations."""
    cloth = grid_cloth(3, 3, stiffness=1e5)
    x = cloth.positions + np.random.default_rng(0).normal(scale=0.2, size=cloth.positions.shape)
    return cloth.system, x


def test_an_unconverged_implicit_step_says_so_with_its_numbers():
    s, x = stiff_cloth()
    args = (x, 0 * x, s.masses, s.springs, s.rest, s.k, 1.0, s.fixed, s.gravity)
    stats = step(s, x, 0 * x, 1.0).stats
    assert not stats.converged and stats.iterations == 50
    with pytest.warns(NotConvergedWarning) as caught:
        x_new, _ = implicit_euler_step(*args)
    message = str(caught[0].message)
    grad = np.linalg.norm(implicit_euler_gradient(x_new, *args))  # measured afresh
    assert f"after 50 iterations with ‖∇E‖ = {grad:.3g} N" in message
    assert f"threshold {stats.threshold:.3g} N" in message and grad > stats.threshold
    with warnings.catch_warnings():
        warnings.simplefilter("error", NotConvergedWarning)
        x_new, _ = implicit_euler_step(*args, max_iter=1000)
    assert np.linalg.norm(implicit_euler_gradient(x_new, *args)) <= stats.threshold


def test_simulate_says_which_steps_did_not_converge():
    s, x = stiff_cloth()
    with pytest.warns(NotConvergedWarning, match=r"simulate: .* stopped in step 1 after 50 "
                                                  r"iterations.* of 3 steps did not converge"):
        run = simulate(s, x, 0 * x, 1.0, 3)
    assert run.unconverged == [n for n, st in enumerate(run.stats, 1) if not st.converged]
    assert run.unconverged[0] == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error", NotConvergedWarning)
        calm = simulate(s, x, 0 * x, 1.0, 3, max_iter=1000)
    assert calm.unconverged == [] and all(st.converged for st in calm.stats)


def test_a_system_come_to_rest_converges_at_rounding_level():
    """No gravity and nearly at rest: the force scale tends to 0, and tol times it fell below
    the rounding error of ∇E itself. 12 of these 400 steps then chased noise (‖∇E‖ ~1e-14)
    for all 50 iterations and said they had not converged; the threshold's floor, rounding's
    size, stops them at once, and no warning is given."""
    system, x, v = single_spring(k=100.0, m=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", NotConvergedWarning)
        run = simulate(system, x, v, 0.3, 400, "implicit")
    assert run.unconverged == [] and max(st.iterations for st in run.stats) <= 2
    late = run.stats[-1]
    assert late.gradient_norm <= late.threshold < 1e-10  # still only rounding's size


@settings(derandomize=True, max_examples=25, deadline=None)
@given(st.integers(0, 10_000), st.integers(1, 4))
def test_property_the_warning_is_given_exactly_when_the_gradient_is_too_large(seed, max_iter):
    """The flag tells the truth: a warning iff ‖∇E(x⁺)‖, computed afresh, is above tol times
    the force scale (the free particles' weight, or the gradient at the start if larger)."""
    system, x, v = random_system(seed, fixed=[0], gravity=(0.0, -9.81, 0.0))
    args = (x, v, system.masses, system.springs, system.rest, system.k, 0.1, system.fixed,
            system.gravity)
    free = np.ones(len(x), bool)
    free[0] = False
    start = x + 0.1 * v + 0.01 * np.array(system.gravity)
    start[0] = x[0]
    scale = max(np.linalg.norm(system.masses[free]) * 9.81,
                np.linalg.norm(implicit_euler_gradient(start, *args)))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", NotConvergedWarning)
        x_new, _ = implicit_euler_step(*args, max_iter=max_iter)
    too_large = np.linalg.norm(implicit_euler_gradient(x_new, *args)) > 1e-6 * scale
    assert too_large == any(issubclass(w.category, NotConvergedWarning) for w in caught)
    if too_large:
        assert f"after {max_iter} iterations" in str(caught[0].message)


def test_grid_cloth_springs():
    n, m = 5, 7
    cloth = grid_cloth(n, m, size=1.2)
    spacing = 1.2 / (m - 1)
    counts = np.bincount(cloth.kinds, minlength=3)
    assert counts[STRUCTURAL] == n * (m - 1) + (n - 1) * m
    assert counts[SHEAR] == 2 * (n - 1) * (m - 1)
    assert counts[BEND] == n * (m - 2) + (n - 2) * m
    rest = {STRUCTURAL: spacing, SHEAR: np.sqrt(2) * spacing, BEND: 2 * spacing}
    for kind, length in rest.items():
        assert np.allclose(cloth.system.rest[cloth.kinds == kind], length)
    assert cloth.system.masses.sum() == pytest.approx(1.0)
    assert sorted(cloth.system.fixed.tolist()) == [0, m - 1]
    assert np.allclose(cloth.system.spring_gradient(cloth.positions), 0)  # starts at rest
    assert cloth.quads.shape == ((n - 1) * (m - 1), 4)
    stiffer = cloth.with_stiffness(3 * cloth.stiffness)
    assert np.allclose(stiffer.system.k, 3 * cloth.system.k)
    assert grid_cloth(3, 3, bend=0).kinds.max() == SHEAR
    assert len(grid_cloth(3, 3, pinned="all corners").system.fixed) == 4


# -- bad input ------------------------------------------------------------------------------


GOOD = {
    "masses": [1.0, 1.0, 1.0],
    "springs": [[0, 1], [1, 2]],
    "rest": [1.0, 1.0],
    "k": 10.0,
}


@pytest.mark.parametrize("name, value, message", [
    ("masses", [1.0, -1.0, 1.0], "masses: must be positive, masses[1]"),
    ("masses", [[1.0, 1.0, 1.0]], "masses: expected shape"),
    ("masses", [1.0, np.nan, 1.0], "masses: contains NaN"),
    ("springs", [[0, 3], [1, 2]], "springs: springs[0] = [0, 3] references a missing particle"),
    ("springs", [[0, 1], [-1, 2]], "springs: springs[1]"),
    ("springs", [[0, 1, 2]], "springs: expected integer index pairs"),
    ("springs", [[0.0, 1.0], [1.0, 2.0]], "springs: expected integer index pairs"),
    ("springs", [[1, 1], [1, 2]], "springs: springs[0] joins particle 1 to itself"),
    ("rest", [1.0], "rest: expected shape"),
    ("rest", [1.0, -0.5], "rest: rest lengths must be >= 0"),
    ("k", 0.0, "k: stiffness must be positive"),
    ("k", [1.0, 2.0, 3.0], "k: expected shape"),
    ("fixed", [5], "fixed: index 5 is not a particle"),
    ("fixed", [True, False], "fixed: a boolean mask must have shape"),
    ("fixed", [0.5], "fixed: expected particle indices"),
    ("gravity", [0.0, -9.81], "gravity: expected shape"),
])
def test_bad_system_input_names_the_argument(name, value, message):
    with pytest.raises(ValueError, match=message.replace("[", r"\[").replace("]", r"\]")):
        SpringSystem.create(**{**GOOD, name: value})


@pytest.mark.parametrize("kwargs, message", [
    ({"h": 0.0}, "^h: "),
    ({"h": -0.1}, "^h: "),
    ({"h": float("nan")}, "^h: "),
    ({"x": np.zeros((2, 3))}, r"^x: expected shape \(3, 3\)"),
    ({"v": np.zeros((3, 2))}, r"^v: expected shape \(3, 3\)"),
    ({"x": np.full((3, 3), np.inf)}, "^x: contains NaN"),
    ({"method": "verlet"}, "^method: "),
    ({"solver": "lu"}, "^solver: "),
    ({"pd_fix": "maybe"}, "^pd_fix: "),
    ({"tol": 0.0}, "^tol and max_iter: "),
])
def test_bad_step_input_names_the_argument(kwargs, message):
    system = SpringSystem.create(**GOOD)
    call = {"x": np.eye(3), "v": np.zeros((3, 3)), "h": 0.01, **kwargs}
    with pytest.raises(ValueError, match=message):
        step(system, **call)


def test_bad_input_to_the_flat_functions_and_cloth():
    with pytest.raises(ValueError, match="^masses: must be positive"):
        implicit_euler_step(np.eye(3), np.zeros((3, 3)), [1.0, 0.0, 1.0], GOOD["springs"],
                            GOOD["rest"], 10.0, 0.01)
    with pytest.raises(ValueError, match="^x_new: expected shape"):
        implicit_euler_gradient(np.eye(2), np.eye(3), np.zeros((3, 3)), *GOOD.values(), 0.01)
    with pytest.raises(ValueError, match="^h: "):
        explicit_euler_step(np.eye(3), np.zeros((3, 3)), *GOOD.values(), h=0)
    with pytest.raises(ValueError, match="^rows: "):
        grid_cloth(1, 4)
    with pytest.raises(ValueError, match="^pinned: "):
        grid_cloth(3, 3, pinned="middle")
    with pytest.raises(ValueError, match="^n_steps: "):
        simulate(SpringSystem.create(**GOOD), np.eye(3), np.zeros((3, 3)), 0.01, -1)
    with pytest.raises(ValueError, match="^stiffness: "):
        grid_cloth(3, 3).with_stiffness(-1.0)
