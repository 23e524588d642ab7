"""A field written in numpy meshes like the same formula as an expression field: same topology,
vertices on the same surface, close to the expression's mesh."""
import numpy as np
import pytest

import cdp

from conftest import nearest_distances, topology

BOX = ((-1.5, -1.5, -0.5), (1.5, 1.5, 0.5))
FORMULA = "(sqrt(x^2 + y^2) - 1)^2 + z^2 - 0.09"


def torus(p):
    return (np.sqrt(p[:, 0] ** 2 + p[:, 1] ** 2) - 1) ** 2 + p[:, 2] ** 2 - 0.09


def torus_gradient(p):
    r = np.sqrt(p[:, 0] ** 2 + p[:, 1] ** 2)
    s = 2 * (r - 1) / r
    return np.stack([s * p[:, 0], s * p[:, 1], 2 * p[:, 2]], axis=1)


@pytest.fixture(scope="module")
def expression():
    return cdp.expression(FORMULA, bounds=BOX)


# Marching at cell 0.1: the root searches and the normals call Python point by point (see
# python/README.md), and finer cells only take longer. The adaptive method tracked alone: in
# blocks a Python function is cut into smaller blocks than the expression (lockstep), another mesh.
@pytest.mark.parametrize("method, options",
                         [("adaptive", {"factor": 3, "blocks": False}), ("mc", {"cell": 0.1}), ("mt", {"cell": 0.1})])
@pytest.mark.parametrize("gradient", [None, torus_gradient])
def test_callable_field_meshes_like_the_expression(expression, method, options, gradient):
    field = cdp.callable_field(torus, BOX, gradient=gradient)
    V, F, _, stats = cdp.polygonize(field, method, **options)
    V_ref, F_ref, _, stats_ref = cdp.polygonize(expression, method, **options)
    assert topology(V, F) == topology(V_ref, F_ref) == (1, 1, True)
    assert stats["components"] == 1
    # On the expression's surface: the first-order distance |F| / |grad F| of every vertex.
    distance = np.abs(expression.values(V)) / np.linalg.norm(expression.gradients(V), axis=1)
    assert distance.max() < 1e-6
    # Near the expression's mesh: no vertex farther from the other mesh's vertices than a
    # fraction of an edge (the meshes need not be identical: the finite differences differ
    # from the exact derivatives in the last digits, and the tracker's choices follow them).
    edge = np.linalg.norm(V_ref[F_ref[:, 0]] - V_ref[F_ref[:, 1]], axis=1).mean()
    assert nearest_distances(V, V_ref).max() < 0.75 * edge
    assert abs(len(F) - len(F_ref)) <= 0.05 * len(F_ref)


def test_python_errors_in_the_field_propagate_and_leave_nothing_broken(expression):
    calls = [0]

    def flaky(p):
        calls[0] += 1
        if calls[0] == 30:
            raise ArithmeticError("call 30 fails")
        return torus(p)

    field = cdp.callable_field(flaky, BOX, trace=False)
    with pytest.raises(ArithmeticError, match="call 30 fails"):
        cdp.polygonize(field, factor=3)
    V, F, _, _ = cdp.polygonize(field, factor=3)  # the same field, the same module: fine again
    assert topology(V, F) == (1, 1, True)
    with pytest.raises(ValueError, match=r"^callable field: f returned shape \((\d+), 2\) for \1 points; expected \(\1,\)$"):
        cdp.polygonize(cdp.callable_field(lambda p: p[:, :2], BOX), factor=3)


