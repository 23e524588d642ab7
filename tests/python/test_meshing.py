"""polygonize, marching_cubes, marching_tetrahedra: results, options, errors, and the same
arrays as build/bin/polygonize, bit for bit."""
import json
import subprocess
import warnings

import numpy as np
import pytest

import cdp

from conftest import program, topology


@pytest.fixture(scope="module")
def sphere():
    return cdp.sphere(radius=1)


def bits(a):
    """The array's bytes: equality of these is bit-for-bit equality (-0.0 differs from 0.0)."""
    return np.ascontiguousarray(a).tobytes()


@pytest.mark.parametrize("method, options", [("adaptive", {"factor": 2}), ("mc", {"cell": 0.1}), ("mt", {"cell": 0.1})])
def test_sphere_meshes_are_closed_spheres(sphere, method, options):
    V, F, _, stats = cdp.polygonize(sphere, method, **options)
    assert V.dtype == np.float64 and V.shape[1] == 3
    assert F.dtype == np.int32 and F.shape[1] == 3
    assert topology(V, F) == (1, 0, True)
    assert np.abs(np.linalg.norm(V, axis=1) - 1).max() < 1e-6
    assert stats["method"] == method
    assert stats["triangles"] == len(F) and stats["vertices"] == len(V)
    assert stats["field_evaluations"]["total"] > 0
    # Once more: the same mesh bit for bit (a run keeps no state), with the field's normals.
    V2, F2, N, stats2 = cdp.polygonize(sphere, method, **options)
    assert bits(V2) == bits(V) and bits(F2) == bits(F)
    assert np.allclose(N, V / np.linalg.norm(V, axis=1)[:, None], atol=1e-6)


def test_marching_functions_are_polygonize(sphere):
    for function, method in [(cdp.marching_cubes, "mc"), (cdp.marching_tetrahedra, "mt")]:
        V, F, _, stats = function(sphere, cell=0.2, traversal="grid")
        V2, F2, _, stats2 = cdp.polygonize(sphere, method, cell=0.2, traversal="grid")
        assert bits(V) == bits(V2) and bits(F) == bits(F2)
        assert stats["traversal"] == "grid"


def test_progress_and_phase_callbacks(sphere):
    fractions, phases = [], []
    cdp.polygonize(cdp.torus(major_radius=1, minor_radius=0.3), factor=3, progress=fractions.append, phase=phases.append)
    # The default variant repairs slivers after meshing (polygonizer/src/adaptive/quality.h).
    assert phases == ["sampling the seed grid", "meshing", "repairing triangles", "checking the mesh"]
    # A field with creases traces them, then meshes along them first.
    phases.clear()
    cube = cdp.field_from_json({"type": "expression", "value": "max(abs(x),max(abs(y),abs(z)))-1",
                                "bounds": [[-1.6, -1.6, -1.6], [1.5, 1.5, 1.5]]})
    cdp.polygonize(cube, factor=3, phase=phases.append)
    assert phases == ["sampling the seed grid", "tracing creases", "meshing along creases", "meshing",
                      "repairing triangles", "checking the mesh"]
    assert fractions and fractions[-1] == 1.0
    fractions.clear()
    cdp.marching_cubes(sphere, cell=0.05, progress=fractions.append)
    assert fractions and fractions[-1] == 1.0


