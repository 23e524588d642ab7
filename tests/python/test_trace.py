"""cdp.trace: numpy functions of points become expression fields (python/cdp/trace.py)."""
import math

import numpy as np
import pytest

import cdp
from conftest import topology

BOX = ((-1.1, -1.1, -1.1), (1.1, 1.1, 1.1))


def points(n=300, seed=20261129):
    return np.random.default_rng(seed).uniform(-1.1, 1.1, (n, 3))


def gyroid_ball(p):
    """The issue's model: a gyroid clipped by a ball, as people write it in numpy."""
    q = 6 * p
    g = np.sin(q[:, 0]) * np.cos(q[:, 1]) + np.sin(q[:, 1]) * np.cos(q[:, 2]) + np.sin(q[:, 2]) * np.cos(q[:, 0])
    return np.maximum(g / 6, np.linalg.norm(p, axis=1) - 1)


def rounded_box(p):
    q = np.abs(p) - np.array([0.6, 0.4, 0.3])
    return np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0) - 0.15


def smooth_union(p, k=0.3):
    a = np.linalg.norm(p - np.array([0.3, 0, 0]), axis=1) - 0.5
    b = np.linalg.norm(p + np.array([0.3, 0, 0]), axis=1) - 0.5
    h = np.clip(0.5 + 0.5 * (b - a) / k, 0, 1)
    return b * (1 - h) + a * h - k * h * (1 - h)


def test_a_clipped_gyroid_callable_meshes_along_its_creases():
    """The black box fails here (fronts meet where the gyroid's sheets cut the sphere at a
    sharp angle); traced, the max is a branch point and its creases are followed. Marching
    Cubes on the black box (values only) gives the reference topology, the same at cells
    0.04, 0.02 and 0.015."""
    black_box = cdp.callable_field(gyroid_ball, BOX, trace=False)
    V, F, _, _ = cdp.marching_cubes(black_box, cell=0.02)
    reference = topology(V, F)
    assert reference == (1, 13, True)
    field = cdp.callable_field(gyroid_ball, BOX)
    assert not isinstance(field, cdp.CallableField) and field.type == "expression"
    for options in (dict(factor=3), dict(tolerance=1e-3)):
        V, F, _, stats = cdp.polygonize(field, **options)
        assert topology(V, F) == reference
        assert stats["creases"]["followed"] and stats["creases"]["curves"] >= 1
        assert stats["creases"]["fallback"] == ""
        assert stats["min_angle_degrees"] >= 5
        assert np.abs(gyroid_ball(V)).max() < 1e-6


def finite_gradients(f, p, h=1e-6):
    return np.stack([(f(p + h * e) - f(p - h * e)) / (2 * h) for e in np.eye(3)], axis=1)


@pytest.mark.parametrize("function", [gyroid_ball, rounded_box, smooth_union])
def test_traced_values_and_derivatives_are_the_functions(function):
    field = cdp.trace(function, BOX)
    p = points()
    assert np.allclose(field.values(p), function(p), rtol=0, atol=1e-12)
    if function is rounded_box:  # sqrt(0) inside the core box: no derivative there, as written
        p = p[(np.abs(p) > [0.6, 0.4, 0.3]).any(axis=1)]
    g = field.gradients(p)
    assert np.allclose(g, finite_gradients(function, p), rtol=0, atol=1e-6)
    H = field.hessians(p)
    fd = np.stack([(field.gradients(p + 1e-5 * e) - field.gradients(p - 1e-5 * e)) / 2e-5 for e in np.eye(3)], axis=2)
    assert np.allclose(H, fd, rtol=0, atol=1e-4)


