"""The examples (examples/) run and write what they say."""
import os
import subprocess
import sys

import cdp

from conftest import ROOT, program, topology


def test_example_writes_a_mesh_and_a_picture(tmp_path):
    render = program("render")
    result = subprocess.run([sys.executable, ROOT / "examples" / "mesh_numpy_implicit.py", "--out", tmp_path,
                             "--render", render], check=True, capture_output=True, text=True, env=dict(os.environ))
    assert "Python calls" in result.stdout and "wrote" in result.stdout
    V, F = cdp.read_mesh(tmp_path / "wavy_torus.ply")
    assert topology(V, F) == (1, 1, True)
    assert (tmp_path / "wavy_torus.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_sdf_example_meshes_its_models(tmp_path):
    """examples/sdf_models.py, on its two quickest models (each well under a second)."""
    render = program("render")
    result = subprocess.run([sys.executable, ROOT / "examples" / "sdf_models.py", "--out", tmp_path, "--render", render,
                             "--only", "fogleman", "capsule_chain"], check=True, capture_output=True, text=True,
                            env=dict(os.environ))
    assert "fogleman:" in result.stdout and "minimum angle" in result.stdout and "FAILED" not in result.stdout
    for name, genus in (("fogleman", 5), ("capsule_chain", 0)):
        V, F = cdp.read_mesh(tmp_path / f"{name}.ply")
        assert topology(V, F) == (1, genus, True)
        assert cdp.field_from_json(tmp_path / f"{name}.json").type == "expression"
        assert (tmp_path / f"{name}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_numpy_creases_example_traces_and_follows_the_creases(tmp_path):
    """examples/numpy_creases.py: the gyroid ball written in numpy, traced, meshed along its creases."""
    render = program("render")
    result = subprocess.run([sys.executable, ROOT / "examples" / "numpy_creases.py", "--out", tmp_path, "--render",
                             render], check=True, capture_output=True, text=True, env=dict(os.environ))
    assert "traced" in result.stdout and "crease curves followed" in result.stdout
    V, F = cdp.read_mesh(tmp_path / "gyroid_ball.ply")
    assert topology(V, F) == (1, 13, True)
    assert (tmp_path / "gyroid_ball.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_volume_example_meshes_the_scan_and_compares_scikit_image(tmp_path):
    """examples/mesh_volume.py: nibabel's brain scan as a cdp.volume_field, beside skimage's marching cubes."""
    render = program("render")
    result = subprocess.run([sys.executable, ROOT / "examples" / "mesh_volume.py", "--out", tmp_path, "--render",
                             render], check=True, capture_output=True, text=True, env=dict(os.environ))
    assert "anatomical.nii" in result.stdout and "scikit-image:" in result.stdout
    assert "watertight True" in result.stdout
    V, F = cdp.read_mesh(tmp_path / "brain.ply")
    components, genus, closed = topology(V, F)
    assert closed and components == 1
    assert (tmp_path / "brain.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "report.txt").read_text().splitlines()[1].startswith("ours:")
