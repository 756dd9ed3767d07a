"""course.keyframes.curves: closed forms, continuity measured numerically, errors, properties."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.interpolate import CubicSpline
from scipy.special import comb

from course import keyframes as kf

TIMES = np.array([0.0, 0.4, 1.1, 1.5, 2.2, 2.6, 3.0])  # deliberately uneven
SCHEMES = {
    "linear": kf.linear,
    "polynomial": kf.polynomial,
    "cubic": kf.cubic,
    "catmull_rom": kf.catmull_rom,
    "catmull_rom uniform": lambda k, x, t, **kw: kf.catmull_rom(k, x, t, knots="uniform", **kw),
    "catmull_rom centripetal": lambda k, x, t, **kw: kf.catmull_rom(k, x, t, knots="centripetal",
                                                                     **kw),
}


def cubic_poly(x):
    return x**3 - 2 * x**2 + 0.5 * x + 1


def cubic_poly_slope(x):
    return 3 * x**2 - 4 * x + 0.5


def one_sided(f, x, side, derivative):
    """f's ``derivative`` at ``x`` from the left (side=-1) or the right (+1), by a one-sided
    second-order stencil on that side only, so a jump at ``x`` does not leak in."""
    if derivative == 0:
        return f(np.array([x + side * 1e-12]))[0]
    h = side * (1e-5 if derivative == 1 else 1e-3)
    v = f(x + h * np.arange(4.0))
    if derivative == 1:
        return (-3 * v[0] + 4 * v[1] - v[2]) / (2 * h)
    return (2 * v[0] - 5 * v[1] + 4 * v[2] - v[3]) / h**2


def jump(f, x, derivative):
    return abs(one_sided(f, x, 1, derivative) - one_sided(f, x, -1, derivative))


# --------------------------------------------------------------------------- closed forms
def test_linear_reproduces_lines_and_its_velocity():
    keys = 2.0 * TIMES - 1.0
    t = np.linspace(0, 3, 301)
    assert np.allclose(kf.linear(keys, TIMES, t), 2 * t - 1, atol=1e-14)
    assert np.allclose(kf.linear(keys, TIMES, t, derivative=1), 2.0)
    assert np.all(kf.linear(keys, TIMES, t, derivative=2) == 0)


def test_clamped_cubic_through_keys_of_a_cubic_is_exact():
    t = np.linspace(0, 3, 301)
    x4 = TIMES[[0, 2, 4, 6]]  # 4 keys
    spline = kf.cubic(cubic_poly(x4), x4, t, start_tangent=cubic_poly_slope(0.0),
                      end_tangent=cubic_poly_slope(3.0))
    assert np.abs(spline - cubic_poly(t)).max() < 1e-12
    velocity = kf.cubic(cubic_poly(x4), x4, t, start_tangent=cubic_poly_slope(0.0),
                        end_tangent=cubic_poly_slope(3.0), derivative=1)
    assert np.abs(velocity - cubic_poly_slope(t)).max() < 1e-11
    # the natural spline is not exact (its ends are straight: a cubic's are not)
    natural = kf.cubic(cubic_poly(x4), x4, t)
    assert np.abs(natural - cubic_poly(t)).max() > 1e-2


def test_natural_cubic_matches_scipy_and_has_straight_ends():
    rng = np.random.default_rng(1)
    keys = rng.normal(size=(TIMES.size, 3))
    t = np.linspace(0, 3, 257)
    ref = CubicSpline(TIMES, keys, bc_type="natural")
    assert np.abs(kf.cubic(keys, TIMES, t) - ref(t)).max() < 1e-12
    end_acc = kf.cubic(keys, TIMES, np.array([0.0, 3.0]), derivative=2)
    assert np.abs(end_acc).max() < 1e-10


def test_clamped_cubic_matches_scipy():
    rng = np.random.default_rng(2)
    keys = rng.normal(size=TIMES.size)
    t = np.linspace(0, 3, 257)
    ref = CubicSpline(TIMES, keys, bc_type=((1, 0.7), (1, -2.0)))
    got = kf.cubic(keys, TIMES, t, start_tangent=0.7, end_tangent=-2.0)
    assert np.abs(got - ref(t)).max() < 1e-12


def test_polynomial_reproduces_a_cubic_exactly_with_its_derivatives():
    t = np.linspace(0, 3, 101)
    keys = cubic_poly(TIMES)
    assert np.abs(kf.polynomial(keys, TIMES, t) - cubic_poly(t)).max() < 1e-12
    assert np.abs(kf.polynomial(keys, TIMES, t, derivative=1) - cubic_poly_slope(t)).max() < 1e-10
    assert np.abs(kf.polynomial(keys, TIMES, t, derivative=2) - (6 * t - 4)).max() < 1e-9


def test_polynomial_shows_runge_growth():
    """On 1/(1+25x^2) with equally spaced keys, the error grows with the number of keys
    (Runge), while the natural cubic spline's shrinks."""
    x = np.linspace(-1, 1, 2001)
    f = 1 / (1 + 25 * x**2)
    poly_err, spline_err = [], []
    for n in (5, 9, 13, 17, 21):
        keys_t = np.linspace(-1, 1, n)
        keys = 1 / (1 + 25 * keys_t**2)
        poly_err.append(np.abs(kf.polynomial(keys, keys_t, x) - f).max())
        spline_err.append(np.abs(kf.cubic(keys, keys_t, x) - f).max())
    assert all(b > a for a, b in zip(poly_err, poly_err[1:], strict=False)), poly_err
    assert poly_err[-1] > 50, poly_err  # 21 keys: the curve swings far beyond [0, 1]
    assert all(b < a for a, b in zip(spline_err, spline_err[1:], strict=False)), spline_err
    assert spline_err[-1] < 0.02


