#!/usr/bin/python3
"""Mesh signed distance models written with cdp.sdf (fogleman/sdf's way of modelling).

    PYTHONPATH=build/python /usr/bin/python3 examples/sdf_models.py [--out DIR] [--tolerance EPS] [--only NAME ...]

Each model is built from primitives and operators, rendered to one `expression` field (exact
derivatives, creases known at every min/max/abs), meshed by the adaptive polygonizer within a
chord tolerance, written to DIR/NAME.ply with its field file DIR/NAME.json (so that
`build/bin/polygonize DIR/NAME.json -o OUT.ply --tolerance EPS` meshes the same model) and
drawn to DIR/NAME.png by build/bin/render when that program is built (it says so and skips the
pictures otherwise). A model the mesher fails on is reported and the others still run; the exit
status is 1 then.
"""
import argparse
import pathlib
import subprocess
import sys
import time

import cdp
from cdp.sdf import X, Y, Z, box, capsule, cylinder, rounded_box, sphere, union

ROOT = pathlib.Path(__file__).resolve().parents[1]


def fogleman():
    """fogleman/sdf's README model: a sphere and a cube intersected, three cylinders drilled through."""
    f = sphere(1) & box(1.5)
    c = cylinder(0.5)
    return f - (c.orient(X) | c.orient(Y) | c.orient(Z))


def blended_block():
    """A rounded box smoothly united with a sphere, a hole with sharp rims drilled through it."""
    block = rounded_box((1.6, 1.0, 0.6), 0.12)
    knob = sphere(0.4, center=(0.3, 0, 0.3))
    return block.union(knob, k=0.25) - cylinder(0.15).orient(Y).translate((-0.4, 0, 0))


def capsule_chain():
    """Five capsules in a zigzag, each smoothly united with the next."""
    joints = [(-1.0, 0.0, 0.0), (-0.5, 0.45, 0.1), (0.0, 0.0, 0.2), (0.5, 0.45, 0.1), (1.0, 0.0, 0.0), (1.2, -0.5, 0.0)]
    links = [capsule(a, b, 0.12 + 0.02 * i) for i, (a, b) in enumerate(zip(joints, joints[1:]))]
    return union(*links, k=0.15)


def studded_plate():
    """A plate with a 3 x 3 grid of half spheres (one sphere repeated) smoothly united with it."""
    studs = sphere(0.25).repeat(0.7, count=(1, 1, 0)).translate((0, 0, 0.1))
    return box((2.2, 2.2, 0.2)).union(studs, k=0.1)


MODELS = {"fogleman": fogleman, "blended_block": blended_block, "capsule_chain": capsule_chain,
          "studded_plate": studded_plate}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("."), help="output folder (default: .)")
    parser.add_argument("--tolerance", type=float, default=1e-3, help="chord tolerance (default 1e-3)")
    parser.add_argument("--only", nargs="+", choices=sorted(MODELS), help="mesh only these models")
    parser.add_argument("--render", type=pathlib.Path, default=ROOT / "build" / "bin" / "render",
                        help="the render program (default: build/bin/render of this tree)")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    if not args.render.exists():
        print(f"no pictures: {args.render} is not built (cmake --build build --target render)")

    failed = []
    for name in args.only or MODELS:
        model = MODELS[name]()
        formula, define = model.formula()
        model.save(args.out / f"{name}.json")
        start = time.perf_counter()
        try:
            V, F, N, stats = cdp.polygonize(model, tolerance=args.tolerance)
        except (RuntimeError, ValueError) as e:  # cdp.NoSurfaceError, cdp.LimitExceededError, ...
            print(f"{name}: FAILED after {time.perf_counter() - start:.2f} s: {type(e).__name__}: {e}")
            failed.append(name)
            continue
        seconds = time.perf_counter() - start
        print(f"{name}: {seconds:.2f} s, {stats['triangles']} triangles, {stats['components']} component(s), "
              f"minimum angle {stats['min_angle_degrees']:.1f} deg; formula {len(formula)} characters "
              f"and {len(define)} definitions")
        mesh_path = args.out / f"{name}.ply"
        cdp.write_mesh(mesh_path, V, F, N)
        print(f"wrote {mesh_path}")
        if args.render.exists():
            picture = args.out / f"{name}.png"
            subprocess.run([args.render, mesh_path, "-o", picture, "--up", "z", "--azimuth", "30", "--elevation", "35",
                            "--wireframe", "--width", "800", "--height", "600"], check=True, stdout=subprocess.DEVNULL)
            print(f"wrote {picture}")
    if failed:
        print(f"failed: {', '.join(failed)}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
