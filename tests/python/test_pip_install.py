"""pip install . from the clone into a fresh virtual environment (--system-site-packages, for
Debian's numpy, setuptools and wheel; offline: --no-build-isolation --no-index), reusing the
CMake build directory this test's cdp was imported from (build/python/cdp), so that setup.py
only checks that cdp_python is up to date: about half a minute, most of it the venv and pip.
The installed package meshes a sphere from outside the source tree; pip uninstall removes it;
nothing is left in the clone."""
import json
import os
import pathlib
import re
import subprocess
import sys
import time

import pytest

import cdp

ROOT = pathlib.Path(__file__).resolve().parents[2]
# Where pip and setuptools would leave files in a clone (setup.py sends them to a temporary
# directory); "build" is the CMake build directory, whose own files are not looked at.
WATCHED = {ROOT: None, ROOT / "python": None, ROOT / "python" / "cdp": None, ROOT / "build": r"(lib|bdist|temp)\."}
LEFTOVER = re.compile(r".*\.(egg-info|dist-info|whl|so)$|^(dist|build-pip|_version\.py)$")

CHECK = """
import json, sys
import numpy as np
import cdp
from cdp import _version
mesh = cdp.polygonize(cdp.sphere(1.0))
V, F = mesh[0], mesh[1]
print(json.dumps({"file": cdp.__file__, "version": _version.__version__, "vertices": len(V), "faces": len(F),
                  "radius_error": float(np.abs(np.linalg.norm(V, axis=1) - 1).max()), "prefix": sys.prefix}))
"""


def leftovers():
    found = set()
    for folder, pattern in WATCHED.items():
        if folder.is_dir():
            for entry in folder.iterdir():
                if (pattern and re.match(pattern, entry.name)) or (not pattern and LEFTOVER.match(entry.name)):
                    found.add(entry)
    return found


def run(args, **kwargs):
    result = subprocess.run(args, capture_output=True, text=True, **kwargs)
    assert result.returncode == 0, f"{' '.join(map(str, args))} failed:\n{result.stdout}\n{result.stderr}"
    return result


@pytest.mark.slow
def test_pip_install_into_a_venv_meshes_a_sphere(tmp_path):
    build_dir = pathlib.Path(cdp.__file__).resolve().parents[2]
    if not (build_dir / "CMakeCache.txt").exists():
        pytest.fail(f"cdp was not imported from a CMake build tree ({cdp.__file__}); run with PYTHONPATH=build/python")
    version = re.search(r"project\(\s*cdp\s+VERSION\s+([0-9.]+)", (ROOT / "CMakeLists.txt").read_text()).group(1)
    before = leftovers()

    venv = tmp_path / "venv"
    run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)])
    python = venv / "bin" / "python"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env.update(CDP_BUILD_DIR=str(build_dir), PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_NO_INPUT="1")
    start = time.monotonic()
    run([python, "-m", "pip", "install", "--no-build-isolation", "--no-deps", "--no-index", str(ROOT)],
        env=env, cwd=tmp_path)
    print(f"pip install: {time.monotonic() - start:.1f} s")

    # From outside the clone, so that nothing of the source tree is on sys.path.
    result = json.loads(run([python, "-c", CHECK], env=env, cwd=tmp_path).stdout)
    package = pathlib.Path(result["file"]).parent
    assert package.is_relative_to(venv), result["file"]
    assert result["version"] == version
    assert result["faces"] > 100 and result["radius_error"] < 1e-6, result
    for name in ("_cdp.pyi", "__init__.pyi", "py.typed", "sdf.py", "trace.py", "_version.py"):
        assert (package / name).exists(), f"{name} was not installed"
    metadata = run([python, "-m", "pip", "show", "cdp"], env=env, cwd=tmp_path).stdout
    assert f"Version: {version}" in metadata

    run([python, "-m", "pip", "uninstall", "-y", "cdp"], env=env, cwd=tmp_path)
    assert not package.exists(), f"pip uninstall left {sorted(p.name for p in package.iterdir())}"
    gone = subprocess.run([python, "-c", "import cdp; print(cdp.__file__)"], capture_output=True, text=True,
                          env=env, cwd=tmp_path)
    assert gone.returncode != 0 or not pathlib.Path(gone.stdout.strip()).is_relative_to(venv)
    assert leftovers() == before, f"left in the clone: {sorted(map(str, leftovers() - before))}"