def test_a_value_used_twice_is_computed_once():
    """The smooth union's clamp h is used three times: one definition, so one clamp (two branch
    points, which the mesher finds C1) instead of three independent ones."""
    formula, define = cdp.trace_formula(smooth_union)
    text = formula + " " + " ".join(define.values())
    assert text.count("min(") == 1 and text.count("max(") == 1
    V, F, _, stats = cdp.polygonize(cdp.trace(smooth_union, BOX), factor=3)
    assert topology(V, F) == (1, 0, True)
    assert stats["creases"]["curves"] == 0  # C1 seams are not creases


def test_rounded_box_traced_is_smooth_and_exact():
    V, F, _, stats = cdp.polygonize(cdp.trace(rounded_box, BOX), factor=3)
    assert topology(V, F) == (1, 0, True)
    assert stats["creases"]["curves"] == 0
    assert stats["min_angle_degrees"] >= 20


def _running_min(p):
    """A union written as a loop from an empty start, as people write it."""
    d = np.full_like(p[:, 0], np.inf)
    for c in ((0.3, 0, 0), (-0.3, 0, 0), (0, 0.4, 0)):
        d = np.minimum(d, np.linalg.norm(p - np.array(c), axis=1) - 0.35)
    return d


def _forms():
    M = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 2.0]])
    return {
        "unpack_T": lambda p: (lambda x, y, z: x * x + y * y + z * z - 1)(*p.T),
        "stack": lambda p: np.linalg.norm(np.stack([p[:, 0], 2 * p[:, 1], p[:, 2]], axis=-1), axis=-1) - 1,
        "column_stack": lambda p: np.sum(np.column_stack([p[:, 1], p[:, 2]]) ** 2, axis=1) - 0.25,
        "matmul": lambda p: np.linalg.norm(p @ M, axis=1) - 1,
        "dot": lambda p: np.dot(p, np.array([1.0, 2.0, 3.0])) - 0.5,
        "reduce": lambda p: np.maximum.reduce(np.abs(p), axis=1) - 0.8,
        "amax_amin": lambda p: np.amax(np.abs(p), axis=1) + 0.1 * np.amin(p, axis=1) - 0.8,
        "mean_prod": lambda p: p.mean(axis=1) + 0.1 * p.prod(axis=1) - 0.1,
        "ellipsis_fancy": lambda p: np.sum((p[..., [2, 0, 1]] - p) ** 2, axis=-1) + p[..., 0] - 0.3,
        "functions": lambda p: (np.hypot(p[:, 0], p[:, 1]) + np.arctan2(p[:, 1], p[:, 0]) * 0.1
                                + np.exp(-np.square(p[:, 2])) + np.log(2 + p[:, 0]) - 1.5),
        "clip_one_side": lambda p: np.clip(p[:, 0], None, 0.5) + np.clip(p[:, 1], -0.2, None) + np.fmin(p[:, 2], 0.3),
        "mod_floor": lambda p: np.mod(p[:, 0], 0.5) + np.floor_divide(p[:, 1], 0.5) * 0.01 + p[:, 2] % 0.3 - 0.4,
        "power_reciprocal": lambda p: (p[:, 0] ** 4 + np.power(np.abs(p[:, 1]), 3.0) + np.reciprocal(2 + p[:, 2])
                                       - np.float_power(2.0, p[:, 0]) + np.tan(p[:, 2] * 0.5)),
        "constants_1x3": lambda p: np.linalg.norm(p - np.array([[0.1, 0.2, 0.3]]), axis=1) - 0.5,
        "running_min_from_inf": lambda p: _running_min(p),
        "zeros_and_ones_like": lambda p: np.zeros_like(p[:, 0]) + np.ones_like(p[:, 1]) * p[:, 2] - 0.3,
        "keepdims_column": lambda p: (np.sqrt(np.sum(p * p, axis=1, keepdims=True)) - p[:, 0:1] * 0.5 - 0.7),
        "reduce_keepdims": lambda p: np.maximum.reduce(np.abs(p), axis=-1, keepdims=True)[:, 0] - 0.8,
    }


