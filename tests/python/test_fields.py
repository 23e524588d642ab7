"""Fields: JSON dicts and files, the keyword models, expressions, callable fields and their
finite differences, and the errors of each."""
import json

import numpy as np
import pytest

import cdp

from conftest import ROOT


def test_keyword_models_match_their_json():
    pts = np.array([[0.3, -0.2, 0.9], [1.5, 0.1, 0.0], [0.0, 0.0, 0.0]])
    pairs = [
        (cdp.sphere(radius=1, center=(0, 0, 0)), {"type": "sphere", "radius": 1}),
        (cdp.torus(major_radius=1, minor_radius=0.3), {"type": "torus", "major_radius": 1, "minor_radius": 0.3}),
        (cdp.ellipsoid(radii=(1, 2, 0.5)), {"type": "ellipsoid", "radii": [1, 2, 0.5]}),
        (cdp.blobs([((0, 0, 0), 1), ((1.2, 0, 0), 1, 0.5)], threshold=0.3),
         {"type": "blobs", "threshold": 0.3,
          "blobs": [{"center": [0, 0, 0], "radius": 1}, {"center": [1.2, 0, 0], "radius": 1, "strength": 0.5}]}),
        (cdp.expression("x^2 + y^2 + z^2 - r^2", bounds=((-2, -2, -2), (2, 2, 2)), params={"r": 1.0}),
         {"type": "expression", "value": "x^2 + y^2 + z^2 - r^2", "params": {"r": 1.0},
          "bounds": [[-2, -2, -2], [2, 2, 2]]}),
    ]
    for field, spec in pairs:
        other = cdp.field_from_json(spec)
        assert field.type == spec["type"]
        assert np.array_equal(field.values(pts), other.values(pts))
        assert np.array_equal(field.bounds, other.bounds)


def test_field_values_gradients_hessians_of_a_sphere():
    s = cdp.sphere(radius=2, center=(1, 0, 0))
    p = np.array([[3.0, 0, 0], [1, 0, 4]])
    assert np.allclose(s.values(p), [0, 2])
    assert np.allclose(s.gradients(p), [[1, 0, 0], [0, 0, 1]])
    h = s.hessians(p)
    assert h.shape == (2, 3, 3)
    assert np.allclose(h[0], np.diag([0, 0.5, 0.5]))
    assert s.bounds.shape == (2, 3)
    assert s.lipschitz_bound == 1.0
    assert "sphere" in repr(s)
    s.reset_counts()
    s.values(p)
    s.gradients(p)
    assert s.counts() == {"value": 2, "value_gradient": 2, "gradient_hessian": 0, "total": 4}


def test_field_from_json_file_and_its_relative_paths(tmp_path):
    path = tmp_path / "torus.json"
    path.write_text(json.dumps({"type": "torus", "major_radius": 1, "minor_radius": 0.25}))
    field = cdp.field_from_json(path)  # os.PathLike
    assert field.type == "torus"
    assert cdp.field_from_json(str(path)).values([[1.25, 0, 0]])[0] == pytest.approx(0, abs=1e-15)
    assert "double_torus" in cdp.field_types()
    assert cdp.field_from_json({"type": "double_torus"}).type == "double_torus"


def test_numpy_values_in_dicts():
    field = cdp.field_from_json({"type": "sphere", "radius": np.float64(1.5), "center": np.zeros(3),
                                 "bounds": np.array([[-2, -2, -2], [2, 2, 2]], dtype=np.int32)})
    assert field.values([[1.5, 0, 0]])[0] == 0


