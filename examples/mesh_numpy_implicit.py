#!/usr/bin/python3
"""Mesh an implicit surface written in numpy with the paper's adaptive polygonizer.

    PYTHONPATH=build/python /usr/bin/python3 examples/mesh_numpy_implicit.py [--out DIR] [--factor K]

The surface is a torus whose tube swells and thins five times around the ring, so the edge
length (the minimum radius of curvature / factor) varies along it. The script prints the
statistics, writes DIR/wavy_torus.ply (float64, with field normals and the maximum absolute
curvature per vertex) and draws DIR/wavy_torus.png with build/bin/render, coloured by
curvature, when that program is built (it says so and skips the picture otherwise).
"""
import argparse
import pathlib
import subprocess
import sys
import time

import numpy as np

import cdp

ROOT = pathlib.Path(__file__).resolve().parents[1]


def wavy_torus(p):
    """F(x, y, z) on an (N, 3) array: negative inside, zero on the surface. Vectorised, as
    callable_field requires: one call evaluates a whole batch of points."""
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    ring = np.sqrt(x * x + y * y)
    tube = 0.3 + 0.1 * np.cos(5 * np.arctan2(y, x))
    return (ring - 1.0) ** 2 + z * z - tube ** 2


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("."), help="output folder (default: .)")
    parser.add_argument("--factor", type=float, default=3, help="the paper's heuristic factor (default 3)")
    parser.add_argument("--black-box", action="store_true",
                        help="call the function on every batch of points instead of tracing it (see cdp.trace)")
    parser.add_argument("--render", type=pathlib.Path, default=ROOT / "build" / "bin" / "render",
                        help="the render program (default: build/bin/render of this tree)")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    # Traced (cdp.trace): numpy arithmetic becomes an expression with exact derivatives, and no
    # Python runs while meshing. With --black-box, the function is called on every batch of
    # points and its derivatives come from central differences (python/README.md has the steps).
    field = cdp.callable_field(wavy_torus, bounds=((-1.5, -1.5, -0.5), (1.5, 1.5, 0.5)), trace=not args.black_box)
    start = time.perf_counter()
    V, F, N, stats = cdp.polygonize(field, method="adaptive", factor=args.factor)
    seconds = time.perf_counter() - start
    curvature = cdp.curvature(field, V)

    evaluations = stats["field_evaluations"]
    print(f"{stats['triangles']} triangles, {stats['vertices']} vertices, {stats['components']} component(s), "
          f"{stats['seeds']} seed(s), {stats['splits']} splits, {stats['merges']} merges, "
          f"minimum angle {stats['min_angle_degrees']:.1f} deg")
    print(f"{seconds:.2f} s; field evaluations: {evaluations['value']} values, "
          f"{evaluations['value_gradient']} value+gradient, {evaluations['gradient_hessian']} gradient+Hessian; "
          + (f"{field.python_calls} Python calls ({field.python_calls / stats['triangles']:.1f} per triangle)"
             if isinstance(field, cdp.CallableField) else "traced: no Python calls while meshing"))
    print(f"maximum absolute curvature on the mesh: {curvature['mac'].min():.3g} to {curvature['mac'].max():.3g}")

    mesh_path = args.out / "wavy_torus.ply"
    cdp.write_mesh(mesh_path, V, F, N, scalars={"mac": curvature["mac"]})
    print(f"wrote {mesh_path}")

    if not args.render.exists():
        print(f"no picture: {args.render} is not built (cmake --build build --target render)")
        return 0
    picture = args.out / "wavy_torus.png"
    subprocess.run([args.render, mesh_path, "-o", picture, "--color", "mac", "--wireframe", "--elevation", "35",
                    "--width", "800", "--height", "600"], check=True, stdout=subprocess.DEVNULL)
    print(f"wrote {picture}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
