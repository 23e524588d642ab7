"""cdp.volume_field and the JSON type "volume": sampled volumes (numpy arrays, .npy and NRRD
files) as fields, meshed within their interpolation error with their topology."""
import gzip
import json
import subprocess

import numpy as np
import pytest

import cdp

from conftest import program, topology


def grid(n, half):
    g = np.linspace(-half, half, n)
    return np.meshgrid(g, g, g, indexing="ij")


def torus_distance(X, Y, Z):
    return np.hypot(np.hypot(X, Y) - 1.0, Z) - 0.4


def interpolation_error(field, distance, half, band):
    """The largest |S - d| at random points within `band` of the surface: how far the
    interpolant's zero set may lie from the sampled one (|grad d| = 1)."""
    rng = np.random.default_rng(4)
    P = rng.uniform(-half, half, (400000, 3))
    d = distance(*P.T)
    P, d = P[np.abs(d) < band], d[np.abs(d) < band]
    return np.abs(field.values(P) - d).max()


@pytest.mark.parametrize("n", [20, 32, 48])
def test_a_sampled_torus_meshes_within_its_interpolation_error(n):
    X, Y, Z = grid(n, 1.6)
    field = cdp.volume_field(torus_distance(X, Y, Z), ((-1.6,) * 3, (1.6,) * 3))
    assert field.type == "volume" and field.smooth
    V, F, N, stats = cdp.polygonize(field)
    assert topology(V, F) == (1, 1, True)
    assert stats["summary"]["watertight"] and stats["summary"]["genus"] == 1
    error = interpolation_error(field, torus_distance, 1.6, 2 * 3.2 / (n - 1))
    assert np.abs(torus_distance(*V.T)).max() <= 1.5 * error + 1e-9
    assert stats["creases"]["curves"] == 0


def test_a_noisy_density_meshes_closed():
    # Two Gaussian blobs as a density (inside above the level) with 1% noise, as a scan gives.
    X, Y, Z = grid(40, 2.0)
    density = np.exp(-((X - 0.5) ** 2 + Y ** 2 + Z ** 2) / 0.4) + np.exp(-((X + 0.5) ** 2 + Y ** 2 + Z ** 2) / 0.4)
    density += np.random.default_rng(7).normal(0, 0.01, density.shape)
    field = cdp.volume_field(density, ((-2,) * 3, (2,) * 3), level=0.5, inside="above")
    V, F, _, stats = cdp.polygonize(field, factor=2)
    assert topology(V, F) == (1, 0, True)
    assert stats["summary"]["watertight"] and stats["summary"]["smallest_angle_degrees"] > 10
    assert np.abs(field.values(V)).max() < 1e-6


def test_spacing_and_origin_place_the_grid():
    X, Y, Z = grid(24, 1.5)
    d = np.sqrt(X ** 2 + Y ** 2 + Z ** 2) - 1.0
    step = 3.0 / 23
    placed = cdp.volume_field(d, spacing=step, origin=(-1.5 + 10, -1.5, -1.5))
    assert np.allclose(placed.bounds, [[8.5, -1.5, -1.5], [11.5, 1.5, 1.5]])
    V = cdp.polygonize(placed).vertices
    assert np.abs(np.linalg.norm(V - (10, 0, 0), axis=1) - 1).max() < 1e-3
    stretched = cdp.volume_field(d, spacing=(2 * step, step, step), origin=(-3, -1.5, -1.5))
    assert np.allclose(stretched.bounds[1], [3, 1.5, 1.5])