@pytest.mark.parametrize("name", sorted(_forms()))
def test_the_numpy_forms_people_write_trace(name):
    f = _forms()[name]
    field = cdp.trace(f, BOX)
    p = points()
    assert np.allclose(field.values(p), f(p).reshape(-1), rtol=1e-12, atol=1e-12)


def test_a_long_sum_built_in_a_loop_traces():
    """200 blobs added one by one: a chain of 200 additions, written as one flat sum."""
    centres = np.random.default_rng(200).uniform(-0.8, 0.8, (200, 3))

    def blobs(p):
        total = 0
        for c in centres:
            total = total + np.exp(-20 * np.sum((p - c) ** 2, axis=1))
        return 0.5 - total

    field = cdp.trace(blobs, BOX)
    p = points()
    assert np.allclose(field.values(p), blobs(p), rtol=0, atol=1e-12)


def test_np_where_choosing_the_smaller_or_larger_of_what_it_compares_is_a_min_or_max():
    """np.where(u < v, u, v) is how some SDF code writes min and max (and np.where(d > 0, d, 0)
    a rounded box's outside part): traced as the branch point it is, its creases are followed."""
    def box(p):
        a = np.abs(p)
        m = np.where(a[:, 0] > a[:, 1], a[:, 0], a[:, 1])
        return np.where(m >= a[:, 2], m, a[:, 2]) - 0.8

    def rounded_box_where(p):
        q = np.abs(p) - np.array([0.6, 0.4, 0.3])
        return np.linalg.norm(np.where(q > 0, q, 0), axis=1) + np.where(0 < q.max(axis=1), 0, q.max(axis=1)) - 0.15

    def two_balls(p):
        a = np.linalg.norm(p - [0.3, 0, 0], axis=1) - 0.5
        b = np.linalg.norm(p + [0.3, 0, 0], axis=1) - 0.5
        return np.where(b <= a, b, a)

    def constant_column(p):  # comparisons of numbers (zeros_like's) decide as numpy does, ties too
        q = np.stack([p[:, 0], np.zeros_like(p[:, 0])], axis=1)
        return np.where(q[:, 1] <= 0, np.linalg.norm(p, axis=1), p[:, 0]) - np.where(q[:, 1] < 0, 1.0, 0.5)

    assert cdp.trace_formula(constant_column)[0] == "sqrt(x * x + y * y + z * z) - 0.5"
    assert cdp.trace_formula(box) == ("max(abs(x), abs(y), abs(z)) - 0.8", {})
    assert cdp.trace_formula(two_balls)[0].startswith("min(")
    p = points()
    for f in (box, rounded_box_where, two_balls):
        field = cdp.trace(f, BOX)
        assert np.allclose(field.values(p), f(p), rtol=0, atol=1e-12)
        assert np.allclose(field.values(p), {box: lambda q: np.abs(q).max(axis=1) - 0.8,
                                             rounded_box_where: rounded_box, two_balls: lambda q: np.minimum(
            np.linalg.norm(q - [0.3, 0, 0], axis=1), np.linalg.norm(q + [0.3, 0, 0], axis=1)) - 0.5}[f](p),
                           rtol=0, atol=1e-12)
    V, F, _, stats = cdp.polygonize(cdp.trace(box, BOX), factor=2)
    assert stats["creases"]["followed"] and stats["creases"]["curves"] == 12
    assert topology(V, F) == (1, 0, True)


@pytest.mark.parametrize("function", [
    lambda p: np.sinh(p[:, 1]) * np.cosh(p[:, 2]) + p[:, 0],
    lambda p: np.log10(2 + p[:, 0]) + np.log2(2 + p[:, 1]) + np.log1p(0.5 + p[:, 2]),
    lambda p: np.exp2(p[:, 0]) + np.expm1(p[:, 1]) + np.radians(p[:, 2]) + np.degrees(p[:, 0] * p[:, 1]) / 90,
])
def test_functions_written_with_the_expressions_own_trace_with_their_derivatives(function):
    field = cdp.trace(function, BOX)
    p = points()
    assert np.allclose(field.values(p), function(p), rtol=0, atol=1e-12)
    assert np.allclose(field.gradients(p), finite_gradients(function, p), rtol=0, atol=1e-6)