@pytest.mark.parametrize("make, message", [
    (lambda: cdp.sphere(radius=-1), "cdp.sphere: radius: must be positive, found -1.000000"),
    (lambda: cdp.sphere(radius="big"), "cdp.sphere: radius: expected a number, found a string"),
    (lambda: cdp.sphere(radius=1, center=(0, 0)), "cdp.sphere: center: expected 3 numbers [x, y, z], found 2"),
    (lambda: cdp.torus(major_radius=1, minor_radius=2),
     "cdp.torus: minor_radius: must be smaller than major_radius (a ring torus)"),
    (lambda: cdp.blobs([], threshold=0.3), "cdp.blobs: blobs: needs at least one blob"),
    (lambda: cdp.blobs([((0, 0, 0), 1)], threshold=0.3, kernel="gauss"),
     'cdp.blobs: kernel: "gauss" is not one of "wyvill", "blinn"'),
    (lambda: cdp.expression("x^2 + q", bounds=((-1, -1, -1), (1, 1, 1))),
     "cdp.expression: value: expression: unknown name 'q' at position 7"),
    (lambda: cdp.field_from_json({"type": "sphere", "raduis": 1}),
     'cdp.field_from_json: raduis: unknown key (did you mean "radius"?)'),
    (lambda: cdp.field_from_json({"type": "cube"}), None),
    (lambda: cdp.field_from_json({"type": "sphere", "radius": float("nan")}),
     "cdp.field_from_json: radius: nan is not a finite number (JSON has none)"),
    (lambda: cdp.field_from_json({"type": "sphere", 1: 2}),
     "cdp.field_from_json: keys must be strings, found int 1"),
    (lambda: cdp.field_from_json(42), "cdp.field_from_json: expected a dict or a path to a JSON file, found int"),
])
def test_bad_fields_are_value_errors_with_the_library_message(make, message):
    with pytest.raises(ValueError) as e:
        make()
    if message is not None:
        assert str(e.value) == message
    else:
        assert 'unknown model type "cube"' in str(e.value)


def test_field_files_that_cannot_be_opened_are_os_errors(tmp_path):
    missing = tmp_path / "missing.json"
    with pytest.raises(FileNotFoundError) as e:
        cdp.field_from_json(missing)
    assert str(e.value) == f"{missing}: cannot open file"
    assert e.value.errno == 2
    with pytest.raises(IsADirectoryError) as e:
        cdp.field_from_json(tmp_path)
    assert str(e.value) == f"{tmp_path}: is a folder, not a JSON file"
    bad = tmp_path / "bad.json"
    bad.write_text('{"type": "sphere", "radius": 1, "radius": 2}')
    with pytest.raises(ValueError, match='appears twice in one object'):
        cdp.field_from_json(bad)
    vis = tmp_path / "vis.json"
    vis.write_text('{"type": "vis", "points": "nowhere.ply"}')
    with pytest.raises(FileNotFoundError) as e:
        cdp.field_from_json(vis)
    assert str(e.value) == f"{vis}: points: file not found: {tmp_path / 'nowhere.ply'}"


def test_points_must_be_n_by_3():
    s = cdp.sphere(radius=1)
    with pytest.raises(ValueError) as e:
        s.values([1, 2, 3])
    assert str(e.value) == "points: expected an array of shape (N, 3), found shape (3,)"
    assert s.values(np.empty((0, 3))).shape == (0,)


# --- callable fields ---

TORUS = "(sqrt(x^2 + y^2) - 1)^2 + z^2 - 0.09"
BOX = ((-1.5, -1.5, -0.5), (1.5, 1.5, 0.5))


def torus_numpy(p):
    return (np.sqrt(p[:, 0] ** 2 + p[:, 1] ** 2) - 1) ** 2 + p[:, 2] ** 2 - 0.09


def test_callable_field_values_are_one_vectorised_call():
    f = cdp.callable_field(torus_numpy, BOX, trace=False)
    assert isinstance(f, cdp.CallableField) and f.type == "python"
    p = np.random.default_rng(1).uniform(-1.5, 1.5, (1000, 3))
    assert np.array_equal(f.values(p), torus_numpy(p))
    assert f.python_calls == 1
    assert f.lipschitz_bound is None
    assert cdp.callable_field(torus_numpy, BOX, lipschitz=4, trace=False).lipschitz_bound == 4
    assert np.array_equal(f.bounds, np.array(BOX, dtype=float))