@pytest.mark.parametrize("call, message", [
    (lambda s: cdp.polygonize(s, "adaptive", cell=0.1), 'cell does not apply to method "adaptive"'),
    (lambda s: cdp.polygonize(s, "mc", factor=2), 'factor does not apply to method "mc"'),
    (lambda s: cdp.polygonize(s, "mt", face_ambiguity="join_inside"), 'face_ambiguity does not apply to method "mt"'),
    (lambda s: cdp.polygonize(s, factor=2, tolerance=0.01), "give one of factor, tolerance and chord, not several"),
    (lambda s: cdp.polygonize(s, tolerance=0.01, chord=0.01), "give one of factor, tolerance and chord, not several"),
    (lambda s: cdp.polygonize(s, chord=0), "chord must be a positive number, not 0.0"),
    (lambda s: cdp.polygonize(s, "mt", chord=0.01), 'chord does not apply to method "mt"'),
    (lambda s: cdp.polygonize(s, factor=-1), "factor must be a positive number, not -1.0"),
    (lambda s: cdp.polygonize(s, min_edge=float("nan")), "min_edge must be a positive number, not nan"),
    (lambda s: cdp.polygonize(s, "marching"), 'method must be "adaptive", "mc" or "mt", not "marching"'),
    (lambda s: cdp.polygonize(s, triangle_count="floor"), 'triangle_count must be "hartmann" or "paper_floor", not "floor"'),
    (lambda s: cdp.polygonize(s, curvature="yes"), 'curvature must be true or false, not "yes"'),
    (lambda s: cdp.marching_tetrahedra(s, cell=0.1, precision=1), "give one of cell and precision, not several"),
    (lambda s: cdp.polygonize(s, creases="sharp"), 'creases must be "follow" or "ignore", not "sharp"'),
    (lambda s: cdp.polygonize(s, "mc", creases="follow"), 'creases does not apply to method "mc"'),
    (lambda s: cdp.polygonize(s, seed_resolution=1), "seed_resolution must be an integer in [2, 2147483647], not 1"),
    (lambda s: cdp.polygonize(s, threads=-1), "threads must be an integer in [0, 2147483647], not -1"),
    (lambda s: cdp.marching_cubes(s, cell=0), "cell must be a positive number, not 0.0"),
    (lambda s: cdp.marching_cubes(s, traversal="walk"), 'traversal must be "continuation" or "grid", not "walk"'),
    (lambda s: cdp.marching_cubes(s, cell=1e-9), None),
    (lambda s: cdp.marching_tetrahedra(s, precision=2),
     'marching: --precision needs a variational (data-driven) model with constraint points; the "sphere" field has '
     'none, give a cell size instead'),
])
def test_bad_options_are_value_errors(sphere, call, message):
    with pytest.raises(ValueError) as e:
        call(sphere)
    if message is None:
        assert "needs more than 2^19 cells" in str(e.value)
    else:
        assert str(e.value) == message


def test_algorithm_errors_are_runtime_error_subclasses():
    assert issubclass(cdp.NoSurfaceError, RuntimeError) and issubclass(cdp.LimitExceededError, RuntimeError)
    outside = cdp.sphere(radius=1, bounds=((2, 2, 2), (3, 3, 3)))
    with pytest.raises(cdp.NoSurfaceError) as e:
        cdp.polygonize(outside)
    assert str(e.value).startswith("adaptive: no zero crossing of the field in its box")
    with pytest.raises(cdp.NoSurfaceError):
        cdp.marching_cubes(outside, cell=0.1)
    with pytest.raises(cdp.LimitExceededError):
        cdp.polygonize(cdp.torus(major_radius=1, minor_radius=0.3), factor=3, max_triangles=10)