def test_the_tracker_calls_python_once_per_batch_not_once_per_point(expression):
    """The adaptive tracker hands a callable field the points of each expansion together: one
    call of f per Newton round of all its new points, one for their curvature (python/README.md,
    "Callable fields"). Sequentially it made one call per value-and-gradient (f on 7 points)
    and one per gradient-and-Hessian (f on 25 points)."""
    sizes = []

    def recorded(p):
        sizes.append(len(p))
        return torus(p)

    field = cdp.callable_field(recorded, BOX, trace=False)
    V, F, _, stats = cdp.polygonize(field, factor=3, blocks=False)  # the tracker's own batches
    evaluations = stats["field_evaluations"]
    # Every evaluation is in exactly one call: the seed grid's values all in the first call
    # (this field has no Lipschitz bound, so there is no refinement and no other value), then 7
    # points for each value and gradient and 25 for each gradient and Hessian (central
    # differences), so the counts in the stats are the work done, however it was batched.
    assert sizes[0] == evaluations["value"]
    assert sum(sizes) == evaluations["value"] + 7 * evaluations["value_gradient"] + 25 * evaluations["gradient_hessian"]
    assert field.python_calls == len(sizes)
    # The seed's hexagon measures its six corners in one call.
    assert 6 * 25 in sizes
    # Most expansions of a front place one new point (a front angle near 2 pi / 3 takes two
    # triangles), which nothing can batch; about one in five places two or more, which share
    # their calls. Measured: 6,208 calls for 7,500 derivative evaluations (0.83); one call per
    # evaluation, as before the batching, would be 1.
    derivative_calls = len(sizes) - 1
    assert derivative_calls < 0.9 * (evaluations["value_gradient"] + evaluations["gradient_hessian"])
    # Deterministic: the same field and options give the same arrays.
    V2, F2, _, _ = cdp.polygonize(field, factor=3, blocks=False)
    assert np.array_equal(V, V2) and np.array_equal(F, F2)
    # And the mesh is the expression's surface, as in the test above.
    V_ref, F_ref, _, _ = cdp.polygonize(expression, factor=3)
    assert topology(V, F) == topology(V_ref, F_ref) == (1, 1, True)
    distance = np.abs(expression.values(V)) / np.linalg.norm(expression.gradients(V), axis=1)
    assert distance.max() < 1e-6


def test_blocks_of_a_callable_share_their_calls_in_lockstep(expression):
    """With blocks, a callable field's blocks are meshed in lockstep and their faces' seams traced
    so: one call of f makes the evaluations of all of them, values, gradients and Hessians alike
    (issue 58: at most 0.5 calls per vertex on this torus at factor 8, against about 5.5 tracked
    alone; 0.38 with a call for each kind a round, 0.21 with one). The batches are the same on
    every run, so the mesh is too."""
    sizes = []

    def recorded(p):
        sizes.append(len(p))
        return torus(p)

    field = cdp.callable_field(recorded, BOX, trace=False)
    V, F, _, stats = cdp.polygonize(field, factor=8, blocks=True)
    b = stats["blocks"]
    assert b["used"], b["fallback"]
    assert b["lockstep_tasks"] > 16 and b["lockstep_batches"] > 0
    assert topology(V, F) == (1, 1, True)
    evaluations = stats["field_evaluations"]
    assert sum(sizes) == evaluations["value"] + 7 * evaluations["value_gradient"] + 25 * evaluations["gradient_hessian"]
    assert len(sizes) <= 0.3 * len(V), (len(sizes), len(V))
    calls = len(sizes)
    V2, F2, _, _ = cdp.polygonize(field, factor=8, blocks=True)
    assert len(sizes) == 2 * calls
    assert np.array_equal(V, V2) and np.array_equal(F, F2)
    distance = np.abs(expression.values(V)) / np.linalg.norm(expression.gradients(V), axis=1)
    assert distance.max() < 1e-6


