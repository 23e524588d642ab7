#!/usr/bin/python3
"""results/figures/*.png: the paper's rendered figures. Meshes come from build/bin/polygonize (or,
where an experiment already made the same mesh, from results/<experiment>/meshes/); panels are
rendered by build/bin/render (Embree ray casting of the mesh, see apps/README.md) and laid out
with matplotlib, which also draws the colour bars. Captions go to results/figures/captions.json,
which scripts/results_readme.py puts on the results page.

A figure whose mesh cannot be made (no polygonize program, a failing or slow polygonization)
is skipped with its reason, printed and written as its caption; the script still exits 0 unless
--strict is given, so one missing model does not stop `make reproduce`."""
import argparse
import concurrent.futures
import json
import math
import os
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.cm  # noqa: E402
import matplotlib.colors  # noqa: E402
import matplotlib.image  # noqa: E402
import matplotlib.ticker  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIELDS = os.path.join(ROOT, "experiments", "fields")

# name: field file, polygonize arguments, and meshes an experiment may already have written
# (same field, same arguments), tried first. Adaptive meshes carry the curvature properties
# (--curvature: vertex scalars "mac" and "shape_index") for the colour maps.
MESHES = {
    "igea_vis4004_k1": ("igea_vis4004.json", ["--factor", "1", "--curvature"], []),
    "igea_vis4004_k2": ("igea_vis4004.json", ["--factor", "2", "--curvature"], []),
    "igea_vis4004_k3": ("igea_vis4004.json", ["--factor", "3", "--curvature"], []),
    "igea_vis4004_k5": ("igea_vis4004.json", ["--factor", "5", "--curvature"], []),
    "bunny_mpu_k3": ("bunny_mpu.json", ["--factor", "3", "--curvature"], []),
    "igea_mpu_k3": ("igea_mpu.json", ["--factor", "3", "--curvature"], []),
    "horse_mpu_k3": ("horse_mpu.json", ["--factor", "3", "--curvature"], []),
    "bunny_vis800_k2": ("bunny_vis800.json", ["--factor", "2"], ["table1/meshes/adaptive_factor2.ply"]),
    "bunny_vis800_mt1": ("bunny_vis800.json", ["--method", "mt", "--precision", "1"], ["table1/meshes/mt_precision1.ply"]),
    "bunny_vis2000_k3": ("bunny_vis2000.json", ["--factor", "3", "--curvature"], []),
    "bunny_vis2000_k5": ("bunny_vis2000.json", ["--factor", "5", "--curvature"], []),
}

# Views (render options). The scans' frames: bunny and Igea have y up and face +z; the horse has
# z up, its length along y, the head at +y (seen from +x at azimuth 0).
IGEA = ["--up", "y", "--azimuth", "20", "--elevation", "5", "--zoom", "1.3"]
BUNNY = ["--up", "y", "--azimuth", "-15", "--elevation", "10", "--zoom", "1.35"]
BUNNY_HEAD = ["--up", "y", "--azimuth", "-15", "--elevation", "10", "--zoom", "3", "--focus", "-0.068,0.135,0.02"]
HORSE = ["--up", "z", "--azimuth", "0", "--elevation", "5", "--zoom", "1.2"]
HORSE_HEAD = ["--up", "z", "--azimuth", "25", "--elevation", "10", "--zoom", "3", "--focus", "0,0.074,0.05"]
WIRE = ["--wireframe", "--line-width", "0.7"]