@pytest.mark.parametrize("method, flags, options", [
    ("adaptive", ["--factor", "3"], {"factor": 3}),
    ("adaptive", ["--tolerance", "0.002", "--min-edge", "0.01"], {"tolerance": 0.002, "min_edge": 0.01}),
    ("adaptive", ["--chord", "0.002"], {"chord": 0.002}),
    ("mc", ["--cell", "0.05"], {"cell": 0.05}),
    ("mt", ["--cell", "0.08", "--traversal", "grid"], {"cell": 0.08, "traversal": "grid"}),
    # Nothing given: the defaults are the same (one table, cdp/io/polygonize_options.h).
    ("adaptive", [], {}),
    ("adaptive", ["--variant", "paper", "--triangle-count", "paper_floor", "--check-self-intersections", "false"],
     {"variant": "paper", "triangle_count": "paper_floor", "check_self_intersections": False}),
    ("mc", ["--cell", "0.08", "--face-ambiguity", "separate_inside"], {"cell": 0.08, "face_ambiguity": "separate_inside"}),
    # Different thread counts on the two sides: the same arrays.
    ("adaptive", ["--factor", "3", "--threads", "1"], {"factor": 3, "threads": 2}),
    ("mc", ["--cell", "0.05", "--threads", "2"], {"cell": 0.05, "threads": 1}),
])
def test_same_arrays_as_the_polygonize_program(tmp_path, method, flags, options):
    field_path = tmp_path / "field.json"
    field_path.write_text(json.dumps({
        "type": "blobs", "threshold": 0.3,
        "blobs": [{"center": [0, 0, 0], "radius": 1}, {"center": [0.9, 0.3, 0], "radius": 0.8, "strength": 0.7}]}))
    out, stats_path = tmp_path / "mesh.ply", tmp_path / "stats.json"
    subprocess.run([program("polygonize"), field_path, "-o", out, "--method", method, "--stats", stats_path, "--quiet",
                    *flags], check=True)
    V_file, F_file, N_file = cdp.read_mesh(out, return_normals=True)
    V, F, N, stats = cdp.polygonize(cdp.field_from_json(field_path), method, **options)
    assert bits(V) == bits(V_file)
    assert bits(F) == bits(F_file)
    assert bits(N) == bits(N_file)
    program_stats = json.loads(stats_path.read_text())
    # Times, and what only the program knows (its field file, its own peak resident memory).
    timing = {"seconds", "curvature_seconds", "hessian_seconds", "seed_grid_seconds", "field", "peak_resident_bytes"}

    def untimed(s):
        out = {k: v for k, v in s.items() if k not in timing}
        if "phases" in out:  # each phase's seconds differ; its evaluation counts do not
            out["phases"] = {name: {k: v for k, v in p.items() if k != "seconds"} for name, p in out["phases"].items()}
        if "blocks" in out:  # the blocks' and the passes' times differ (the passes also with the threads)
            out["blocks"] = {k: v for k, v in out["blocks"].items()
                             if k not in {"seconds", "layout_seconds", "block_seconds", "pass_seconds", "pass_blocks"}}
        return out
    assert untimed(stats) == untimed(program_stats)


def test_creases_are_followed_or_ignored():
    # A cube: followed, its 12 creases are edges of the mesh (and the stats say so); ignored, the
    # tracker meshes across them.
    cube = cdp.field_from_json({"type": "expression", "value": "max(abs(x+0.0137),max(abs(y+0.0137),abs(z+0.0137)))-1",
                                "bounds": [[-1.6, -1.6, -1.6], [1.6, 1.6, 1.6]]})
    V, F, _, stats = cdp.polygonize(cube, factor=3)
    assert stats["creases"]["followed"] and stats["creases"]["curves"] == 12 and stats["creases"]["corners"] == 8
    shifted = V + 0.0137
    on_two_faces = (np.abs(np.abs(shifted) - 1) < 1e-9).sum(axis=1) >= 2
    assert on_two_faces.sum() == stats["creases"]["vertices"]
    V, F, _, stats = cdp.polygonize(cube, factor=3, creases="ignore")
    assert not stats["creases"]["followed"] and stats["creases"]["handling"] == "ignore"


def test_an_unknown_keyword_is_a_type_error_naming_the_nearest_option(sphere):
    with pytest.raises(TypeError) as e:
        cdp.polygonize(sphere, factr=2)
    assert str(e.value) == "polygonize() got an unexpected keyword argument 'factr' (did you mean 'factor'?)"
    with pytest.raises(TypeError) as e:
        cdp.marching_cubes(sphere, cel=0.1)
    assert str(e.value) == "marching_cubes() got an unexpected keyword argument 'cel' (did you mean 'cell'?)"
    with pytest.raises(TypeError) as e:
        cdp.polygonize(sphere, colour="red")
    assert str(e.value) == "polygonize() got an unexpected keyword argument 'colour'"