def test_central_differences_against_exact_expression_derivatives():
    """The callable field evaluates the expression itself, so what differs from the expression's
    exact (automatic) derivatives is the finite differences alone."""
    exact = cdp.expression(TORUS, bounds=BOX)
    approx = cdp.callable_field(exact.values, BOX, trace=False)
    p = np.random.default_rng(2).uniform(-1.2, 1.2, (400, 3)) * [1, 1, 0.3]
    # Away from the z axis, where sqrt(x^2 + y^2) is not differentiable.
    p = p[np.hypot(p[:, 0], p[:, 1]) > 0.3]
    g_exact, g = exact.gradients(p), approx.gradients(p)
    h_exact, h = exact.hessians(p), approx.hessians(p)
    g_err = np.linalg.norm(g - g_exact, axis=1) / np.maximum(np.linalg.norm(g_exact, axis=1), 1)
    h_err = np.linalg.norm(h - h_exact, axis=(1, 2)) / np.maximum(np.linalg.norm(h_exact, axis=(1, 2)), 1)
    # Measured on 2000 such points (python/README.md): gradient median 6e-10, max 7e-9;
    # Hessian median 4e-8, max 1e-6 (relative to max(|exact|, 1)).
    assert np.median(g_err) < 3e-9 and g_err.max() < 3e-8
    assert np.median(h_err) < 3e-7 and h_err.max() < 1e-5
    assert np.allclose(h, np.transpose(h, (0, 2, 1)))
    # One call per batch for each derivative kind, with 7 points a point for the gradient and 25
    # for the Hessian.
    sizes = []

    def recorded(q):
        sizes.append(len(q))
        return exact.values(q)

    counted = cdp.callable_field(recorded, BOX, trace=False)
    assert np.array_equal(counted.gradients(p[:3]), approx.gradients(p[:3]))
    assert np.array_equal(counted.hessians(p[:3]), approx.hessians(p[:3]))
    assert counted.python_calls == 2 and sizes == [3 * 7, 3 * 25]


def test_user_derivatives_are_used_when_given():
    exact = cdp.expression(TORUS, bounds=BOX)
    p = np.random.default_rng(3).uniform(-1.2, 1.2, (50, 3)) * [1, 1, 0.3]
    both = cdp.callable_field(exact.values, BOX, gradient=exact.gradients, hessian=exact.hessians)
    assert np.array_equal(both.gradients(p), exact.gradients(p))
    assert np.array_equal(both.hessians(p), exact.hessians(p))
    grad_only = cdp.callable_field(exact.values, BOX, gradient=exact.gradients)
    assert np.array_equal(grad_only.gradients(p), exact.gradients(p))
    h_err = np.abs(grad_only.hessians(p) - exact.hessians(p)).max()
    assert h_err < 1e-6


def test_callable_field_errors():
    with pytest.raises(ValueError) as e:
        cdp.callable_field(3, BOX)
    assert str(e.value) == "cdp.callable_field: f must be callable, found int"
    with pytest.raises(ValueError) as e:
        cdp.callable_field(torus_numpy, ((1, 1, 1), (0, 2, 2)))
    assert str(e.value) == "cdp.callable_field: bounds: every min must be below its max, and all finite"
    with pytest.raises(ValueError) as e:
        cdp.callable_field(torus_numpy, BOX, gradient_step=-1)
    assert str(e.value) == "cdp.callable_field: gradient_step must be a positive number, not -1.0"
    wrong = cdp.callable_field(lambda p: p, BOX)
    with pytest.raises(ValueError) as e:
        wrong.values(np.zeros((4, 3)))
    assert str(e.value) == "callable field: f returned shape (4, 3) for 4 points; expected (4,)"
    bad_gradient = cdp.callable_field(torus_numpy, BOX, gradient=lambda p: p[:, 0])
    with pytest.raises(ValueError) as e:
        bad_gradient.gradients(np.zeros((1, 3)))
    assert str(e.value) == "callable field: gradient returned shape (1,) for 1 points; expected (1, 3)"

    def raises(p):
        raise ZeroDivisionError("from the user's function")

    with pytest.raises(ZeroDivisionError, match="from the user's function"):
        cdp.callable_field(raises, BOX).values(np.zeros((2, 3)))