def test_bad_volumes_are_value_errors_naming_the_problem():
    X, Y, Z = grid(8, 1.5)
    d = np.sqrt(X ** 2 + Y ** 2 + Z ** 2) - 1.0
    box = ((-1.5,) * 3, (1.5,) * 3)
    cases = [
        (lambda: cdp.volume_field(d[0], box), "values must be a 3-D array, not 2-D"),
        (lambda: cdp.volume_field(d[:, :, :3], box), "at least 4 samples along each axis, found 3 along z"),
        (lambda: cdp.volume_field(np.where(X > 1, np.nan, d), box), "is not finite"),
        (lambda: cdp.volume_field(d - 5, box), "the interpolant reaches the level on the grid's faces"),
        (lambda: cdp.volume_field(d, box, inside="inside"), 'inside must be "below" or "above"'),
        (lambda: cdp.volume_field(d, box, spacing=0.1), "either bounds or spacing and origin"),
        (lambda: cdp.volume_field(d, spacing=-1), "spacing must be positive"),
        (lambda: cdp.volume_field(d, origin=(0, 0)), "origin must be one point"),
        (lambda: cdp.volume_field("not numbers", box), "cdp.volume_field"),
    ]
    for make, words in cases:
        with pytest.raises(ValueError) as e:
            make()
        assert words in str(e.value), (words, str(e.value))


def write_nrrd(path, array, encoding="raw", directions=None, origin=(0, 0, 0), dtype="<i2", type_name="short"):
    """A 3-D array as NRRD: its first axis varies fastest there (Fortran order)."""
    data = np.asfortranarray(array.astype(dtype)).tobytes(order="F")
    if encoding == "gzip":
        data = gzip.compress(data)
    directions = directions or [(1, 0, 0), (0, 1, 0), (0, 0, 1)]
    header = ["NRRD0004", "# written by test_volume.py", f"type: {type_name}", "dimension: 3",
              "sizes: " + " ".join(str(s) for s in array.shape), "space: left-posterior-superior",
              "space directions: " + " ".join("(%r,%r,%r)" % tuple(map(float, v)) for v in directions),
              "kinds: domain domain domain", "endian: " + ("big" if dtype.startswith(">") else "little"),
              f"encoding: {encoding}", "space origin: (%r,%r,%r)" % tuple(map(float, origin))]
    path.write_bytes(("\n".join(header) + "\n\n").encode() + data)


def sampled_at_nodes(field, shape, origin, spacing):
    idx = np.stack(np.meshgrid(*[np.arange(s) for s in shape], indexing="ij"), axis=-1).reshape(-1, 3)
    return field.values(np.asarray(origin) + idx * np.asarray(spacing)).reshape(shape)


def test_npy_and_nrrd_files_give_the_arrays_they_hold(tmp_path):
    rng = np.random.default_rng(2)
    a = rng.integers(0, 100, (6, 7, 8)).astype(np.int16)
    # Outside (below 0, the inside being above) in the two layers next to each face; random within.
    a[[0, 1, -2, -1], :, :] = a[:, [0, 1, -2, -1], :] = a[:, :, [0, 1, -2, -1]] = -1000
    a[2:4, 3:5, 3:5] = -100
    for name, array in [("c.npy", a.astype("<f8")), ("f.npy", np.asfortranarray(a.astype("<f4"))),
                        ("big.npy", a.astype(">i2")), ("bytes.npy", np.clip(a + 100, 0, 255).astype(np.uint8))]:
        np.save(tmp_path / name, array)
        level = 100 if name == "bytes.npy" else 0
        field = cdp.field_from_json({"type": "volume", "file": name, "level": level, "inside": "above"}, tmp_path)
        assert np.allclose(sampled_at_nodes(field, a.shape, (0, 0, 0), (1, 1, 1)), level - array.astype(float),
                           atol=1e-9), name
    # NRRD: raw and gzip, with spacing and origin, and an axis whose direction is negative (flipped).
    write_nrrd(tmp_path / "raw.nrrd", a, directions=[(0.5, 0, 0), (0, 2, 0), (0, 0, 1)], origin=(1, 2, 3))
    write_nrrd(tmp_path / "gz.nrrd", a, encoding="gzip", directions=[(0.5, 0, 0), (0, 2, 0), (0, 0, 1)], origin=(1, 2, 3))
    for name in ("raw.nrrd", "gz.nrrd"):
        field = cdp.field_from_json({"type": "volume", "file": name, "inside": "above"}, tmp_path)
        assert np.allclose(field.bounds, [[1, 2, 3], [1 + 5 * 0.5, 2 + 6 * 2, 3 + 7]])
        assert np.allclose(sampled_at_nodes(field, a.shape, (1, 2, 3), (0.5, 2, 1)), -a, atol=1e-9)
    write_nrrd(tmp_path / "flip.nrrd", a, directions=[(-0.5, 0, 0), (0, 2, 0), (0, 0, 1)], origin=(1, 2, 3))
    field = cdp.field_from_json({"type": "volume", "file": "flip.nrrd", "inside": "above"}, tmp_path)
    assert np.allclose(field.bounds[0], [1 - 5 * 0.5, 2, 3])
    assert np.allclose(sampled_at_nodes(field, a.shape, (1 - 2.5, 2, 3), (0.5, 2, 1)), -a[::-1], atol=1e-9)
    # "bounds" places an .npy grid.
    field = cdp.field_from_json({"type": "volume", "file": "c.npy", "inside": "above",
                                 "bounds": [[0, 0, 0], [5, 12, 14]]}, tmp_path)
    assert np.allclose(sampled_at_nodes(field, a.shape, (0, 0, 0), (1, 2, 2)), -a, atol=1e-9)


