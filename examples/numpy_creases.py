#!/usr/bin/python3
"""Mesh a numpy function with sharp creases: a gyroid clipped by a ball.

    PYTHONPATH=build/python /usr/bin/python3 examples/numpy_creases.py [--out DIR] [--factor K] [--black-box]

The function is plain numpy, as one writes it for scikit-image's marching cubes. cdp.callable_field
traces it (cdp.trace: called once on symbols, it becomes an expression with exact derivatives,
and np.maximum's creases, where the gyroid's sheets cut the sphere, are known), so the adaptive
polygonizer meshes along the creases. With --black-box the function is called on every batch
of points instead: the creases are unknown, and the run stops at its first failure saying so.
Writes DIR/gyroid_ball.ply and draws DIR/gyroid_ball.png with build/bin/render when that program
is built (it says so and skips the picture otherwise).
"""
import argparse
import pathlib
import subprocess
import sys
import time

import numpy as np

import cdp

ROOT = pathlib.Path(__file__).resolve().parents[1]


def gyroid_ball(p):
    """F on an (N, 3) array: a gyroid of period 2 pi / 6 inside the unit ball."""
    q = 6 * p
    g = np.sin(q[:, 0]) * np.cos(q[:, 1]) + np.sin(q[:, 1]) * np.cos(q[:, 2]) + np.sin(q[:, 2]) * np.cos(q[:, 0])
    return np.maximum(g / 6, np.linalg.norm(p, axis=1) - 1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("."), help="output folder (default: .)")
    parser.add_argument("--factor", type=float, default=3, help="the paper's heuristic factor (default 3)")
    parser.add_argument("--black-box", action="store_true", help="do not trace the function (see above)")
    parser.add_argument("--render", type=pathlib.Path, default=ROOT / "build" / "bin" / "render",
                        help="the render program (default: build/bin/render of this tree)")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    bounds = ((-1.1, -1.1, -1.1), (1.1, 1.1, 1.1))
    field = cdp.callable_field(gyroid_ball, bounds, trace=not args.black_box)
    print("traced: an expression field" if field.type == "expression" else "a black box: called on every batch")
    start = time.perf_counter()
    try:
        V, F, _, stats = cdp.polygonize(field, factor=args.factor)
    except (cdp.LimitExceededError, cdp.NoSurfaceError) as e:
        print(f"failed after {time.perf_counter() - start:.2f} s: {e}")
        return 1
    creases = stats["creases"]
    print(f"{stats['triangles']} triangles in {time.perf_counter() - start:.2f} s, {stats['components']} component(s), "
          f"minimum angle {stats['min_angle_degrees']:.1f} deg; {creases['curves']} crease curves "
          f"{'followed' if creases['followed'] else 'not followed'}")
    mesh_path = args.out / "gyroid_ball.ply"
    cdp.write_mesh(mesh_path, V, F)
    print(f"wrote {mesh_path}")
    if not args.render.exists():
        print(f"no picture: {args.render} is not built (cmake --build build --target render)")
        return 0
    picture = args.out / "gyroid_ball.png"
    subprocess.run([args.render, mesh_path, "-o", picture, "--wireframe", "--elevation", "30", "--width", "800",
                    "--height", "600"], check=True, stdout=subprocess.DEVNULL)
    print(f"wrote {picture}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