def test_a_repetition_with_np_round_traces():
    """fogleman/sdf's repeat (p - spacing * np.clip(np.round(p / spacing), -count, count)): np.round
    is the expression's round, whose halves go away from zero where numpy's go to the even
    neighbour; the check against the function meets any difference that makes."""
    def balls(p):
        q = p - 0.75 * np.clip(np.round(p / 0.75), -1, 1)
        return np.linalg.norm(q, axis=1) - 0.25

    field = cdp.trace(balls, BOX)
    assert "round(" in cdp.trace_formula(balls)[1]["_t0"] or "round(" in cdp.trace_formula(balls)[0]
    p = points()
    assert np.allclose(field.values(p), balls(p), rtol=0, atol=1e-12)
    V, F, _, _ = cdp.polygonize(field, factor=2)
    assert topology(V, F)[0] == 27
    with pytest.raises(cdp.TraceError, match="decimals=0"):
        cdp.trace(lambda q: np.round(q[:, 0], 2) - 0.5, BOX)


@pytest.mark.parametrize("function, words", [
    (lambda p: np.where(p[:, 0] > 0, p[:, 0], -p[:, 0]) - 0.5, "compares values of the points"),
    (lambda p: np.where(np.logical_and(p[:, 0] > 0, p[:, 1] > 0), p[:, 0], p[:, 1]), "compares values of the points"),
    (lambda p: np.where(p[:, 0] > p[:, 1], p[:, 2], p[:, 1]), "compares values of the points"),
    (lambda p: np.linalg.norm(p, axis=1) - 1 if (p[:, 0] > 0).all() else p[:, 0], "compares values of the points"),
    (lambda p: p[:, 0] if p[:, 1] else p[:, 2], "decides on the points' values"),
    (lambda p: p[:, 0] + np.ones((5, 1)), "a constant of shape"),
    (lambda p: np.zeros(len(p)) + p[:, 0], "number of points"),
    (lambda p: p[:, 0] + 0 * p.shape[0], "number of points"),
    (lambda p: np.array([math.sqrt(q @ q) for q in p]) - 1, "iterates over the points"),
    (lambda p: p[:10, 0], "indexes the points' axis"),
    (lambda p: p, "more than one value per point"),
    (lambda p: 1.0, "returns float"),
    (lambda p: np.cbrt(p[:, 0]), "np.cbrt cannot be traced"),
    (lambda p: np.tanh(p[:, 0]), "np.tanh cannot be traced"),
    (lambda p: p[:, 0] + np.inf, "uses the constant inf"),
    (lambda p: p[:, 0] + np.nan, "uses the constant nan"),
    (lambda p: np.asarray(p)[:, 0], "plain numpy array"),
    (lambda p: np.linalg.norm(p, axis=1) - 1 if isinstance(p, np.ndarray) else p[:, 0], "where the function gives"),
])
def test_what_cannot_be_traced_says_why_and_stays_a_black_box(function, words):
    with pytest.raises(cdp.TraceError, match=words.replace("(", r"\(")):
        cdp.trace(function, BOX)
    field = cdp.callable_field(function, BOX)
    assert isinstance(field, cdp.CallableField)


def test_callable_field_checks_its_arguments_before_tracing():
    with pytest.raises(ValueError, match="gradient_step must be a positive number"):
        cdp.callable_field(rounded_box, BOX, gradient_step=-1)
    # A gradient given: the black box, which calls it.
    field = cdp.callable_field(rounded_box, BOX, gradient=lambda p: finite_gradients(rounded_box, p))
    assert isinstance(field, cdp.CallableField)
