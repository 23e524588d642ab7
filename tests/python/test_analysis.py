"""curvature, project and evaluate, the last against build/bin/evaluate."""
import json
import subprocess

import numpy as np
import pytest

import cdp

from conftest import program


def test_curvature_of_a_sphere_and_a_torus():
    sphere = cdp.sphere(radius=2, center=(1, 0, 0))
    p = np.array([[3.0, 0, 0], [1, 2, 0], [1, 0, -2]])
    c = cdp.curvature(sphere, p)
    assert set(c) == {"normal", "k1", "k2", "dir1", "dir2", "gaussian", "mean", "mac", "min_radius", "shape_index", "C"}
    assert np.allclose(c["k1"], 0.5) and np.allclose(c["k2"], 0.5)
    assert np.allclose(c["normal"], (p - [1, 0, 0]) / 2)
    assert np.allclose(c["shape_index"], -1) and np.allclose(c["min_radius"], 2)
    assert c["C"].shape == (3, 3, 3) and c["dir1"].shape == (3, 3)
    t = cdp.curvature(cdp.torus(major_radius=1, minor_radius=0.3), [[1.3, 0, 0]])
    assert t["k1"][0] == pytest.approx(1 / 0.3) and t["k2"][0] == pytest.approx(1 / 1.3)
    assert np.allclose(np.abs(t["dir1"][0]), [0, 0, 1]) and np.allclose(np.abs(t["dir2"][0]), [0, 1, 0])


def test_curvature_is_evaluated_where_the_points_are():
    # Off the surface: the curvature of the level set through the point (radius 3, not 1).
    c = cdp.curvature(cdp.sphere(radius=1), [[3.0, 0, 0]])
    assert c["k1"][0] == pytest.approx(1 / 3)


def test_curvature_where_the_gradient_vanishes_names_the_point():
    field = cdp.expression("x^2 + y^2 + z^2 - 1", bounds=((-2, -2, -2), (2, 2, 2)))
    with pytest.raises(cdp.NoSurfaceError) as e:
        cdp.curvature(field, [[1, 0, 0], [0, 0, 0]])
    assert str(e.value).startswith("points[1] (0, 0, 0): curvature: ")


def test_project():
    sphere = cdp.sphere(radius=1)
    p = np.array([[2.0, 0, 0], [0.1, 0.2, -0.3], [0.0, 0.0, 0.0]])
    r = cdp.project(sphere, p)
    assert list(r["converged"]) == [True, True, False]
    assert r["status"][0] == "converged" and r["status"][2] != "converged"
    assert np.allclose(np.linalg.norm(r["points"][:2], axis=1), 1)
    assert r["iterations"].dtype == np.int32 and r["residual"][0] < 1e-9
    assert cdp.project(sphere, p[:1], max_iterations=1, max_step=0.1)["status"][0] == "max_iterations"
    with pytest.raises(ValueError, match=r"^max_iterations must be an integer in \[1, 1000000\], not 0$"):
        cdp.project(sphere, p, max_iterations=0)


def test_evaluate_matches_the_program(tmp_path):
    field_path = tmp_path / "torus.json"
    field_path.write_text(json.dumps({"type": "torus", "major_radius": 1, "minor_radius": 0.4}))
    field = cdp.field_from_json(field_path)
    V, F, N, _ = cdp.polygonize(field, factor=2)
    mesh_path, metrics_path = tmp_path / "torus.ply", tmp_path / "metrics.json"
    cdp.write_mesh(mesh_path, V, F, N)
    subprocess.run([program("evaluate"), field_path, mesh_path, "-o", metrics_path, "--views", "2", "--rays", "24",
                    "--samples", "2000", "--quiet"], check=True, stdout=subprocess.DEVNULL)
    metrics = cdp.evaluate(field, V, F, normals=N, views=2, resolution=24, samples=2000)
    expected = json.loads(metrics_path.read_text())
    assert metrics["topology"]["genus"] == 1 and metrics["topology"]["watertight"]
    assert metrics["rays"]["ground_truth_cached"] is False
    assert metrics["rays"]["ground_truth_seconds"] >= 0
    for key in ["depth_error", "phong_error_deg", "silhouette_disagreement", "edge_ratio", "topology",
                "min_angle_deg", "triangles", "vertices", "vertex_distance", "mesh_to_surface", "surface_to_mesh"]:
        assert metrics[key] == expected[key], key
    without = cdp.evaluate(field, V, F, views=1, resolution=8, samples=100)
    assert without["normals"] == "area_weighted (no normals given)"


def test_evaluate_bad_input():
    sphere = cdp.sphere(radius=1)
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    with pytest.raises(ValueError, match=r"^faces: face 0 refers to vertex 3 of 3$"):
        cdp.evaluate(sphere, V, [[0, 1, 3]])
    with pytest.raises(ValueError, match=r"^views must be an integer in \[1, 10000\], not 0$"):
        cdp.evaluate(sphere, V, [[0, 1, 2]], views=0)
    with pytest.raises(ValueError, match="orthogonal"):
        cdp.evaluate(sphere, V, [[0, 1, 2]], projection="orthogonal")