def test_hermite_meets_its_keys_and_tangents():
    rng = np.random.default_rng(3)
    keys, tangents = rng.normal(size=(TIMES.size, 2)), rng.normal(size=(TIMES.size, 2))
    assert np.allclose(kf.hermite(keys, tangents, TIMES, TIMES), keys, atol=1e-14)
    assert np.allclose(kf.hermite(keys, tangents, TIMES, TIMES, derivative=1), tangents,
                       atol=1e-12)
    f = lambda t: kf.hermite(keys, tangents, TIMES, t, derivative=1)  # noqa: E731
    for x in TIMES[1:-1]:  # the velocity approached from either side is the given tangent
        assert np.allclose(one_sided(lambda t: kf.hermite(keys, tangents, TIMES, t), x, -1, 1),
                           f(np.array([x]))[0], atol=1e-5)


def test_cubic_tangents_solve_the_tridiagonal_system():
    rng = np.random.default_rng(4)
    keys = rng.normal(size=TIMES.size)
    m = kf.cubic_tangents(keys, TIMES)
    h, delta = np.diff(TIMES), np.diff(keys) / np.diff(TIMES)
    interior = h[1:] * m[:-2] + 2 * (h[:-1] + h[1:]) * m[1:-1] + h[:-1] * m[2:]
    assert np.allclose(interior, 3 * (h[1:] * delta[:-1] + h[:-1] * delta[1:]))
    assert np.isclose(2 * m[0] + m[1], 3 * delta[0])
    assert np.isclose(m[-2] + 2 * m[-1], 3 * delta[-1])


def test_catmull_rom_uniform_tangent_is_the_central_difference():
    keys = np.array([0.0, 1.0, 4.0, 2.0, 3.0])
    times = np.arange(5.0) * 0.5
    velocity = kf.catmull_rom(keys, times, times, derivative=1)
    assert np.allclose(velocity[1:-1], (keys[2:] - keys[:-2]) / (2 * 0.5))
    assert np.allclose(velocity[[0, -1]], [(keys[1] - keys[0]) / 0.5, (keys[-1] - keys[-2]) / 0.5])


def test_catmull_rom_by_time_divides_by_the_time_between_the_neighbours():
    keys = np.array([0.0, 1.0, 4.0, 2.0])
    times = np.array([0.0, 0.3, 1.2, 1.5])
    velocity = kf.catmull_rom(keys, times, times, derivative=1)
    assert np.allclose(velocity[1:-1], (keys[2:] - keys[:-2]) / (times[2:] - times[:-2]))