def test_the_program_python_and_experiment_files_share_one_table_of_options(tmp_path):
    """Every option of cdp.polygonize_options() is a flag of the polygonize program with its default
    in the help, a keyword polygonize takes, and a key an experiment file's run takes (turned into
    that flag): the three cannot drift apart."""
    options = cdp.polygonize_options()
    names = [o["name"] for o in options]
    assert len(set(names)) == len(names)
    assert {"factor", "tolerance", "chord", "min_edge", "max_edge", "triangle_count", "variant", "creases",
            "curvature", "check_self_intersections", "cell", "precision", "traversal", "face_ambiguity",
            "seed_resolution", "max_triangles", "threads"} <= set(names)
    help_text = subprocess.run([program("polygonize"), "--help"], capture_output=True, text=True, check=True).stdout
    for o in options:
        assert o["flag"] == "--" + o["name"].replace("_", "-")
        assert o["flag"] in help_text, o["name"]
        if o["default"] is not None and o["kind"] != "flag":
            line = next(l for l in help_text.splitlines() if o["flag"] + " " in l + " ")
            assert "=" + o["default"] + " " in line + " ", (o["name"], line)
        if o["kind"] == "choice":
            assert o["default"] == o["choices"][0]
    # Python takes each with its default value (or, without one, a valid one) for each method it applies to.
    sphere = cdp.sphere(radius=1)
    example = {"number": 0.2, "integer": 8, "boolean": True, "flag": False, "real": -0.05}
    for method in ("adaptive", "mc", "mt"):
        given = {}
        for o in options:
            if method not in o["methods"] or o["name"] in ("tolerance", "chord", "precision", "max_triangles"):
                continue
            given[o["name"]] = o["choices"][0] if o["kind"] == "choice" else example[o["kind"]]
        given["seed_resolution"] = 16
        V, F, _, stats = cdp.polygonize(sphere, method, **given)
        assert topology(V, F) == (1, 0, True), method
    # An experiment run with every option of its method runs the program with them: its mesh is
    # polygonize's with the same keywords, bit for bit.
    run = {"method": "adaptive", "factor": 2, "min_edge": 0.01, "max_edge": 0.5, "triangle_count": "paper_floor",
           "variant": "improved", "creases": "follow", "curvature": True, "check_self_intersections": True,
           "seed_resolution": 16, "max_triangles": 100000, "threads": 1}
    marching = {"method": "mc", "cell": 0.1, "traversal": "grid", "face_ambiguity": "join_inside", "seed_resolution": 16,
                "threads": 1}
    experiment = tmp_path / "e.json"
    experiment.write_text(json.dumps({"field": {"type": "sphere", "radius": 1}, "runs": [run, marching],
                                      "evaluation": {"views": 1, "resolution": 8}}))
    out = tmp_path / "out"
    subprocess.run([program("experiment"), experiment, "--out", out, "--jobs", "1"], check=True, capture_output=True)
    for options, mesh in ((run, "adaptive_factor2"), (marching, "mc_cell0.1")):
        V_file, F_file = cdp.read_mesh(out / "meshes" / (mesh + ".ply"))
        keywords = {k: v for k, v in options.items() if k != "method"}
        V, F, _, _ = cdp.polygonize(sphere, options["method"], **keywords)
        assert bits(V) == bits(V_file) and bits(F) == bits(F_file), mesh
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"field": {"type": "sphere", "radius": 1}, "runs": [{"method": "mc", "cell": 0.1,
                                                                                   "curvature": True}]}))
    r = subprocess.run([program("experiment"), bad, "--commands"], capture_output=True, text=True)
    assert r.returncode != 0 and 'does not apply to method "mc"' in r.stderr
    # An experiment measures F = 0 (evaluate, the ground truth): a level is refused, not mismeasured.
    bad.write_text(json.dumps({"field": {"type": "sphere", "radius": 1}, "runs": [{"method": "mc", "cell": 0.1,
                                                                                   "level": 0.05}]}))
    r = subprocess.run([program("experiment"), bad, "--commands"], capture_output=True, text=True)
    assert r.returncode != 0 and "experiment runs measure the surface F = 0" in r.stderr


