"""examples/mesh_numpy_implicit.py runs and writes what it says."""
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
