"""Shared helpers of the cdp module's tests (run with /usr/bin/python3 -m pytest tests/python,
PYTHONPATH=build/python; ctest sets both)."""
import os
import pathlib

import numpy as np
import pytest

import cdp  # noqa: F401  (a missing PYTHONPATH fails here, before any test)

ROOT = pathlib.Path(__file__).resolve().parents[2]
BIN = pathlib.Path(os.environ.get("CDP_BIN_DIR", ROOT / "build" / "bin"))


def pytest_configure(config):
    # ctest runs the tests marked slow as python.pytest_slow (label slow: make test-slow) and the
    # rest as python.pytest (make test); pytest alone runs both.
    config.addinivalue_line("markers", "slow: a test of a second or more that make test leaves to make test-slow")


def program(name):
    path = BIN / name
    if not path.exists():
        pytest.fail(f"{path} is not built (cmake --build build --target {name})")
    return path


def topology(vertices, faces):
    """(components, genus, closed) of a triangle mesh: components through shared edges, genus
    from the Euler characteristic V - E + F = sum over components of (2 - 2 g)."""
    faces = np.asarray(faces, dtype=np.int64)
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    unique, uses = np.unique(edges, axis=0, return_counts=True)
    closed = bool(np.all(uses == 2))
    used = np.unique(faces)
    parent = np.arange(len(vertices))

    def find(i):
        root = i
        while parent[root] != root:
            root = parent[root]
        while parent[i] != root:
            parent[i], i = root, parent[i]
        return root

    for a, b in unique:
        ra, rb = find(a), find(b)
        if ra != rb:
            parent[ra] = rb
    components = len({find(v) for v in used})
    euler = len(used) - len(unique) + len(faces)
    return components, (2 * components - euler) // 2, closed


def nearest_distances(a, b, chunk=512):
    """For every row of a, the distance to the nearest row of b (brute force, small meshes)."""
    out = np.empty(len(a))
    for i in range(0, len(a), chunk):
        d = np.linalg.norm(a[i:i + chunk, None, :] - b[None, :, :], axis=2)
        out[i:i + chunk] = d.min(axis=1)
    return out