# Figures: file, title, caption, panels (mesh, render arguments, label). "{field}" in the
# arguments becomes the mesh's field file (for --field).
FIGURES = [
    ("figure1_igea_vis4004.png", "Figure 1: Igea, VIS with 4004 constraints, four densities",
     "The Igea head as a variational implicit surface (2002 points, 4004 constraints) polygonized by our adaptive "
     "method at heuristic factors 1, 2, 3 and 5: the triangles shrink where the curvature is high.",
     [("igea_vis4004_k1", IGEA + WIRE, "k = 1"), ("igea_vis4004_k2", IGEA + WIRE, "k = 2"),
      ("igea_vis4004_k3", IGEA + WIRE, "k = 3"), ("igea_vis4004_k5", IGEA + WIRE, "k = 5")]),
    ("figure2_bunny_mpu_curvature.png", "Figure 2: curvature measures on the bunny MPU model",
     "Shape index (left; -1 convex cap, 0 saddle, +1 concave cup, matplotlib's coolwarm map) and maximum absolute "
     "curvature (right; log scale, viridis, range the 2nd to 98th percentile) computed from the field's Hessian at "
     "the vertices of our mesh (factor 3) of the bunny MPU implicit, blended across the triangles.",
     [("bunny_mpu_k3", BUNNY + ["--color", "shape_index"], "shape index"),
      ("bunny_mpu_k3", BUNNY + ["--color", "mac"], "MAC")]),
    ("figure3_horse_directions.png", "Figure 3: principal directions on the horse MPU model",
     "Directions of maximum (red) and minimum (blue) principal curvature of the horse MPU implicit, evaluated from "
     "the field at the visible points of our mesh (factor 3) on a grid of pixels and drawn as short segments "
     "(foreshortened with the surface); near-umbilic points (|k1 - k2| < 5% of max |k|) get none.",
     [("horse_mpu_k3", HORSE + ["--field", "{field}", "--directions", "--spacing", "11"], "whole model"),
      ("horse_mpu_k3", HORSE_HEAD + ["--field", "{field}", "--directions", "--spacing", "14"], "head")]),
    ("figure4_igea_mpu.png", "Figure 4: Igea MPU polygonized by our approach, and its MAC",
     "Our mesh (factor 3) of the Igea MPU implicit (left) and the maximum absolute curvature on it (right, log "
     "scale): the triangles are small where MAC is high.",
     [("igea_mpu_k3", IGEA + WIRE, "mesh"), ("igea_mpu_k3", IGEA + ["--color", "mac"], "MAC")]),
    ("figure9_mt_vs_ours.png", "Figure 9: Marching Tetrahedra against our method, close-up",
     "The bunny VIS-800 model (the Table 1 model), close-up of the head: Marching Tetrahedra at precision 1 (left) "
     "and our method at factor 2 (right). MT's triangles follow its grid, with slivers; ours follow the curvature.",
     [("bunny_vis800_mt1", BUNNY_HEAD + WIRE, "Marching Tetrahedra"),
      ("bunny_vis800_k2", BUNNY_HEAD + WIRE, "ours")]),
    ("figure10_bunny_vis2000.png", "Figure 10: bunny VIS with 2000 constraints, two densities",
     "The Stanford bunny as a variational implicit surface with 2000 constraints, polygonized by our method at "
     "factors 3 and 5.",
     [("bunny_vis2000_k3", BUNNY + WIRE, "k = 3"), ("bunny_vis2000_k5", BUNNY + WIRE, "k = 5")]),
]

COLOR_LABELS = {"shape_index": "shape index", "mac": "maximum absolute curvature (1 / model unit)"}


class Failure(Exception):
    pass


def run(cmd, timeout):
    try:
        r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        raise Failure("{} took more than {} s".format(os.path.basename(cmd[0]), timeout))
    if r.returncode != 0:
        lines = (r.stderr or r.stdout).strip().splitlines()
        raise Failure(lines[-1] if lines else "{} exited with {}".format(os.path.basename(cmd[0]), r.returncode))
    return r


def make_mesh(a, name):
    """The mesh's path and where it came from; Failure with the reason when there is none."""
    field, args, existing = MESHES[name]
    for rel in existing:
        path = os.path.join(ROOT, "results", rel)
        if os.path.exists(path):
            return path, "results/" + rel
    mesh = os.path.join(a.out, "meshes", name + ".ply")
    if a.reuse and os.path.exists(mesh):
        return mesh, "reused"
    exe = os.path.join(a.build, "bin", "polygonize")
    if not os.path.exists(exe):
        raise Failure("no {} (build it first)".format(exe))
    if not os.path.exists(os.path.join(FIELDS, field)):
        raise Failure("no field file experiments/fields/" + field)
    run([exe, os.path.join(FIELDS, field), "-o", mesh, "--quiet"] + args, a.timeout)
    return mesh, "polygonize " + " ".join([field] + args)


def render_panel(a, mesh_name, mesh_path, args, index):
    field = os.path.join(FIELDS, MESHES[mesh_name][0])
    png = os.path.join(a.out, "panels", "{}_{}.png".format(mesh_name, index))
    cmd = [os.path.join(a.build, "bin", "render"), mesh_path, "-o", png, "--width", str(a.size), "--height",
           str(a.size), "--samples", str(a.samples)] + [field if x == "{field}" else x for x in args]
    summary = json.loads(run(cmd, a.timeout).stdout)
    return png, summary


