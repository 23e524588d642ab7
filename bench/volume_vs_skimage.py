#!/usr/bin/python3
"""BM_VolumeVsSkimage: one sampled volume meshed by cdp's adaptive polygonizer (cdp.volume_field,
a tricubic B-spline through the samples) and by scikit-image's marching_cubes (linear along the
cells' edges), compared at the same accuracy. Installed as build/bin/bench_volume_vs_skimage and
run by scripts/run_benchmarks.py like the C++ programs: it takes Google Benchmark's flags and
writes its JSON (manual time: real_time is the run's wall time).

The volume: the signed distance to a torus (radii 1 and 0.4) sampled on a 48^3 grid over
[-1.6, 1.6]^3, so the true surface is known. Each mesh's error is the distance to the true torus of 16 points
of each triangle (corners, points on the edges, inside; mean and max). scikit-image meshes the samples once; ours is run at tolerances
from coarse to fine and the first whose mean error is at most scikit-image's is "at the same
accuracy". Counters: triangles, smallest angle (degrees), share of triangles under 30 degrees,
mean and max error; for ours also the tolerance and the ratios of triangles and time to
scikit-image's (the same repetition).
"""
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "python"))  # build/python beside build/bin

import numpy as np  # noqa: E402

import _gbench  # noqa: E402  (bench/_gbench.py, beside this file in build/bin)

NAME = "BM_VolumeVsSkimage/torus_n48"
TOLERANCES = (3.2e-2, 1.6e-2, 8e-3, 4e-3, 2e-3, 1e-3, 5e-4)


def torus_distance(P):
    return np.hypot(np.hypot(P[:, 0], P[:, 1]) - 1.0, P[:, 2]) - 0.4


def smallest_angles(V, F):
    P = V[F]
    angles = []
    for i in range(3):
        a, b = P[:, (i + 1) % 3] - P[:, i], P[:, (i + 2) % 3] - P[:, i]
        with np.errstate(invalid="ignore", divide="ignore"):
            cos = (a * b).sum(1) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))
        angles.append(np.degrees(np.arccos(np.clip(np.nan_to_num(cos, nan=1.0), -1, 1))))
    return np.min(angles, axis=0)


# Where on each triangle the error is measured (barycentric): the corners, the edges' midpoints
# and quarter points, the centroid and the points halfway from it to the corners. The corners
# alone would hide a coarse mesh's chords: ours are projected onto the surface.
SAMPLES = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [.5, .5, 0], [0, .5, .5], [.5, 0, .5], [.75, .25, 0],
                    [.25, .75, 0], [0, .75, .25], [0, .25, .75], [.25, 0, .75], [.75, 0, .25], [1 / 3, 1 / 3, 1 / 3],
                    [2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6], [1 / 6, 1 / 6, 2 / 3]])


def figures(V, F, seconds):
    angles = smallest_angles(V, F)
    error = np.abs(torus_distance(np.einsum("sk,tkd->tsd", SAMPLES, V[F]).reshape(-1, 3)))
    return {"real_time": seconds * 1e3, "triangles": float(len(F)), "smallest_angle": float(angles.min()),
            "share_under_30": float(np.mean(angles < 30)), "mean_error": float(error.mean()),
            "max_error": float(error.max())}


def one_repetition():
    import cdp
    from skimage import measure
    n, half = 48, 1.6
    g = np.linspace(-half, half, n)
    X, Y, Z = np.meshgrid(g, g, g, indexing="ij")
    samples = torus_distance(np.stack([X.ravel(), Y.ravel(), Z.ravel()], axis=1)).reshape(X.shape)
    spacing = 2 * half / (n - 1)

    start = time.perf_counter()
    V, F, _, _ = measure.marching_cubes(samples, level=0.0, spacing=(spacing,) * 3)
    seconds = time.perf_counter() - start
    skimage = figures(V - half, F, seconds)

    field = cdp.volume_field(samples, ((-half,) * 3, (half,) * 3))
    ours = None
    for tolerance in TOLERANCES:
        start = time.perf_counter()
        mesh = cdp.polygonize(field, tolerance=tolerance)
        seconds = time.perf_counter() - start
        ours = dict(figures(mesh.vertices, mesh.faces, seconds), tolerance=tolerance)
        if ours["mean_error"] <= skimage["mean_error"]:
            break
    ours["triangles_vs_skimage"] = ours["triangles"] / skimage["triangles"]
    ours["time_vs_skimage"] = ours["real_time"] / skimage["real_time"]
    return {NAME + "/skimage_marching_cubes": skimage, NAME + "/adaptive_same_error": ours}


if __name__ == "__main__":
    sys.exit(_gbench.main(__doc__, [NAME + "/skimage_marching_cubes", NAME + "/adaptive_same_error"], one_repetition))
