#!/usr/bin/python3
"""results/figures/*.png: the paper's figures, polygonized by build/bin/polygonize and rendered
by build/bin/render (the project's own ray casting: Embree on the meshes), with captions in
results/figures/captions.json."""
import argparse
import concurrent.futures
import json
import os
import subprocess
import sys

from PIL import Image, ImageDraw

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIELDS = os.path.join(ROOT, "experiments", "fields")

# name: (field, polygonize arguments)
MESHES = {
    "igea_vis4004_k1": ("igea_vis4004.json", ["--factor", "1"]),
    "igea_vis4004_k2": ("igea_vis4004.json", ["--factor", "2"]),
    "igea_vis4004_k3": ("igea_vis4004.json", ["--factor", "3"]),
    "igea_vis4004_k5": ("igea_vis4004.json", ["--factor", "5"]),
    "bunny_mpu_k4": ("bunny_mpu.json", ["--factor", "4"]),
    "igea_mpu_k3": ("igea_mpu.json", ["--factor", "3"]),
    "horse_mpu_k4": ("horse_mpu.json", ["--factor", "4"]),
    "bunny_vis800_k2": ("bunny_vis800.json", ["--factor", "2"]),
    "bunny_vis800_mt1": ("bunny_vis800.json", ["--method", "mt", "--precision", "1"]),
    "bunny_vis2000_k3": ("bunny_vis2000.json", ["--factor", "3"]),
    "bunny_vis2000_k5": ("bunny_vis2000.json", ["--factor", "5"]),
}

# Figures: title, caption, and panels (mesh, render arguments, panel label).
FIGURES = [
    ("figure1_igea_vis4004.png", "Figure 1: Igea, VIS with 4004 constraints, four densities",
     "The Igea head as a variational implicit surface (2002 points, 4004 constraints) polygonized by our adaptive "
     "method at heuristic factors 1, 2, 3 and 5: triangles shrink where the curvature is high.",
     [("igea_vis4004_k1", ["--wireframe"], "k = 1"), ("igea_vis4004_k2", ["--wireframe"], "k = 2"),
      ("igea_vis4004_k3", ["--wireframe"], "k = 3"), ("igea_vis4004_k5", ["--wireframe"], "k = 5")]),
    ("figure2_bunny_mpu_curvature.png", "Figure 2: curvature measures on the bunny MPU model",
     "Shape index (left; −1 convex cup, +1 concave, 0 saddle) and maximum absolute curvature (right; log scale) "
     "computed from the field's Hessian at the vertices of our mesh of the bunny MPU implicit.",
     [("bunny_mpu_k4", ["--color", "shape_index"], "shape index"), ("bunny_mpu_k4", ["--color", "mac"], "MAC")]),
    ("figure3_horse_directions.png", "Figure 3: principal directions on the horse MPU model",
     "Directions of maximum (left) and minimum (right) principal curvature on the horse's head, drawn as short "
     "segments at mesh vertices.",
     [("horse_mpu_k4", ["--directions", "max", "--view", "head"], "k max"),
      ("horse_mpu_k4", ["--directions", "min", "--view", "head"], "k min")]),
    ("figure4_igea_mpu.png", "Figure 4: Igea MPU polygonized by our approach, and its MAC",
     "Our mesh of the Igea MPU implicit (left) and the maximum absolute curvature on it (right): small triangles "
     "where MAC is high.",
     [("igea_mpu_k3", ["--wireframe"], "mesh"), ("igea_mpu_k3", ["--color", "mac"], "MAC")]),
    ("figure9_mt_vs_ours.png", "Figure 9: Marching Tetrahedra against our method, close-up",
     "The bunny VIS-800 model: Marching Tetrahedra at precision 1 (left) and our method at factor 2 (right), at "
     "comparable triangle counts. MT's triangles follow the grid; ours follow the surface.",
     [("bunny_vis800_mt1", ["--wireframe", "--view", "closeup"], "MT"),
      ("bunny_vis800_k2", ["--wireframe", "--view", "closeup"], "ours")]),
    ("figure10_bunny_vis2000.png", "Figure 10: bunny VIS with 2000 constraints, two densities",
     "The Stanford bunny reconstructed as a VIS with 2000 constraints, polygonized at factors 3 and 5.",
     [("bunny_vis2000_k3", ["--wireframe"], "k = 3"), ("bunny_vis2000_k5", ["--wireframe"], "k = 5")]),
]


def run(cmd):
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError("{}: {}".format(" ".join(cmd), (r.stderr or r.stdout).strip().splitlines()[-1:]))
    return r


def make_mesh(build, out, name):
    field, args = MESHES[name]
    mesh = os.path.join(out, "meshes", name + ".ply")
    stats = os.path.join(out, "meshes", name + ".stats.json")
    run([os.path.join(build, "bin", "polygonize"), os.path.join(FIELDS, field), "-o", mesh, "--stats", stats] + args)
    with open(stats) as f:
        return name, json.load(f)


def render_panel(build, out, mesh, args, size):
    field = MESHES[mesh][0]
    img = os.path.join(out, "panels", "{}_{}.ppm".format(mesh, "_".join(a.strip("-") for a in args)))
    run([os.path.join(build, "bin", "render"), os.path.join(out, "meshes", mesh + ".ply"), "--field",
         os.path.join(FIELDS, field), "-o", img, "--size", "{0},{0}".format(size)] + args)
    return img


def compose(panels, labels, path):
    ims = [Image.open(p).convert("RGB") for p in panels]
    w, h = ims[0].size
    canvas = Image.new("RGB", (w * len(ims), h + 24), "white")
    draw = ImageDraw.Draw(canvas)
    for i, (im, label) in enumerate(zip(ims, labels)):
        canvas.paste(im, (i * w, 24))
        draw.text((i * w + 8, 6), label, fill="black")
    canvas.save(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--build", default="build")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--size", type=int, default=420)
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "figures"))
    a = ap.parse_args()
    os.makedirs(os.path.join(a.out, "meshes"), exist_ok=True)
    os.makedirs(os.path.join(a.out, "panels"), exist_ok=True)
    stats, failures = {}, []
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        for fut in [pool.submit(make_mesh, a.build, a.out, m) for m in MESHES]:
            try:
                name, s = fut.result()
                stats[name] = s
                print("figures: meshed {} ({} triangles, {:.1f} s)".format(name, s.get("triangles"), s.get("seconds", 0)),
                      flush=True)
            except RuntimeError as e:
                failures.append(str(e))
                print("figures: FAILED " + str(e), flush=True)
        captions = []
        for file, title, caption, panels in FIGURES:
            if any(p[0] not in stats for p in panels):
                captions.append({"file": file, "title": title, "caption": "Not produced: a mesh failed ({}).".format(
                    "; ".join(failures))})
                continue
            futs = [pool.submit(render_panel, a.build, a.out, m, args, a.size) for m, args, _ in panels]
            try:
                images = [f.result() for f in futs]
            except RuntimeError as e:
                captions.append({"file": file, "title": title, "caption": "Not produced: " + str(e)})
                continue
            compose(images, ["{} ({} triangles)".format(lbl, stats[m]["triangles"]) for m, _, lbl in panels],
                    os.path.join(a.out, file))
            captions.append({"file": file, "title": title, "caption": caption})
            print("figures: wrote " + file, flush=True)
    with open(os.path.join(a.out, "captions.json"), "w") as f:
        json.dump(captions, f, indent=1)
    if failures:
        sys.exit("figures: {} mesh(es) failed".format(len(failures)))


if __name__ == "__main__":
    main()