def compose(panels, path):
    """panels: (png, render summary, label). One row; a colour bar under coloured panels."""
    images = [matplotlib.image.imread(p) for p, _, _ in panels]
    h, w = images[0].shape[:2]
    n = len(panels)
    bars = any("color" in s for _, s, _ in panels)
    top, bottom = 28, (72 if bars else 4)
    dpi = 100
    fig = plt.figure(figsize=(n * w / dpi, (h + top + bottom) / dpi), dpi=dpi)
    H = h + top + bottom
    for i, (img, (_, summary, label)) in enumerate(zip(images, panels)):
        ax = fig.add_axes([i / n, bottom / H, 1 / n, h / H])
        ax.imshow(img, interpolation="nearest")
        ax.set_axis_off()
        ax.set_title("{} ({:,} triangles)".format(label, summary["triangles"]), fontsize=10)
        color = summary.get("color")
        if color:
            lo, hi = color["range"]
            norm = matplotlib.colors.LogNorm(lo, hi) if color["scale"] == "log" else matplotlib.colors.Normalize(lo, hi)
            cax = fig.add_axes([(i + 0.15) / n, 46 / H, 0.7 / n, 10 / H])
            bar = fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=color["map"]), cax=cax,
                               orientation="horizontal")
            if color["scale"] == "log":
                # Ticks at 1, 2, 5 x 10^k: a range under a decade would otherwise show one label.
                ticks = [m * 10.0 ** k for k in range(math.floor(math.log10(lo)), math.ceil(math.log10(hi)) + 1)
                         for m in (1, 2, 5) if lo <= m * 10.0 ** k <= hi]
                bar.set_ticks(ticks, labels=["{:g}".format(t) for t in ticks])
                bar.ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
            bar.ax.tick_params(labelsize=7)
            bar.set_label(COLOR_LABELS.get(color["property"], color["property"]), fontsize=8)
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=dpi)
    plt.close(fig)
    os.replace(tmp, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--size", type=int, default=600, help="panel width and height in pixels")
    ap.add_argument("--samples", type=int, default=3, help="rays per pixel side (anti-aliasing)")
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "figures"))
    ap.add_argument("--timeout", type=float, default=600, help="seconds per polygonization or rendering")
    ap.add_argument("--reuse", action="store_true", help="reuse meshes already in OUT/meshes")
    ap.add_argument("--only", nargs="*", help="figure files (or prefixes, e.g. figure3) to make")
    ap.add_argument("--strict", action="store_true", help="exit non-zero when a figure is not produced")
    a = ap.parse_args()
    a.build = os.path.join(ROOT, a.build) if not os.path.isabs(a.build) else a.build
    os.makedirs(os.path.join(a.out, "meshes"), exist_ok=True)
    os.makedirs(os.path.join(a.out, "panels"), exist_ok=True)
    figures = [f for f in FIGURES if not a.only or any(f[0].startswith(o) for o in a.only)]
    renderer = os.path.join(a.build, "bin", "render")

    meshes, failures = {}, {}
    with concurrent.futures.ThreadPoolExecutor(max(1, a.jobs)) as pool:
        wanted = sorted({p[0] for f in figures for p in f[3]})
        futures = {m: pool.submit(make_mesh, a, m) for m in wanted}
        for m, fut in futures.items():
            try:
                meshes[m], source = fut.result()
                print("figures: mesh {} ({})".format(m, source), flush=True)
            except Failure as e:
                failures[m] = str(e)
                print("figures: no mesh {}: {}".format(m, e), flush=True)

        captions = []
        for file, title, caption, panels in figures:
            missing = [m for m, _, _ in panels if m not in meshes]
            reason = None
            if not os.path.exists(renderer):
                reason = "no {} (build it first)".format(renderer)
            elif missing:
                reason = "; ".join("mesh {}: {}".format(m, failures[m]) for m in dict.fromkeys(missing))
            if reason is None:
                futs = [pool.submit(render_panel, a, m, meshes[m], args, i) for i, (m, args, _) in enumerate(panels)]
                try:
                    rendered = [f.result() for f in futs]
                    compose([(png, s, p[2]) for (png, s), p in zip(rendered, panels)], os.path.join(a.out, file))
                except Failure as e:
                    reason = "render: {}".format(e)
            if reason is None:
                captions.append({"file": file, "title": title, "caption": caption})
                print("figures: wrote " + file, flush=True)
            else:
                captions.append({"file": None, "title": title, "caption": "Not produced: " + reason})
                print("figures: SKIPPED {}: {}".format(file, reason), flush=True)
    # Keep the captions of figures not asked for this time (--only).
    path = os.path.join(a.out, "captions.json")
    if a.only and os.path.exists(path):
        with open(path) as f:
            old = {c["title"]: c for c in json.load(f)}
        made = {c["title"]: c for c in captions}
        captions = [made.get(t) or old.get(t) for _, t, _, _ in FIGURES if t in made or t in old]
    with open(path + ".tmp", "w") as f:
        json.dump(captions, f, indent=1)
    os.replace(path + ".tmp", path)
    skipped = sum(1 for c in captions if not c["file"])
    print("figures: {} of {} figures written to {}".format(len(captions) - skipped, len(captions), a.out), flush=True)
    if skipped and a.strict:
        sys.exit("figures: {} figure(s) not produced".format(skipped))


if __name__ == "__main__":
    main()