@pytest.mark.parametrize("method, options", [("adaptive", {"factor": 2}), ("mc", {"cell": 0.1}), ("mt", {"cell": 0.1})])
def test_every_method_returns_a_named_mesh_with_a_summary(method, options):
    torus = cdp.torus(major_radius=1, minor_radius=0.4)
    mesh = cdp.polygonize(torus, method, **options)
    assert isinstance(mesh, cdp.Mesh) and isinstance(mesh, tuple) and len(mesh) == 4
    V, F, N, stats = mesh
    assert V is mesh.vertices and F is mesh.faces and N is mesh.normals and stats is mesh.stats
    assert N.shape == V.shape and np.allclose(np.linalg.norm(N, axis=1), 1)
    components, genus, closed = topology(V, F)  # counted apart in numpy
    summary = stats["summary"]
    assert summary["watertight"] and summary["closed"] == closed and summary["manifold"] and summary["outward"]
    assert (summary["components"], summary["genus"]) == (components, genus) == (1, 1)
    assert summary["smallest_angle_degrees"] == stats["angles"]["min_degrees"] > 0
    with pytest.warns(DeprecationWarning, match="return_normals"):
        again = cdp.polygonize(torus, method, return_normals=True, **options)
    assert bits(again.vertices) == bits(V)


@pytest.mark.parametrize("method, options, within", [("adaptive", {"factor": 2}, 1e-9), ("mc", {"cell": 0.05}, 2e-3),
                                                     ("mt", {"cell": 0.05}, 2e-3)])
def test_level_meshes_another_value_of_the_field(method, options, within):
    # x^2 + y^2 + z^2 = 0.64: the sphere of radius 0.8; the same mesh as the field shifted by hand.
    square = cdp.expression("x^2 + y^2 + z^2", ((-1, -1, -1), (1, 1, 1)))
    V, F, _, stats = cdp.polygonize(square, method, level=0.64, **options)
    assert np.abs(np.linalg.norm(V, axis=1) - 0.8).max() < within
    assert stats["summary"]["watertight"] and stats["summary"]["genus"] == 0
    shifted = cdp.polygonize(cdp.expression("x^2 + y^2 + z^2 - 0.64", ((-1, -1, -1), (1, 1, 1))), method, **options)
    assert np.abs(shifted.vertices - V).max() < 1e-9 and bits(shifted.faces) == bits(F)
    with pytest.raises(ValueError, match="level must be a finite number, not nan"):
        cdp.polygonize(square, method, level=float("nan"), **options)


def test_level_keeps_the_smooth_seams_of_a_rounded_box():
    # A rounded box's seams are C1 (no creases) wherever its level set is: at level 1.15 of
    # "base + 1" it is the same surface, and mesh, as "base - 0.15" (branch kinds and smooth
    # sides are those of the shifted field, not of its own zero set, where they differ).
    bounds = ((-1, -1, -1), (1, 1, 1))
    base = "sqrt(max(abs(x)-0.6,0)^2 + max(abs(y)-0.4,0)^2 + max(abs(z)-0.3,0)^2)"
    direct = cdp.polygonize(cdp.expression(base + " - 0.15", bounds), factor=3)
    shifted = cdp.polygonize(cdp.expression(base + " + 1", bounds), level=1.15, factor=3)
    assert len(shifted.faces) == len(direct.faces) and np.abs(shifted.vertices - direct.vertices).max() < 1e-9
    assert shifted.stats["creases"]["curves"] == direct.stats["creases"]["curves"] == 0


def test_level_keeps_the_creases_of_a_csg_field():
    # The cube max(|x|, |y|, |z|) = 1 at level 0.2 is the cube of half-side 1.2, its 12 edges followed.
    cube = cdp.expression("max(abs(x), max(abs(y), abs(z))) - 1", ((-1.5, -1.5, -1.5), (1.5, 1.5, 1.5)))
    V, F, _, stats = cdp.polygonize(cube, level=0.2, factor=2)
    assert np.abs(np.abs(V).max(axis=1) - 1.2).max() < 1e-9
    assert stats["creases"]["followed"] and stats["creases"]["curves"] == 12 and stats["creases"]["corners"] == 8
    assert {tuple(c) for c in np.round(V, 9)} >= {(sx * 1.2, sy * 1.2, sz * 1.2) for sx in (-1, 1) for sy in (-1, 1)
                                                   for sz in (-1, 1)}