def test_centripetal_tangent_is_the_slope_of_the_parabola_in_its_knots():
    keys = np.array([[0.0, 0.0], [1.0, 1.0], [1.1, 1.0], [2.0, 0.0]])
    times = np.arange(4.0)
    s = np.concatenate([[0.0], np.cumsum(np.sqrt(np.linalg.norm(np.diff(keys, axis=0), axis=1)))])
    # d/dt = dp/ds * ds/dt; leaving key i the segment has ds/dt = s_{i+1} - s_i
    velocity = kf.catmull_rom(keys, times, times[1:3], knots="centripetal", derivative=1)
    for k, i in enumerate((1, 2)):
        slope = [np.polyval(np.polyder(np.polyfit(s[i - 1:i + 2], keys[i - 1:i + 2, c], 2)), s[i])
                 for c in range(2)]
        assert np.allclose(velocity[k], np.array(slope) * (s[i + 1] - s[i]))


def test_centripetal_has_no_loop_where_uniform_does():
    """Two close keys between far ones: uniform knots make the short segment overshoot into
    a loop (its x goes backwards); centripetal knots keep it going forward."""
    keys = np.array([[0.0, 0.0], [1.0, 1.0], [1.1, 1.0], [2.0, 0.0]])
    t = np.linspace(1, 2, 201)
    x_uniform = kf.catmull_rom(keys, np.arange(4.0), t, knots="uniform")[:, 0]
    x_centripetal = kf.catmull_rom(keys, np.arange(4.0), t, knots="centripetal")[:, 0]
    assert np.diff(x_uniform).min() < 0
    assert np.diff(x_centripetal).min() > 0


def test_catmull_rom_reproduces_a_parabola_between_equally_spaced_keys():
    """A quadratic's central differences are its exact slopes at equal spacing, so every
    interior Hermite segment is the quadratic."""
    times = np.linspace(0, 3, 7)
    keys = 2 * times**2 - times
    t = np.linspace(times[1], times[-2], 200)
    assert np.abs(kf.catmull_rom(keys, times, t) - (2 * t**2 - t)).max() < 1e-12


def test_bezier_de_casteljau_matches_bernstein_form_and_derivative():
    rng = np.random.default_rng(5)
    control = rng.normal(size=(6, 2))
    s = np.linspace(0, 1, 101)
    n = 5
    bernstein = sum(comb(n, i) * s[:, None] ** i * (1 - s[:, None]) ** (n - i) * control[i]
                    for i in range(n + 1))
    assert np.abs(kf.bezier(control, s) - bernstein).max() < 1e-13
    d_bernstein = sum(n * comb(n - 1, i) * s[:, None] ** i * (1 - s[:, None]) ** (n - 1 - i)
                      * (control[i + 1] - control[i]) for i in range(n))
    assert np.abs(kf.bezier(control, s, derivative=1) - d_bernstein).max() < 1e-12
    assert np.allclose(kf.bezier(control, [0.0, 1.0]), control[[0, -1]])


def test_hermite_segment_is_the_bezier_with_thirds_of_the_tangents():
    p0, p1, m0, m1, h = np.array([0.0, 1.0]), np.array([2.0, 0.5]), np.array([1.0, 3.0]), \
        np.array([-1.0, 0.0]), 0.8
    s = np.linspace(0, 1, 50)
    hermite = kf.hermite([p0, p1], [m0, m1], [0.0, h], s * h)
    bez = kf.bezier([p0, p0 + h * m0 / 3, p1 - h * m1 / 3, p1], s)
    assert np.abs(hermite - bez).max() < 1e-14


# --------------------------------------------------------------------------- continuity
@pytest.mark.parametrize("name", list(SCHEMES))
def test_every_scheme_interpolates_its_keys(name):
    rng = np.random.default_rng(6)
    keys = rng.normal(size=(TIMES.size, 4, 3))
    got = SCHEMES[name](keys, TIMES, TIMES)
    assert got.shape == keys.shape
    assert np.abs(got - keys).max() < 1e-10


@pytest.mark.parametrize(("name", "order"), [
    ("linear", 0), ("catmull_rom", 1), ("catmull_rom centripetal", 0), ("cubic", 2),
    ("polynomial", 2),
])
def test_continuity_order_measured(name, order):
    """C^order at interior keys (one-sided finite differences agree) and not C^(order+1)
    (except the polynomial, smooth everywhere)."""
    rng = np.random.default_rng(7)
    keys = rng.normal(size=TIMES.size)
    f = lambda t: SCHEMES[name](keys, TIMES, t)  # noqa: E731
    tol = (1e-9, 1e-4, 1e-2)
    for x in TIMES[1:-1]:
        for d in range(order + 1):
            assert jump(f, x, d) < tol[d], f"{name}: derivative {d} jumps at {x}"
    if name != "polynomial" and order < 2:
        assert max(jump(f, x, order + 1) for x in TIMES[1:-1]) > 0.1