def test_evaluate_a_callable_field():
    """The ray casting calls the field from TBB's threads, each taking the GIL in turn."""
    box = ((-1.5, -1.5, -0.5), (1.5, 1.5, 0.5))
    expression = cdp.expression("(sqrt(x^2 + y^2) - 1)^2 + z^2 - 0.09", bounds=box)
    field = cdp.callable_field(lambda p: (np.sqrt(p[:, 0] ** 2 + p[:, 1] ** 2) - 1) ** 2 + p[:, 2] ** 2 - 0.09, box, trace=False)
    V, F, N, _ = cdp.polygonize(expression, factor=3)
    a = cdp.evaluate(expression, V, F, normals=N, views=1, resolution=24, samples=500)
    b = cdp.evaluate(field, V, F, normals=N, views=1, resolution=24, samples=500)
    assert field.python_calls > 0
    assert b["rays"]["surface_hits"] == a["rays"]["surface_hits"]
    assert b["depth_error"]["mean"] == pytest.approx(a["depth_error"]["mean"], rel=1e-6)


def test_trace_creases_of_a_cube_and_a_capped_cylinder():
    cube = cdp.expression("max(abs(x),max(abs(y),abs(z)))-1", bounds=[[-1.5] * 3, [1.5] * 3])
    r = cdp.trace_creases(cube)
    assert len(r["curves"]) == 12 and r["stops"] == 0 and r["duplicates"] == 0
    assert r["corners"].shape == (8, 3)
    assert np.allclose(np.abs(r["corners"]), 1, atol=1e-9)
    for c in r["curves"]:
        assert not c["closed"] and c["starts_at_corner"] and c["ends_at_corner"]
        # Every point on two faces.
        assert (np.sum(np.isclose(np.abs(c["points"]), 1, atol=1e-9), axis=1) >= 2).all()
    cylinder = cdp.expression("max(sqrt(x^2+y^2)-1, abs(z)-1)", bounds=[[-1.5] * 3, [1.5] * 3])
    rims = cdp.trace_creases(cylinder, max_spacing=0.05)
    assert [c["closed"] for c in rims["curves"]] == [True, True]
    for c in rims["curves"]:
        p = c["points"]
        assert np.allclose(np.hypot(p[:, 0], p[:, 1]), 1) and np.allclose(np.abs(p[:, 2]), 1)
        assert np.linalg.norm(np.diff(p, axis=0), axis=1).max() <= 0.05 * 1.0001
    # A smooth model reports no pieces, so no creases.
    assert cdp.trace_creases(cdp.sphere(radius=1))["curves"] == []
    with pytest.raises(ValueError):
        cdp.trace_creases(cube, resolution=1)


def test_crease_angles_tell_a_meshed_cubes_edges_from_its_faces():
    """On a cube meshed along its creases, every triangle with a corner on an edge is at a
    crease; the rest lie inside the faces. The counts add up, and the smallest angle of each
    group is that of its triangles, computed here from the mesh."""
    cube = cdp.expression("max(abs(x),max(abs(y),abs(z)))-1", bounds=[[-1.5] * 3, [1.5] * 3])
    v, f, _, _ = cdp.polygonize(cube, factor=2)
    a = cdp.crease_angles(cube, v, f)
    on_edge = (np.abs(v) > 1 - 1e-9).sum(axis=1) >= 2
    at = on_edge[f].any(axis=1)
    assert a["crease_vertices"] == on_edge.sum() > 0
    assert (a["triangles_at_creases"], a["triangles_away"]) == (at.sum(), (~at).sum())
    p = v[f]
    def smallest(p):
        angles = []
        for i in range(3):
            u, w = p[:, (i + 1) % 3] - p[:, i], p[:, (i + 2) % 3] - p[:, i]
            angles.append(np.degrees(np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), (u * w).sum(axis=1))))
        return np.min(angles, axis=0)
    assert np.isclose(a["min_degrees_at_creases"], smallest(p[at]).min())
    assert np.isclose(a["min_degrees_away"], smallest(p[~at]).min())
    assert a["worst_away"].shape == (3,)
    # A smooth field reports no pieces: no triangle is at a crease.
    b = cdp.crease_angles(cdp.sphere(radius=1), v, f)
    assert b["crease_vertices"] == b["triangles_at_creases"] == 0 and b["min_degrees_at_creases"] == 180
    with pytest.raises(ValueError):
        cdp.crease_angles(cube, v, f, near=-1)


def test_corner_normals_are_each_sides_on_a_cubes_edges():
    cube = cdp.expression("max(abs(x),max(abs(y),abs(z)))-1", bounds=[[-1.5] * 3, [1.5] * 3])
    v, f, _, _ = cdp.polygonize(cube, factor=2)
    n = cdp.corner_normals(cube, v, f)
    assert n.shape == (len(f), 3, 3)
    # Every corner's normal is the axis of its triangle's face: one side's, never a blend.
    e1, e2 = v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]
    face = np.cross(e1, e2)
    face /= np.linalg.norm(face, axis=1)[:, None]
    assert np.allclose(n, face[:, None, :], atol=1e-12)
    # A smooth field: the vertex normals at every corner.
    sphere = cdp.sphere(radius=1)
    v, f, _, _ = cdp.polygonize(sphere, factor=2)
    assert np.allclose(cdp.corner_normals(sphere, v, f), v[f], atol=1e-9)
    # The Phong error with them is zero on the cube (flat faces, exact normals), not so with blends.
    v, f, _, _ = cdp.polygonize(cube, factor=2)
    e_field = cdp.evaluate(cube, v, f, normals="field", views=2, resolution=16)
    e_mesh = cdp.evaluate(cube, v, f, normals="mesh", views=2, resolution=16)
    assert "each side's at creases" in e_field["normals"]
    assert e_field["phong_error_deg"]["max"] < 1e-6 < 1 < e_mesh["phong_error_deg"]["mean"]
    with pytest.raises(ValueError, match="normals"):
        cdp.evaluate(cube, v, f, normals="exact")