@pytest.mark.parametrize("method", ["mc", "mt"])
@pytest.mark.parametrize("traversal", ["continuation", "grid"])
def test_the_marching_methods_call_python_in_batches(expression, method, traversal):
    """Marching Cubes and Tetrahedra hand a callable field the lattice corners, the edge root
    searches and the normals in batches (python/README.md, "Callable fields"). They made about
    4.2 calls per triangle on this torus at cell 0.05 when each root probe and each normal was a
    call of its own."""
    sizes = []

    def recorded(p):
        sizes.append(len(p))
        return torus(p)

    field = cdp.callable_field(recorded, BOX, trace=False)
    V, F, _, stats = cdp.polygonize(field, method, cell=0.05, traversal=traversal)
    evaluations = stats["field_evaluations"]
    # Every evaluation is in exactly one call (7 points for a value and gradient by central
    # differences), so the counts in the stats are the work, however it was grouped.
    assert sum(sizes) == evaluations["value"] + 7 * evaluations["value_gradient"]
    assert field.python_calls == len(sizes)
    # What is left does not grow with the vertices: the lattice's corners one call per slab
    # (grid: 21 here) or per breadth-first level of the walk (continuation: about 100, half the
    # torus's circumference plus half its tube's in cells, after ~40 single points of the seed
    # search); the roots about 22 regula falsi rounds per batch of 4096 edges (2 batches for
    # MC's 6,456 vertices, 5 for MT's 19,692), the normals one call per 16,384 vertices. So
    # under 300 calls for either method: 0.023 a triangle for MC's 12,912 triangles, 0.0076
    # for MT's 39,384 (measured: 186 and 249 calls with the continuation, 53 and 100 with the
    # grid traversal).
    assert len(sizes) < 300
    assert len(sizes) < (0.023 if method == "mc" else 0.0076) * len(F)
    # Deterministic: the same field and options give the same arrays, bit for bit.
    V2, F2, _, stats2 = cdp.polygonize(field, method, cell=0.05, traversal=traversal)
    assert np.array_equal(V, V2) and np.array_equal(F, F2)
    assert stats2["field_evaluations"] == evaluations
    # And the expression's mesh: a root search on the same corner values, whose probes agree
    # up to the last digits of sqrt in numpy and in the expression.
    V_ref, F_ref, _, _ = cdp.polygonize(expression, method, cell=0.05, traversal=traversal)
    assert topology(V, F) == topology(V_ref, F_ref) == (1, 1, True)
    assert np.array_equal(F, F_ref)
    assert np.abs(V - V_ref).max() < 1e-6


def test_the_tolerance_refinement_measures_a_callable_in_batches():
    """With a tolerance, the repair's refinement estimates each triangle's distance from its
    edges' midpoints and its centroid: one call of f a point when the field is not thread-safe
    (11.2 calls a triangle on this torus at 3e-3, 6,824 triangles), now a round's points in
    batched calls (7.2; the relaxation's judgments still measure point by point), the same mesh."""
    field = cdp.callable_field(torus, BOX, trace=False)
    V, F, _, stats = cdp.polygonize(field, tolerance=3e-3)
    assert topology(V, F) == (1, 1, True)
    assert stats["quality"]["splits"] > 0
    assert field.python_calls < 9 * len(F)


def test_a_callable_promised_smooth_skips_the_crease_probes():
    """smooth=True (the zero set has no creases) spares the repair's crease probes, three calls
    per vertex it touches, and changes nothing in the mesh; the default is False, as for any
    callable, which may hide a crease."""
    assert cdp.callable_field(torus, BOX, trace=False).smooth is False
    assert cdp.expression("x^2 + y^2 + z^2 - 1", bounds=BOX).smooth is False  # a polynomial may have a node
    assert cdp.field_from_json({"type": "torus", "major_radius": 1, "minor_radius": 0.3}).smooth is True
    plain = cdp.callable_field(torus, BOX, gradient=torus_gradient)
    smooth = cdp.callable_field(torus, BOX, gradient=torus_gradient, smooth=True)
    assert smooth.smooth is True
    V, F, _, _ = cdp.polygonize(plain, factor=3)
    V_s, F_s, _, _ = cdp.polygonize(smooth, factor=3)
    assert np.array_equal(V, V_s) and np.array_equal(F, F_s)
    assert smooth.python_calls < plain.python_calls