def test_blocks_give_the_same_mesh_on_one_and_two_threads():
    # A torus of about 3.5e4 triangles at factor 12, cut into 3 x 3 x 1 blocks (issue 58).
    torus = cdp.torus(major_radius=1, minor_radius=0.4)
    one = cdp.polygonize(torus, factor=12, blocks=True, threads=1)
    two = cdp.polygonize(torus, factor=12, blocks=True, threads=2)
    assert one.stats["blocks"]["used"], one.stats["blocks"]["fallback"]
    assert one.stats["blocks"]["meshed_blocks"] >= 4
    assert two.stats["blocks"]["threads"] == 2
    assert np.array_equal(one.vertices, two.vertices) and np.array_equal(one.faces, two.faces)
    summary = one.stats["summary"]
    assert summary["watertight"] and summary["genus"] == 1 and summary["components"] == 1
    # Blocks are the default for a field whose calls are cheap: the same mesh as blocks=True.
    default = cdp.polygonize(torus, factor=12)
    assert default.stats["blocks"]["requested"] and default.stats["blocks"]["used"]
    assert np.array_equal(one.vertices, default.vertices) and np.array_equal(one.faces, default.faces)
    # Without blocks the surface is tracked alone, into another mesh of the same surface.
    alone = cdp.polygonize(torus, factor=12, threads=1, blocks=False)
    assert not alone.stats["blocks"]["used"] and not alone.stats["blocks"]["requested"]
    # A Python function too is meshed in blocks by default (in lockstep: python/README.md).
    field = cdp.callable_field(torus.values, torus.bounds, trace=False)
    called = cdp.polygonize(field, factor=3)
    assert called.stats["blocks"]["requested"] and called.stats["blocks"]["used"], called.stats["blocks"]["fallback"]
    assert called.stats["blocks"]["lockstep_batches"] > 0


def test_blocks_in_lockstep_never_cut_a_black_box_rounded_edge():
    # Quilez's rounded box as a numpy function, its C1 seams unknown (trace=False), in blocks at
    # factor 7: chords cut the fillets (radius 0.15) up to 0.04 deep, a mesh closed and of the
    # right genus, until a check sent such meshes to tracking alone (python/README.md); the seams
    # between blocks, spaced by the curvature alone, went from the flat sides' long edges to the
    # fillets' short ones at once. Graded, the blocks' mesh is kept. Tracked alone its triangles'
    # middles lie within 0.004.
    half, radius = np.array([0.6, 0.4, 0.3]), 0.15

    def rounded_box(p):
        q = np.abs(p) - half
        return np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0) - radius

    field = cdp.callable_field(rounded_box, ((-1.1, -1.1, -1.1), (1.1, 1.1, 1.1)), trace=False)
    V, F, _, stats = cdp.polygonize(field, factor=7, blocks=True, threads=1)
    assert stats["blocks"]["used"], stats["blocks"]["fallback"]
    assert stats["summary"]["watertight"] and stats["summary"]["genus"] == 0
    assert np.abs(rounded_box(V[F].mean(axis=1))).max() < 0.004


def test_a_block_edge_the_surface_crosses_twice_between_its_samples_keeps_its_layout():
    # Quilez's rounded cylinder as a numpy function at factor 8: the first layout's cuts meet in
    # a block edge that the surface crosses twice between two of its samples. A seam found no
    # corner to end at, and the run was tracked alone (twice the time, five times the calls);
    # then the cuts were moved by a third of a block (blocks.cpp, kLayoutShifts) and the second
    # layout was kept. Now the edge's samples find the dip between them (kDipHalvings) and the
    # first layout is kept (the crowd of 200 blobs in blocks_test.cpp still needs its third).
    def rounded_cylinder(p, r=0.6, h=0.5, rr=0.1):
        d = np.stack([np.linalg.norm(p[:, :2], axis=1) - r + rr, np.abs(p[:, 2]) - h + rr], axis=1)
        return np.minimum(np.maximum(d[:, 0], d[:, 1]), 0) + np.linalg.norm(np.maximum(d, 0), axis=1) - rr

    field = cdp.callable_field(rounded_cylinder, ((-0.9, -0.9, -0.9), (0.9, 0.9, 0.9)), trace=False)
    V, F, _, stats = cdp.polygonize(field, factor=8, threads=1)
    b = stats["blocks"]
    assert b["used"] and b["layouts"] == 1, (b["layouts"], b["fallback"])
    assert topology(V, F) == (1, 0, True)
    assert stats["angles"]["min_degrees"] > 25
    assert np.abs(rounded_cylinder(V[F].mean(axis=1))).max() < 0.004


