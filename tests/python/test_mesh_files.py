"""read_mesh and write_mesh: bit-for-bit round trips, and what is refused, as which exception."""
import os

import numpy as np
import pytest

import cdp


@pytest.fixture(scope="module")
def mesh():
    V, F, N, _ = cdp.polygonize(cdp.torus(major_radius=1, minor_radius=0.4), factor=2)
    return V, F, N


@pytest.mark.parametrize("name, binary", [("m.ply", True), ("m.ply", False), ("m.obj", True), ("m.off", True)])
def test_round_trip_bit_for_bit(tmp_path, mesh, name, binary):
    V, F, N = mesh
    path = tmp_path / name
    cdp.write_mesh(path, V, F, N if name != "m.off" else None, binary=binary)
    V2, F2, N2 = cdp.read_mesh(path, return_normals=True)
    assert V2.tobytes() == V.tobytes() and F2.tobytes() == F.tobytes()
    if name == "m.off":
        assert N2 is None
    else:
        assert N2.tobytes() == N.tobytes()
    V3, F3 = cdp.read_mesh(str(path))
    assert V3.tobytes() == V.tobytes()


def test_stl_is_float32(tmp_path, mesh):
    V, F, _ = mesh
    cdp.write_mesh(tmp_path / "m.stl", V, F)
    V2, F2, N2 = cdp.read_mesh(tmp_path / "m.stl", return_normals=True)
    assert N2 is None  # STL holds face normals only
    assert len(F2) == len(F)
    assert np.abs(V2[F2] - V[F]).max() < 1e-6


def test_files_that_cannot_be_opened_or_written_are_os_errors(tmp_path, mesh):
    V, F, _ = mesh
    missing = tmp_path / "missing.ply"
    with pytest.raises(FileNotFoundError) as e:
        cdp.read_mesh(missing)
    assert str(e.value) == f"{missing}: file not found" and e.value.errno == 2
    with pytest.raises(IsADirectoryError) as e:
        cdp.read_mesh(tmp_path)
    assert str(e.value) == f"{tmp_path}: is a directory, not a mesh file"
    nowhere = tmp_path / "no" / "such" / "folder.ply"
    with pytest.raises(FileNotFoundError) as e:
        cdp.write_mesh(nowhere, V, F)
    assert str(e.value) == f"{nowhere}: cannot write mesh: No such file or directory"
    assert not nowhere.parent.exists()
    if os.geteuid() != 0:  # root writes anywhere
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        with pytest.raises(PermissionError):
            cdp.write_mesh(locked / "m.ply", V, F)


def test_malformed_files_and_arrays_are_value_errors(tmp_path, mesh):
    V, F, N = mesh
    bad = tmp_path / "bad.ply"
    bad.write_bytes(b"plx\n")
    with pytest.raises(ValueError) as e:
        cdp.read_mesh(bad)
    assert str(e.value) == f'{bad}: not a PLY file (it does not start with "ply")'
    (tmp_path / "m.xyz").write_text("0 0 0\n")
    with pytest.raises(ValueError) as e:
        cdp.read_mesh(tmp_path / "m.xyz")
    assert str(e.value) == f'{tmp_path / "m.xyz"}: unsupported mesh format ".xyz" (.ply, .obj, .off or .stl)'
    out = tmp_path / "out.ply"
    cases = [
        ((V, F + len(V)), f"faces: face 0 refers to vertex {F[0, 0] + len(V)} of {len(V)}"),
        ((V, F.astype(float)), "faces: expected integer vertex indices, found dtype float64"),
        ((V[:, :2], F), "vertices: expected an array of shape (N, 3), found shape "
                        f"({len(V)}, 2)"),
        ((np.where(np.arange(len(V))[:, None] == 3, np.nan, V), F),
         "vertices: vertex 3 has a coordinate that is not a finite number"),
        ((V, F, N[:-1]), f"normals: {len(V) - 1} normals for {len(V)} vertices"),
        ((V, F[:0]), "faces: the mesh has no triangles"),
    ]
    for args, message in cases:
        with pytest.raises(ValueError) as e:
            cdp.write_mesh(out, *args)
        assert str(e.value) == message
    assert not out.exists()
    with pytest.raises(ValueError) as e:
        cdp.write_mesh(tmp_path / "m.xyz", V, F)
    assert str(e.value) == f'{tmp_path / "m.xyz"}: cannot write mesh: unsupported extension ".xyz" (.ply, .obj, .off or .stl)'
