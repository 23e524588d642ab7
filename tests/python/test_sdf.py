"""cdp.sdf: distances of the primitives against closed forms, transforms, operators, exact
derivatives against finite differences, JSON round trips, bounds and errors, and meshing
fogleman/sdf's README model."""
import json
import math
import subprocess

import numpy as np
import pytest

import cdp
from cdp.sdf import (ORIGIN, SDF, UP, X, Y, Z, Vector, bend, blend, box, capped_cone, capped_cylinder, capsule,
                     cylinder, difference, dilate, ellipsoid, erode, intersection, negate, octahedron, orient, plane,
                     repeat, rotate, rounded_box, rounded_cylinder, scale, shell, slab, sphere, tetrahedron, torus,
                     translate, twist, union)

from conftest import program, topology

def points(n=400, lo=-2.0, hi=2.0, seed=20240611):
    """n random points in the cube [lo, hi]^3, the same in every run (of one test or all)."""
    return np.random.default_rng(seed).uniform(lo, hi, size=(n, 3))


def length(v):
    return np.linalg.norm(v, axis=-1)


def exact_box(p, half):
    q = np.abs(p) - half
    return length(np.maximum(q, 0)) + np.minimum(q.max(axis=1), 0)


def segment_distance(p, a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    ba = b - a
    h = np.clip(((p - a) @ ba) / (ba @ ba), 0, 1)
    return length(p - a - h[:, None] * ba)


def rotation(angle, axis):
    """The right-handed rotation matrix by angle about axis."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


# --- primitives -------------------------------------------------------------------------------

def test_sphere_torus_capsule_plane_are_their_closed_forms():
    p = points()
    c = np.array([0.3, -0.2, 0.5])
    assert np.allclose(sphere(0.8, center=c)(p), length(p - c) - 0.8, atol=1e-14)
    assert np.allclose(sphere()(p), length(p) - 1, atol=1e-14)
    ring = np.hypot(p[:, 0], p[:, 1])
    assert np.allclose(torus(1, 0.25)(p), np.hypot(ring - 1, p[:, 2]) - 0.25, atol=1e-14)
    a, b = (-0.5, 0.2, 0.1), (0.7, -0.4, 0.9)
    assert np.allclose(capsule(a, b, 0.3)(p), segment_distance(p, a, b) - 0.3, atol=1e-13)
    assert np.allclose(capsule(-X, X, 0.2)(p), segment_distance(p, -X, X) - 0.2, atol=1e-14)
    n = np.array([1.0, 2.0, -2.0]) / 3
    q = np.array([0.1, 0.2, 0.3])
    # fogleman/sdf's convention: solid on the side the normal points to
    assert np.allclose(plane(n, q)(p), (q - p) @ n, atol=1e-14)
    assert np.allclose(plane()(p), -p[:, 2], atol=0)
    assert np.allclose(cylinder(0.5)(p), ring - 0.5, atol=1e-14)


def test_box_is_exact_inside_and_off_its_faces_and_a_bound_elsewhere():
    half = np.array([0.5, 0.75, 1.0])
    model = box((1.0, 1.5, 2.0))
    p = points(2000)
    value, exact = model(p), exact_box(p, half)
    outside_axes = (np.abs(p) > half).sum(axis=1)
    face = outside_axes <= 1  # inside, or the nearest point on a face
    assert face.sum() > 300 and (~face).sum() > 300
    assert np.allclose(value[face], exact[face], atol=1e-14)
    assert np.all(value[~face] <= exact[~face] + 1e-14) and np.all(value[~face] > 0)
    # corners a, b and a center are the same box
    moved = box((1.0, 1.5, 2.0), center=(1, 2, 3))
    assert np.allclose(moved(p + [1, 2, 3]), value, atol=1e-14)
    assert np.allclose(box(a=(0, 0.5, 1), b=(1, 2, 3))(p + [0.5, 1.25, 2]), value, atol=1e-14)
    assert np.allclose(box(2)(p), np.abs(p).max(axis=1) - 1, atol=0)
    assert model.bounds == ((-0.5, -0.75, -1.0), (0.5, 0.75, 1.0))


def test_rounded_box_and_rounded_cylinder_are_quilez_exact_distances():
    p = points(2000)
    size, r = np.array([1.0, 1.6, 2.2]), 0.2
    q = np.abs(p) - size / 2 + r
    quilez = length(np.maximum(q, 0)) + np.minimum(q.max(axis=1), 0) - r
    model = rounded_box(size, r)
    assert np.allclose(model(p), quilez, atol=1e-14)
    # the exact distance: the box of the core grown by r
    assert np.allclose(model(p), exact_box(p, size / 2 - r) - r, atol=1e-14)
    # finite gradient everywhere, also deep inside where Quilez's sqrt(0) has none
    inner = points(50, -0.2, 0.2)
    g = model.field().gradients(inner)
    assert np.all(np.isfinite(g)) and np.allclose(np.linalg.norm(g, axis=1), 1)
    ra, rb, h = 0.8, 0.15, 1.2
    d = np.stack([np.hypot(p[:, 0], p[:, 1]) - ra + rb, np.abs(p[:, 2]) - h / 2 + rb], axis=1)
    quilez = np.minimum(d.max(axis=1), 0) + length(np.maximum(d, 0)) - rb
    assert np.allclose(rounded_cylinder(ra, rb, h)(p), quilez, atol=1e-14)


def test_capped_cylinder_and_cone_are_exact_off_their_rims():
    a, b, r = np.array([0.2, -0.3, -0.6]), np.array([-0.1, 0.4, 0.8]), 0.5
    axis = (b - a) / np.linalg.norm(b - a)
    half = np.linalg.norm(b - a) / 2
    p = points(2000)
    t = (p - (a + b) / 2) @ axis
    rho = length(p - (a + b) / 2 - t[:, None] * axis)
    d = np.stack([rho - r, np.abs(t) - half], axis=1)
    exact = length(np.maximum(d, 0)) + np.minimum(d.max(axis=1), 0)
    value = capped_cylinder(a, b, r)(p)
    rim = (d > 0).all(axis=1)
    assert rim.sum() > 100 and (~rim).sum() > 100
    assert np.allclose(value[~rim], exact[~rim], atol=1e-13)
    assert np.all(value[rim] <= exact[rim] + 1e-13)
    # a cone from radius 0.6 at a to 0.2 at b: zero on its side, the distance to the side's
    # line off it (in the half-plane of the axis) where that is nearest
    ra, rb = 0.6, 0.2
    cone = capped_cone(a, b, ra, rb)
    radius = ra + (rb - ra) * (t + half) / (2 * half)
    on_side = np.abs(t) < half * 0.9
    surface = (a + b) / 2 + t[:, None] * axis + radius[:, None] * np.cross(axis, [0, 0, 1]) / np.linalg.norm(
        np.cross(axis, [0, 0, 1]))
    assert np.abs(cone(surface[on_side])).max() < 1e-13
    slope = (rb - ra) / (2 * half)
    side = (rho - radius) / math.sqrt(1 + slope * slope)
    # the foot of the perpendicular to the side line lies between the caps
    foot_t = t - side * (-slope) / math.sqrt(1 + slope * slope)
    clear = (np.abs(foot_t) < half) & (np.abs(t) < half) & (side > 0)
    assert clear.sum() > 100
    assert np.allclose(cone(p)[clear], side[clear], atol=1e-13)
    assert cone(np.array([(a + b) / 2]))[0] < 0


def test_ellipsoid_octahedron_tetrahedron_slab():
    p = points()
    r = np.array([0.6, 1.0, 1.4])
    k0, k1 = length(p / r), length(p / (r * r))
    assert np.allclose(ellipsoid(r)(p), k0 * (k0 - 1) / k1, atol=1e-14)
    assert np.allclose(octahedron(1)(p), (np.abs(p).sum(axis=1) - 1) / math.sqrt(3), atol=1e-14)
    x, y, z = p.T
    assert np.allclose(tetrahedron(1)(p), (np.maximum(np.abs(x + y) - z, np.abs(x - y) + z) - 1) / math.sqrt(3),
                       atol=1e-14)
    s = slab(x0=-0.5, z1=0.25)
    assert np.allclose(s(p), np.maximum(-0.5 - x, z - 0.25), atol=0)
    assert s.bounds == ((-0.5, -math.inf, -math.inf), (math.inf, math.inf, 0.25))


# --- transforms ---------------------------------------------------------------------------------

def test_transforms_substitute_the_coordinates():
    p = points()
    base = box((0.4, 0.8, 1.2)) | capsule(ORIGIN, (0.5, 0.3, 0), 0.1)
    offset = np.array([0.3, -1.0, 0.5])
    assert np.allclose(base.translate(offset)(p), base(p - offset), atol=1e-14)
    assert np.allclose(base.scale(2)(p), 2 * base(p / 2), atol=1e-14)
    assert np.allclose(base.scale((1, 2, 3))(p), base(p / [1, 2, 3]), atol=1e-14)
    R = rotation(0.7, (1, 2, 3))
    # rotated shape: its value at p is the original's at R^T p (p rotated back)
    assert np.allclose(base.rotate(0.7, (1, 2, 3))(p), base(p @ R), atol=1e-13)
    # composed: one affine transform, the same values
    chained = base.rotate(0.7, (1, 2, 3)).translate(offset).scale(1.5)
    assert np.allclose(chained(p), 1.5 * base(((p / 1.5) - offset) @ R), atol=1e-13)
    one = box((0.4, 0.8, 1.2)).rotate(0.7, (1, 2, 3)).translate(offset).scale(1.5)
    assert len(one.formula()[1]) == 3  # x, y, z of the one composed transform
    # right-hand rule: a quarter turn about Z takes X to Y; orient takes Z onto the axis
    arm = capsule(ORIGIN, X, 0.1)
    assert np.allclose(arm.rotate(math.pi / 2)(p), capsule(ORIGIN, Y, 0.1)(p), atol=1e-14)
    assert np.allclose(capsule(ORIGIN, Z, 0.1).orient(X)(p), arm(p), atol=1e-14)
    assert np.allclose(capsule(ORIGIN, Z, 0.1).orient(-Y)(p), capsule(ORIGIN, -Y, 0.1)(p), atol=1e-14)
    tilted = np.array([1.0, -2.0, 0.5])
    assert np.allclose(capsule(ORIGIN, Z, 0.1).orient(tilted)(p),
                       capsule(ORIGIN, tilted / np.linalg.norm(tilted), 0.1)(p), atol=1e-14)
    # quarter turns are exact permutations: no 6e-17 terms in the formula
    assert cylinder(0.5).orient(X).formula()[0] == "hypot((-z), y) - 0.5"
    # module functions are the methods
    assert np.array_equal(translate(base, offset)(p), base.translate(offset)(p))
    assert np.array_equal(rotate(base, 0.7, (1, 2, 3))(p), base.rotate(0.7, (1, 2, 3))(p))
    assert np.array_equal(orient(base, X)(p), base.orient(X)(p))
    assert np.array_equal(scale(base, 2)(p), base.scale(2)(p))


def test_boxes_of_transforms_operations_and_modifiers():
    b = box((1, 2, 4))
    assert np.allclose(b.rotate(math.pi / 2).bounds, ((-1, -0.5, -2), (1, 0.5, 2)))
    assert b.translate((1, 0, 0)).bounds == ((0.5, -1, -2), (1.5, 1, 2))
    assert b.scale(2).bounds == ((-1, -2, -4), (1, 2, 4))
    c = cylinder(0.5).orient(X)
    assert c.bounds == ((-math.inf, -0.5, -0.5), (math.inf, 0.5, 0.5))
    assert (sphere(1) & c).bounds == ((-1, -0.5, -0.5), (1, 0.5, 0.5))
    assert (sphere(1) - box(4)).bounds == sphere(1).bounds
    assert (sphere(1) | sphere(1, center=(3, 0, 0))).bounds == ((-1, -1, -1), (4, 1, 1))
    assert union(sphere(1), sphere(1, center=(3, 0, 0)), k=0.5).bounds == ((-1.5, -1.5, -1.5), (4.5, 1.5, 1.5))
    assert sphere(1).shell(0.2).bounds == ((-1.1,) * 3, (1.1,) * 3)
    assert sphere(1).dilate(0.5).bounds == ((-1.5,) * 3, (1.5,) * 3)
    assert sphere(1).erode(0.5).bounds == sphere(1).bounds
    assert sphere(0.2).repeat(1, count=2).bounds == ((-2.2,) * 3, (2.2,) * 3)
    assert sphere(0.2).repeat((1, 0, 0)).bounds == ((-math.inf, -0.2, -0.2), (math.inf, 0.2, 0.2))
    assert np.allclose(box((1, 1, 2)).twist(1).bounds, ((-math.sqrt(0.5),) * 2 + (-1,), (math.sqrt(0.5),) * 2 + (1,)))
    assert negate(sphere(1)).bounds[0][0] == -math.inf
    # every point inside a model is inside its box
    model = (rounded_box((1, 1.5, 0.5), 0.1).rotate(0.4, (1, 1, 0)).translate((0.2, 0, 0))
             | torus(0.6, 0.1).orient((1, 1, 1))).union(sphere(0.3, center=(0.8, 0.8, 0)), k=0.3)
    p = points(20000, -1.5, 1.5)
    lo, hi = np.array(model.bounds)
    inside = p[model(p) < 0]
    assert len(inside) > 500 and np.all((inside >= lo) & (inside <= hi))


def test_repeat_twist_bend():
    p = points()
    s = sphere(0.3)
    rep = s.repeat((1, 0, 2))
    q = p.copy()
    q[:, 0] -= np.round(q[:, 0])
    q[:, 2] -= 2 * np.round(q[:, 2] / 2)
    assert np.allclose(rep(p), s(q), atol=1e-14)
    counted = s.repeat(1, count=1)
    idx = np.clip(np.round(p), -1, 1)
    assert np.allclose(counted(p), s(p - idx), atol=1e-14)
    # padding: the nearest of the neighbouring copies, continuous across the cell edge
    big = sphere(0.7).repeat((2, 0, 0), padding=1)
    x = np.array([[0.99, 0.5, 0], [1.01, 0.5, 0]])
    assert np.allclose(big(x), length(x - [0, 0, 0]).clip(max=length(x - [2, 0, 0])) - 0.7, atol=1e-14)
    assert abs(big(x)[0] - big(x)[1]) < 0.03
    assert np.array_equal(repeat(s, 1, count=1)(p), counted(p))
    # padding with a count: the union of the copies, which may overlap (no round in the formula)
    overlapping = sphere(0.3).repeat(0.5, count=(1, 2, 0), padding=1)
    centers = [(0.5 * i, 0.5 * j, 0) for i in range(-1, 2) for j in range(-2, 3)]
    assert np.allclose(overlapping(p), np.min([length(p - c) for c in centers], axis=0) - 0.3, atol=1e-14)
    assert "round" not in str(overlapping.formula())
    assert overlapping.bounds == ((-0.8, -1.3, -0.3), (0.8, 1.3, 0.3))
    b = box((0.5, 0.2, 1.0))
    c, sn = np.cos(0.8 * p[:, 2]), np.sin(0.8 * p[:, 2])
    q = np.stack([c * p[:, 0] - sn * p[:, 1], sn * p[:, 0] + c * p[:, 1], p[:, 2]], axis=1)
    assert np.allclose(twist(b, 0.8)(p), b(q), atol=1e-14)
    c, sn = np.cos(0.5 * p[:, 0]), np.sin(0.5 * p[:, 0])
    q = np.stack([c * p[:, 0] - sn * p[:, 1], sn * p[:, 0] + c * p[:, 1], p[:, 2]], axis=1)
    assert np.allclose(bend(b, 0.5)(p), b(q), atol=1e-14)


# --- operators ------------------------------------------------------------------------------------

def test_operators_are_min_max_and_the_modifiers_their_formulas():
    p = points()
    a, b, c = sphere(1), box(1.5, center=(0.5, 0, 0)), torus(1, 0.3)
    va, vb, vc = a(p), b(p), c(p)
    assert np.array_equal((a | b)(p), np.minimum(va, vb))
    assert np.array_equal((a & b)(p), np.maximum(va, vb))
    assert np.array_equal((a - b)(p), np.maximum(va, -vb))
    assert np.array_equal((a | b | c)(p), np.minimum(np.minimum(va, vb), vc))
    assert np.array_equal(union(a, b, c)(p), (a | b | c)(p))
    assert np.array_equal(intersection(a, b, c)(p), np.maximum(np.maximum(va, vb), vc))
    assert np.array_equal(difference(a, b, c)(p), np.maximum(np.maximum(va, -vb), -vc))
    assert np.array_equal(a.difference(b)(p), (a - b)(p))
    assert np.allclose(shell(a, 0.2)(p), np.abs(va) - 0.1, atol=1e-15)
    assert np.allclose(dilate(a, 0.2)(p), va - 0.2, atol=1e-15)
    assert np.allclose(erode(a, 0.2)(p), va + 0.2, atol=1e-15)
    assert np.allclose(negate(a)(p), -va, atol=0)
    assert np.allclose((-a)(p), -va, atol=0)
    assert np.allclose(blend(a, b, k=0.25)(p), 0.75 * va + 0.25 * vb, atol=1e-15)
    # n-ary folds stay flat: one min of three
    assert (a | b | c).formula()[0].startswith("min(") and (a | b | c).formula()[0].count("min(") == 1


def quilez(kind, d1, d2, k):
    if kind == "union":
        h = np.clip(0.5 + 0.5 * (d2 - d1) / k, 0, 1)
        return d2 + (d1 - d2) * h - k * h * (1 - h)
    if kind == "intersection":
        h = np.clip(0.5 - 0.5 * (d2 - d1) / k, 0, 1)
        return d2 + (d1 - d2) * h + k * h * (1 - h)
    h = np.clip(0.5 - 0.5 * (d2 + d1) / k, 0, 1)
    return d1 + (-d2 - d1) * h + k * h * (1 - h)


@pytest.mark.parametrize("kind", ["union", "intersection", "difference"])
def test_smooth_operations_are_quilez_polynomial_and_c1(kind):
    a, b, k = sphere(0.8), box(1.2, center=(0.6, 0.3, 0)), 0.3
    op = {"union": union, "intersection": intersection, "difference": difference}[kind]
    model = op(a, b, k=k)
    p = points(2000)
    va, vb = a(p), b(p)
    assert np.allclose(model(p), quilez(kind, va, vb, k), atol=1e-14)
    # the same by method and by .k() on the right operand
    assert np.array_equal(getattr(a, kind)(b, k=k)(p), model(p))
    symbol = {"union": a | b.k(k), "intersection": a & b.k(k), "difference": a - b.k(k)}[kind]
    assert np.array_equal(symbol(p), model(p))
    # the sharp operation away from the blend
    sharp = {"union": np.minimum(va, vb), "intersection": np.maximum(va, vb), "difference": np.maximum(va, -vb)}[kind]
    gap = np.abs(va - vb) if kind != "difference" else np.abs(va + vb)
    far = gap >= k
    assert far.sum() > 200 and np.allclose(model(p)[far], sharp[far], atol=1e-14)
    assert np.all(np.abs(model(p) - sharp) <= k / 4 + 1e-14)
    # the operands are named once each, not repeated
    formula, define = model.formula()
    assert len(define) == 3 and all(formula.count(name) >= 1 for name in define)
    # C1 across the edge of the blend (gap = k): the gradients on either side agree
    field = model.field()
    edge = p[np.abs(gap - k) < 0.05][:20]
    assert len(edge) > 5
    fa, fb = a.field(), b.field()
    for q in edge:
        # walk across the edge along the gradient of the gap
        g = (fa.gradients([q]) + (-1 if kind != "difference" else 1) * fb.gradients([q]))[0]
        g /= np.linalg.norm(g)
        s = np.linspace(-0.02, 0.02, 41)
        line = q + s[:, None] * g
        grads = field.gradients(line)
        assert np.abs(np.diff(grads, axis=0)).max() < 0.05  # no jump of the gradient on the line


# --- derivatives ------------------------------------------------------------------------------------

def finite_gradients(field, p, h=1e-6):
    e = np.eye(3) * h
    return np.stack([(field.values(p + e[i]) - field.values(p - e[i])) / (2 * h) for i in range(3)], axis=1)


def finite_hessians(field, p, h=1e-4):
    cols = [(field.gradients(p + np.eye(3)[i] * h) - field.gradients(p - np.eye(3)[i] * h)) / (2 * h)
            for i in range(3)]
    return np.stack(cols, axis=2)


def test_gradients_and_hessians_are_exact():
    smooth = (torus(0.8, 0.3).rotate(0.5, (1, 0, 1)).translate((0.1, 0.2, 0))
              .union(capsule(-X, Y, 0.3), k=0.4).union(ellipsoid((0.5, 0.7, 0.4)).twist(0.6), k=0.3))
    field = smooth.field()
    p = points(300, -1.2, 1.2)
    g = field.gradients(p)
    assert np.allclose(g, finite_gradients(field, p), rtol=0, atol=2e-7)
    # Hessians where no branch switches within the step (the blends are C1 only at their edges)
    h = field.hessians(p)
    fd = finite_hessians(field, p)
    close = np.abs(h - fd).max(axis=(1, 2)) < 1e-5
    assert close.mean() > 0.97
    assert np.allclose(h, np.transpose(h, (0, 2, 1)))
    # a CSG model: gradient of the piece each point is on
    csg = (box(1.5) & sphere(1)) - cylinder(0.4).orient(X)
    f2 = csg.field()
    q = points(300, -1, 1)
    error = np.abs(f2.gradients(q) - finite_gradients(f2, q)).max(axis=1)
    assert (error < 1e-6).mean() > 0.97


# --- JSON, files, errors ------------------------------------------------------------------------

def fogleman():
    f = sphere(1) & box(1.5)
    c = cylinder(0.5)
    return f - (c.orient(X) | c.orient(Y) | c.orient(Z))


def test_json_round_trip_and_field_file(tmp_path):
    model = rounded_box((1, 1.2, 0.8), 0.1).union(sphere(0.5, center=(0.5, 0.5, 0)), k=0.2) - cylinder(0.2)
    spec = model.to_json()
    assert spec["type"] == "expression" and isinstance(spec["define"], dict) and spec["define"]
    assert set(spec) == {"type", "value", "define", "bounds"}
    text = json.dumps(spec)
    p = points()
    values = model.field().values(p)
    assert np.array_equal(cdp.field_from_json(json.loads(text)).values(p), values)
    assert np.array_equal(cdp.expression(spec["value"], spec["bounds"], define=spec["define"]).values(p), values)
    path = tmp_path / "model.json"
    model.save(path)
    assert json.loads(path.read_text()) == spec
    assert np.array_equal(cdp.field_from_json(path).values(p), values)
    # bounds: the box padded by 0.1 of its longest side, or as given
    lo, hi = np.array(model.bounds)
    margin = 0.1 * (hi - lo).max()
    assert np.allclose(spec["bounds"], [lo - margin, hi + margin])
    assert model.to_json(bounds=((-3, -3, -3), (3, 3, 3)))["bounds"] == [[-3, -3, -3], [3, 3, 3]]
    assert np.allclose(model.field(pad=0).bounds, [lo, hi])
    # numbers round-trip exactly
    odd = sphere(1 / 3, center=(0.1, 0.2, 0.3))
    assert repr(1 / 3) in odd.formula()[0] and "0.1" in odd.formula()[0]


def test_the_program_meshes_the_saved_model_as_the_module_does(tmp_path):
    model = union(box(1), sphere(0.55, center=(0.5, 0.5, 0.5)))
    model.save(tmp_path / "m.json")
    subprocess.run([program("polygonize"), tmp_path / "m.json", "-o", tmp_path / "m.ply", "--factor", "2"], check=True,
                   capture_output=True)
    V, F = cdp.read_mesh(tmp_path / "m.ply")
    V2, F2, _, _ = cdp.polygonize(model, factor=2)
    assert np.array_equal(V, V2) and np.array_equal(F, F2)


def test_unbounded_models_need_bounds():
    for model in (cylinder(1), plane(), sphere(1) | plane(), negate(sphere(1)), sphere(0.2).repeat(1)):
        with pytest.raises(ValueError, match="unbounded"):
            model.field()
        with pytest.raises(ValueError, match="unbounded"):
            model.to_json()
        with pytest.raises(ValueError, match="unbounded"):
            cdp.polygonize(model)
    # given bounds, or bounded by an intersection, they work; values need no bounds
    assert cylinder(1).field(bounds=((-2, -2, -1), (2, 2, 1))).type == "expression"
    assert (cylinder(1) & slab(z0=-1, z1=1)).field().bounds[1][2] == pytest.approx(1.2)
    assert cylinder(1)(np.array([[2.0, 0, 0]]))[0] == 1.0
    with pytest.raises(ValueError, match="empty"):
        (sphere(1) & sphere(1, center=(5, 0, 0))).field()


def test_bad_arguments():
    with pytest.raises(ValueError, match="radius"):
        sphere(-1)
    with pytest.raises(ValueError, match="finite"):
        sphere(float("nan"))
    with pytest.raises(ValueError, match="3 numbers"):
        translate(sphere(), (1, 2))
    with pytest.raises(TypeError):
        sphere() | 3
    with pytest.raises(ValueError, match="positive"):
        scale(sphere(), (1, -1, 1))
    with pytest.raises(ValueError, match="zero vector"):
        orient(sphere(), (0, 0, 0))
    with pytest.raises(AttributeError):
        sphere().radius = 2
    with pytest.raises(ValueError, match="rb"):
        rounded_cylinder(0.5, 0.6, 2)


def test_constants_and_vectors():
    assert X == (1, 0, 0) and UP == Z == (0, 0, 1) and ORIGIN == (0, 0, 0)
    assert -X == (-1, 0, 0) and X + Y == (1, 1, 0) and 2 * Z == (0, 0, 2) and Y / 2 == (0, 0.5, 0)
    assert isinstance(X - Y, Vector)
    assert isinstance(sphere(), SDF)
    assert "sphere" in repr(sphere())
    ns = {}
    exec("from cdp.sdf import *", ns)
    assert {"sphere", "box", "union", "X", "ORIGIN", "SDF"} <= set(ns)


def test_shared_nodes_and_coordinates_are_named_once():
    s = rounded_box(1, 0.1).rotate(0.3, (1, 1, 0))
    model = s | s.shell(0.05)  # the same node at the same coordinates: named once
    formula, define = model.formula()
    text = formula + " ".join(define.values())
    assert text.count("hypot(") == 1
    p = points()
    assert np.allclose(model(p), np.minimum(s(p), np.abs(s(p)) - 0.025), atol=1e-15)


# --- meshing ------------------------------------------------------------------------------------

def test_meshing_foglemans_model():
    """sphere & box minus three perpendicular cylinders: six holes through the faces meeting in
    the middle, a surface of genus 5 (the outer surface and the surface of the cross of tunnels,
    each a sphere with six holes, joined along the six rims: genus 6 - 1). Marching Cubes agrees."""
    model = fogleman()
    V, F, _, stats = cdp.marching_cubes(model, cell=0.04)
    assert topology(V, F) == (1, 5, True)
    V, F, _, stats = cdp.polygonize(model, tolerance=1e-3)
    assert topology(V, F) == (1, 5, True)
    assert stats["components"] == 1 and stats["triangles"] == len(F)
    assert np.abs(model(V)).max() < 1e-6


@pytest.mark.parametrize("name", ["drilled rounded box", "blended block", "ball blended on an edge"])
def test_rounded_and_blended_parts_with_sharp_booleans_mesh_along_their_creases(name):
    """Parts written the usual way: a rounded box drilled through, the same with a ball blended on
    (smooth union) before drilling, and a box with a ball blended onto one edge, whose crease fades
    out inside the blend. Each meshes along its creases (no fallback to meshing across them), with
    the topology Marching Cubes finds, 20-degree triangles at factor 3 and its creases' vertices
    on the surface."""
    models = {
        "drilled rounded box": rounded_box((1.6, 1.0, 0.8), 0.1) - cylinder(0.2),
        "blended block": (rounded_box((1.6, 1.0, 0.8), 0.1) | sphere(0.55, center=(0.6, 0.3, 0.3)).k(0.2))
        - cylinder(0.2),
        "ball blended on an edge": box(1.5) | sphere(0.5, center=(0.75, 0.75, 0)).k(0.25),
    }
    model = models[name]
    V, F, _, _ = cdp.marching_cubes(model, cell=0.03)
    reference = topology(V, F)
    V, F, _, stats = cdp.polygonize(model, factor=3)
    assert topology(V, F) == reference
    assert stats["creases"]["followed"] and stats["creases"]["fallback"] == ""
    assert stats["creases"]["curves"] > 0
    assert stats["min_angle_degrees"] >= 20
    assert np.abs(model(V)).max() < 1e-6