def gyroid_ball(p):
    q = 6 * p
    g = np.sin(q[:, 0]) * np.cos(q[:, 1]) + np.sin(q[:, 1]) * np.cos(q[:, 2]) + np.sin(q[:, 2]) * np.cos(q[:, 0])
    return np.maximum(g / 6, np.linalg.norm(p, axis=1) - 1)


def test_a_black_box_crease_stops_the_run_at_the_first_vertex_on_it_naming_it():
    """The gyroid clipped by a ball as a black box: where its sheets cut the sphere the central
    differences turn the normal within their step, a crease no mesh of this field follows. With
    creases: follow (the default) the run stops at the first vertex placed there and says what
    would mesh it (meshing on, the fronts crowded along the crease: 161,055 Python calls before
    an error, and 833,554 when the careful and finer runs followed)."""
    field = cdp.callable_field(gyroid_ball, ((-1.1,) * 3, (1.1,) * 3), trace=False)
    with pytest.raises(cdp.LimitExceededError) as e:
        cdp.polygonize(field, factor=3)
    message = str(e.value)
    assert "less than the step of the central differences" in message
    assert "cdp.trace" in message and "creases: ignore" in message
    assert "a kink of a field without branch data" in message
    assert field.python_calls < 5_000


def menger_sponge(p):
    a = np.abs(p)
    x, y, z = a[:, 0], a[:, 1], a[:, 2]
    holes = np.minimum(np.minimum(np.maximum(x, y), np.maximum(y, z)), np.maximum(x, z)) - 0.4
    return np.maximum(np.maximum(np.maximum(x, y), z) - 1, -holes)


def octahedron(p):
    return np.abs(p).sum(axis=1) - 1


def test_creases_of_a_black_box_fail_at_once_unless_meshed_across_by_choice():
    """A Menger sponge of level 1 as a black box ran 80 s (3.5 million Python calls) before its
    error; it stops at its first vertex on a crease. creases="ignore" meshes across the creases
    of a black box as before, where the fronts can: the octahedron, its creases cut by chords,
    which the stats say."""
    box = ((-1.3,) * 3, (1.3,) * 3)
    sponge = cdp.callable_field(menger_sponge, box, trace=False)
    with pytest.raises(cdp.LimitExceededError, match="lies on a kink"):
        cdp.polygonize(sponge, factor=3)
    assert sponge.python_calls < 2_000
    field = cdp.callable_field(octahedron, box, trace=False)
    with pytest.raises(cdp.LimitExceededError, match="creases: ignore meshes across"):
        cdp.polygonize(field, factor=1)
    V, F, _, stats = cdp.polygonize(field, factor=1, creases="ignore")
    assert topology(V, F) == (1, 0, True)
    assert stats["creases"]["across_black_box"]
    assert np.abs(octahedron(V)).max() < 1e-6


def capped_sphere(p):
    return np.maximum(np.linalg.norm(p, axis=1) - 1, p[:, 2] - 0.7)


def test_a_black_box_crease_no_vertex_lands_on_is_found_between_two():
    """A sphere capped by a plane (faces meeting at 134 degrees) as a black box: the fronts' steps
    cross the crease with both ends a face's, where the differences resolve the curvature, and
    before the steps were looked at the mesh cut the crease by chords and its stats said nothing
    (creases.across_black_box false). A step whose normal turns more than its ends' curvature
    explains is halved towards the turn, which stays whole across a crease."""
    box = ((-1.25,) * 3, (1.25,) * 3)
    field = cdp.callable_field(capped_sphere, box, trace=False)
    with pytest.raises(cdp.LimitExceededError, match="crosses a kink"):
        cdp.polygonize(field, factor=3)
    assert field.python_calls < 2_000
    V, F, _, stats = cdp.polygonize(field, factor=3, creases="ignore")
    assert topology(V, F) == (1, 0, True)
    assert stats["creases"]["across_black_box"]


def two_spheres(combine, angle_degrees):
    c = np.sin(np.radians(angle_degrees / 2))
    return lambda p: combine(np.linalg.norm(p - [0, 0, c], axis=1) - 1, np.linalg.norm(p + [0, 0, c], axis=1) - 1)