@pytest.mark.parametrize(("curve", "expected"), [
    (lambda t: np.where(t < 0.5, 0.0, 1.0), (1.0, 0.0, 0.0)),             # a step
    (lambda t: np.abs(t - 0.5) * 3.0, (0.0, 6.0, 0.0)),                   # a kink: -3 | +3
    (lambda t: np.where(t < 0.5, 0.0, 2.0 * (t - 0.5) ** 2), (0.0, 0.0, 4.0)),  # p'' 0 | 4
    (lambda t: np.sin(3 * t), (0.0, 0.0, 0.0)),                           # smooth
])
def test_continuity_jumps_closed_forms(curve, expected):
    np.testing.assert_allclose(kf.continuity_jumps(curve, 0.5), expected, atol=1e-6)


def test_continuity_jumps_measures_what_the_schemes_promise():
    """The notebook's C^k table: each scheme's order, from the library's measure."""
    keys = np.array([0.0, 0.8, 0.7, 0.5, 1.0, -0.6])
    times = np.array([0.0, 0.5, 1.2, 1.6, 2.4, 3.0])
    for name, order in (("linear", 0), ("catmull_rom", 1), ("cubic", 2)):
        worst = np.max([kf.continuity_jumps(lambda t, n=name: SCHEMES[n](keys, times, t), x)
                        for x in times[1:-1]], axis=0)
        assert int(np.sum(np.cumprod(worst < [1e-9, 1e-3, 1e-1])) - 1) == order, (name, worst)
    with pytest.raises(ValueError, match="h: expected > 0"):
        kf.continuity_jumps(np.sin, 0.5, h=0.0)
    with pytest.raises(ValueError, match="curve: expected 4 values"):
        kf.continuity_jumps(lambda t: np.zeros(3), 0.5)


def test_catmull_rom_by_time_is_c1_where_uniform_knots_are_not():
    keys = np.array([0.0, 1.0, 3.0, 2.0, 2.5])
    times = np.array([0.0, 0.2, 1.5, 1.7, 3.0])
    by_time = lambda t: kf.catmull_rom(keys, times, t)  # noqa: E731
    uniform = lambda t: kf.catmull_rom(keys, times, t, knots="uniform")  # noqa: E731
    assert max(jump(by_time, x, 1) for x in times[1:-1]) < 1e-4
    assert max(jump(uniform, x, 1) for x in times[1:-1]) > 1.0


def test_analytic_derivatives_match_finite_differences():
    rng = np.random.default_rng(8)
    keys = rng.normal(size=(TIMES.size, 2))
    t = np.linspace(0.05, 2.95, 40)
    t = t[np.min(np.abs(t[:, None] - TIMES), axis=1) > 1e-3]  # away from the kinks
    h = 1e-6
    for name, f in SCHEMES.items():
        fd = (f(keys, TIMES, t + h) - f(keys, TIMES, t - h)) / (2 * h)
        assert np.abs(f(keys, TIMES, t, derivative=1) - fd).max() < 1e-5, name
        fd2 = (f(keys, TIMES, t + 1e-4, derivative=1) - f(keys, TIMES, t - 1e-4, derivative=1))
        assert np.abs(f(keys, TIMES, t, derivative=2) - fd2 / 2e-4).max() < 1e-4, name


def test_centripetal_handles_coincident_keys():
    keys = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [2.0, 1.0]])
    times = np.arange(4.0)
    out = kf.catmull_rom(keys, times, np.linspace(0, 3, 31), knots="centripetal")
    assert np.all(np.isfinite(out))
    resting = kf.catmull_rom(keys, times, [1.0, 1.5, 2.0], knots="centripetal")
    assert np.allclose(resting, keys[1])  # the curve rests between the coincident keys