def test_bad_volume_files_are_one_line_errors(tmp_path):
    a = np.full((5, 5, 5), 1.0)
    np.save(tmp_path / "flat.npy", a[0])
    np.save(tmp_path / "complex.npy", a.astype(np.complex128))
    (tmp_path / "short.npy").write_bytes((tmp_path / "flat.npy").read_bytes()[:-10])
    write_nrrd(tmp_path / "skew.nrrd", a, directions=[(1, 0.1, 0), (0, 1, 0), (0, 0, 1)])
    raw = tmp_path / "cut.nrrd"
    write_nrrd(raw, a)
    raw.write_bytes(raw.read_bytes()[:-8])
    (tmp_path / "x.vti").write_text("<VTKFile/>")
    np.save(tmp_path / "ok.npy", a)
    cases = [("flat.npy", "a volume needs a 3-D array, found 2 dimensions"),
             ("complex.npy", "not a real, integer or bool scalar"),
             ("skew.nrrd", "not axis-aligned"),
             ("cut.nrrd", "truncated NRRD data"),
             ("x.vti", 'unknown volume format ".vti"'),
             ("missing.npy", "missing.npy"),
             ("ok.npy", "the interpolant reaches the level on the grid's faces")]
    for name, words in cases:
        with pytest.raises((ValueError, OSError)) as e:  # a missing file is FileNotFoundError
            cdp.field_from_json({"type": "volume", "file": name, "level": 2.0}, tmp_path)
        assert words in str(e.value) and "\n" not in str(e.value), (name, str(e.value))
    with pytest.raises(ValueError, match="give either bounds or origin and spacing"):
        cdp.field_from_json({"type": "volume", "file": "ok.npy", "level": 0.5, "spacing": 1,
                             "bounds": [[0, 0, 0], [1, 1, 1]]}, tmp_path)


def test_the_program_meshes_a_volume_file_as_python_does(tmp_path):
    X, Y, Z = grid(28, 1.6)
    np.save(tmp_path / "torus.npy", torus_distance(X, Y, Z).astype(np.float32))
    spec = {"type": "volume", "file": "torus.npy", "bounds": [[-1.6, -1.6, -1.6], [1.6, 1.6, 1.6]]}
    (tmp_path / "torus.json").write_text(json.dumps(spec))
    subprocess.run([program("polygonize"), str(tmp_path / "torus.json"), "-o", str(tmp_path / "t.ply"), "--quiet"],
                   check=True)
    V, F = cdp.read_mesh(tmp_path / "t.ply")
    mesh = cdp.polygonize(cdp.field_from_json(spec, tmp_path))
    assert np.array_equal(V, mesh.vertices) and np.array_equal(F, mesh.faces)
    assert topology(V, F) == (1, 1, True)