@pytest.mark.parametrize("combine", [np.maximum, np.minimum], ids=["lens", "union"])
def test_a_shallow_black_box_crease_convex_or_concave_stops_the_run(combine):
    """Two unit spheres meeting at 6 degrees, as their intersection (a convex crease) and their
    union (a concave one, whose angle the faces' own turn hides from the raw turn of a step): the
    turn the ends' curvature does not explain is the crease's. Before, both meshed at factors 1,
    3 and 6 with the crease cut by chords and stats["creases"]["across_black_box"] false."""
    box = ((-1.3,) * 3, (1.3,) * 3)
    # In blocks (the default) the layout traces the seams on the cut planes first, in lockstep:
    # up to 1,710 calls (the union at factor 6) before a block's front meets the crease; a layout
    # whose block edge the surface grazes is traced again with its cuts moved (blocks.layouts):
    # the lens at factor 6, 3,178 calls over two layouts (1,300-2,000 with one).
    for blocks, bound in ((False, 1_000), (None, 2_000)):
        for factor in (1, 3, 6):
            field = cdp.callable_field(two_spheres(combine, 6), box, trace=False)
            with pytest.raises(cdp.LimitExceededError, match="kink"):
                cdp.polygonize(field, factor=factor, blocks=blocks)
            calls = 3_500 if blocks is None and combine is np.maximum and factor == 6 else bound
            assert field.python_calls < calls


def test_a_black_box_promised_smooth_is_meshed_across_its_tight_bends():
    """smooth=True is the caller's word that the zero set has no crease: a bend tighter than the
    differences resolve (here the capped sphere's rim, which the promise wrongly calls smooth) is
    meshed across, as creases="ignore" does, instead of ending the run."""
    box = ((-1.25,) * 3, (1.25,) * 3)
    field = cdp.callable_field(capped_sphere, box, trace=False, smooth=True)
    V, F, _, stats = cdp.polygonize(field, factor=3)
    assert topology(V, F) == (1, 0, True)
    ignored = cdp.callable_field(capped_sphere, box, trace=False)
    V2, F2, _, _ = cdp.polygonize(ignored, factor=3, creases="ignore")
    assert len(F) == len(F2)


def test_nan_away_from_the_surface_counts_as_outside():
    """A function that is NaN in part of its box far from its surface (a mask people write)."""
    def sphere_with_a_hole_in_its_domain(p):
        v = np.linalg.norm(p, axis=1) - 1
        v[p[:, 0] > 1.3] = np.nan
        return v

    field = cdp.callable_field(sphere_with_a_hole_in_its_domain, ((-1.5,) * 3, (1.5,) * 3))
    assert isinstance(field, cdp.CallableField)  # a boolean mask: not traced
    V, F, _, stats = cdp.polygonize(field, factor=3)
    assert topology(V, F) == (1, 0, True)
    assert stats["non_finite_samples"] > 0
    assert np.abs(np.linalg.norm(V, axis=1) - 1).max() < 1e-6


def test_the_error_at_a_black_box_crease_says_why_the_function_was_not_traced():
    """A box whose function assigns through a boolean mask, which tracing does not follow: the
    black box's error at its first crease quotes cdp.trace's reason, the line to write differently."""
    def box(p):
        v = np.abs(p).max(axis=1) - 0.8
        v[np.abs(p[:, 0]) > 5] = 1.0  # never in the box
        return v

    field = cdp.callable_field(box, ((-1.25,) * 3, (1.25,) * 3))
    assert isinstance(field, cdp.CallableField)
    assert "assigns into an array" in field.trace_error
    with pytest.raises(cdp.LimitExceededError, match="cdp.trace could not follow this function: .*assigns into"):
        cdp.polygonize(field, factor=3)
    smooth = cdp.callable_field(torus, BOX, trace=False)
    assert smooth.trace_error is None