def test_creases_not_followed_come_with_a_crease_warning():
    # The warning as cdp.polygonize wraps the compiled function: stats whose crease layout failed
    # (creases.fallback) warn once, naming why; followed creases, creases ignored by request and a
    # smooth field do not.
    def meshed_with(creases):
        return cdp._warns_where_the_mesh_falls_short(lambda: cdp.Mesh(None, None, None, {"creases": creases}))

    failed = {"handling": "follow", "followed": False, "fallback": "adaptive: a crease ends without a corner"}
    with pytest.warns(cdp.CreaseWarning, match=r"creases are not followed.*a crease ends without a corner"):
        meshed_with(failed)()
    # A ball capped by a sheet whose crease fades out where its pieces become tangent: its layout
    # fails (the C++ test AdaptiveCreases.ALayoutThatFailsFallsBackToSmoothMeshingAndSaysWhy).
    capped = cdp.expression("max(max(z, z+x*abs(y)), sqrt(x^2+y^2+z^2)-1)", ((-1.5, -1.5, -1.5), (1.5, 1.5, 1.5)))
    with pytest.warns(cdp.CreaseWarning, match=r"the surface is meshed across them as smooth \(adaptive: ") as said:
        mesh = cdp.polygonize(capped, factor=1)
    assert not mesh.stats["creases"]["followed"] and mesh.stats["creases"]["fallback"]
    assert said[0].filename == __file__  # the caller's line, not the package's
    with warnings.catch_warnings():
        warnings.simplefilter("error", cdp.CreaseWarning)
        meshed_with({"handling": "follow", "followed": True, "fallback": ""})()
        meshed_with({"handling": "ignore", "followed": False, "fallback": ""})()
        meshed_with({"handling": "follow", "followed": False, "fallback": ""})()  # no crease at all
        cdp.polygonize(cdp.sphere(1), factor=1)
        # The pin (a ball pierced by a rod of radius 0.02) follows its creases.
        pin = cdp.sdf.sphere(1) | cdp.sdf.capsule((0, 0, -1.5), (0, 0, 1.5), 0.02)
        assert cdp.polygonize(pin, factor=2).stats["creases"]["followed"]


def test_a_mesh_beyond_the_tolerance_comes_with_a_tolerance_warning():
    # The unit sphere with edges of at least 0.05 lies about 4.2e-4 from its chords: at a tolerance
    # of 4e-4 the refinement cannot split, and some triangles stay beyond it (the C++ test
    # AdaptiveTolerance.ReportsTheTrianglesFartherThanEpsMeasuredDensely counts them). The program
    # names them on stderr; Python callers get a warning, not only a number in the stats.
    sphere = cdp.sphere(1)
    with pytest.warns(cdp.ToleranceWarning, match=r"triangles lie farther from the surface than the tolerance 0.0004") as said:
        mesh = cdp.polygonize(sphere, tolerance=4e-4, min_edge=0.05)
    assert said[0].filename == __file__  # the caller's line, not the package's
    assert mesh.stats["quality"]["over_tolerance"] > 0
    # Within the tolerance, and in factor mode (no distance promised), no warning.
    with warnings.catch_warnings():
        warnings.simplefilter("error", cdp.ToleranceWarning)
        assert cdp.polygonize(sphere, tolerance=1e-3).stats["quality"]["over_tolerance"] == 0
        cdp.polygonize(sphere, factor=1, min_edge=0.05)