# --------------------------------------------------------------------------- shapes, errors
def test_batched_shapes():
    keys = np.zeros((TIMES.size, 5, 3))
    t = np.linspace(0, 3, 24).reshape(2, 3, 4)
    for f in SCHEMES.values():
        assert f(keys, TIMES, t).shape == (2, 3, 4, 5, 3)
        assert f(keys, TIMES, 1.0).shape == (5, 3)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"times": [0.0, 1.0, 1.0, 2.0]}, r"times: must be strictly increasing.*times\[2\]"),
    ({"times": [0.0, 2.0, 1.0, 3.0]}, "times: must be strictly increasing"),
    ({"times": [[0.0, 1.0, 2.0, 3.0]]}, r"times: expected shape \(K,\)"),
    ({"times": [0.0, np.nan, 2.0, 3.0]}, "times: contains NaN"),
    ({"keys": np.zeros(3)}, r"keys: expected one key per time, shape \(4, \.\.\.\)"),
    ({"t": 3.5}, r"t: 3.5 is outside the key times \[0, 3\]"),
    ({"t": [-0.1, 1.0]}, "t: -0.1 is outside"),
    ({"derivative": 3}, "derivative: expected 0"),
])
def test_bad_input_names_the_argument(kwargs, match):
    args = {"keys": np.zeros(4), "times": [0.0, 1.0, 2.0, 3.0], "t": 1.0, "derivative": 0}
    args.update(kwargs)
    for f in (kf.linear, kf.cubic, kf.catmull_rom, kf.polynomial):
        with pytest.raises(ValueError, match=match):
            f(args["keys"], args["times"], args["t"], derivative=args["derivative"])


def test_other_errors():
    with pytest.raises(ValueError, match="times: need at least 2 keys"):
        kf.linear([1.0], [0.0], 0.0)
    with pytest.raises(ValueError, match="knots: expected one of"):
        kf.catmull_rom([0.0, 1.0], [0.0, 1.0], 0.5, knots="chordal")
    with pytest.raises(ValueError, match="tangents: expected the shape of keys"):
        kf.hermite([0.0, 1.0], [0.0], [0.0, 1.0], 0.5)
    with pytest.raises(ValueError, match=r"end_tangent: expected one value per channel, "
                       r"shape \(3,\), got \(2,\)"):
        kf.cubic(np.zeros((3, 3)), [0.0, 1.0, 2.0], 0.5, end_tangent=[1.0, 2.0])
    with pytest.raises(ValueError, match=r"start_tangent: .*got \(2, 3\)"):
        kf.cubic(np.zeros((3, 3)), [0.0, 1.0, 2.0], 0.5, start_tangent=np.zeros((2, 3)))
    with pytest.raises(ValueError, match="s: 1.5 is outside"):
        kf.bezier([[0.0], [1.0]], 1.5)
    with pytest.raises(ValueError, match="control_points: expected shape"):
        kf.bezier([1.0], 0.5)


# --------------------------------------------------------------------------- properties
_float = st.floats(-100, 100, allow_nan=False)


@settings(derandomize=True, max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(0.05, 3.0), _float), min_size=2, max_size=9),
       st.sampled_from(list(SCHEMES)))
def test_property_keys_are_hit_and_constants_kept(steps, name):
    times = np.cumsum([s for s, _ in steps])
    keys = np.array([v for _, v in steps])
    f = SCHEMES[name]
    assert np.allclose(f(keys, times, times), keys, atol=1e-7 * (1 + np.abs(keys).max()))
    t = np.linspace(times[0], times[-1], 37)
    assert np.allclose(f(np.full_like(keys, 2.5), times, t), 2.5)


@settings(derandomize=True, max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(0.05, 3.0), _float, _float), min_size=2, max_size=8),
       st.floats(-5, 5), st.floats(-5, 5))
def test_property_linear_schemes_reproduce_lines(steps, a, b):
    """Lines come back exactly from linear, cubic and time-knotted Catmull-Rom; every scheme
    commutes with adding the same offset to all keys (affine invariance)."""
    times = np.cumsum([s for s, _, _ in steps])
    t = np.linspace(times[0], times[-1], 29)
    line = a * times + b
    for f in (kf.linear, kf.cubic, kf.catmull_rom):
        assert np.allclose(f(line, times, t), a * t + b, atol=1e-8)
    keys = np.array([[x, y] for _, x, y in steps])
    for f in SCHEMES.values():
        shifted = f(keys + [a, b], times, t) - [a, b]
        assert np.allclose(shifted, f(keys, times, t), atol=1e-6 * (1 + np.abs(keys).max()))
