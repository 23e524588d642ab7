#!/usr/bin/python3
"""The mesh viewer, results/viewer/index.html: a few of the meshes `make reproduce` wrote, ours beside
Marching Tetrahedra and Marching Cubes at the nearest triangle count, with each run's figures.

Writes, beside the page (copied from viewer/index.html):
  data/manifest.js           the models, the runs shown and their figures (results/NAME/summary.csv)
  data/NAME/RUN.js           one mesh each: float32 positions, int8 normals (the file's), uint16/uint32
                             triangles, float32 principal curvatures k1 >= k2 of the field at each vertex
                             (cdp.curvature: exact, from the field's Hessian; NaN where it has no gradient)
  viewer.js                  viewer/src/*.js and three.js bundled into one classic script by esbuild
Each data file assigns into a global and is loaded by a <script> tag: Chromium refuses fetch() and
ES modules from file://, so this is what lets the page open without a server.

The meshes are results/NAME/meshes/RUN.ply. Where one is missing (a fresh clone: meshes are not
committed) it is made again by the experiment program into results/viewer/runs/NAME/ (same run,
same options; the committed results/NAME/ is left alone). --have-meshes only says, by its exit
status, whether that is possible without building (`make viewer` builds first when it is not).

Exit status 3: the data were written but the bundle was not (no node, or viewer/node_modules
missing: `bash scripts/install-deps.sh --viewer` runs npm ci, which needs the npm registry).

  scripts/make_viewer.py [--build build] [--have-meshes]
"""
import argparse
import base64
import csv
import json
import math
import os
import shutil
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RESULTS = os.path.join(ROOT, "results")
OUT = os.path.join(RESULTS, "viewer")
VIEWER_SRC = os.path.join(ROOT, "viewer")
NO_BUNDLE = 3

# (results folder, title, our run). Smooth analytic, high genus, a scan through two different
# implicit models, several components, and a creased CSG shape; our run is the one whose triangle
# count the experiment's MT and MC cells were chosen to match (or the closest such), and the
# baselines are picked below by nearest count. About 150k triangles in all, 3-4 MB of data.
MODELS = [
    ("table1", "Bunny, VIS with 800 constraints (Table 1)", "adaptive_factor3"),
    ("torus", "Torus", "adaptive_factor5"),
    ("tanglecube", "Tanglecube (genus 5)", "adaptive_factor3"),
    ("igea_vis4004", "Igea, VIS with 4004 constraints", "adaptive_factor2"),
    ("random_blobs", "Random blobs (three components)", "adaptive_factor5"),
    ("creases_box_minus_ball", "Box minus ball (creases)", "adaptive_tolerance0.002"),
]
BASELINES = ("mt", "mc")

# summary.csv columns shown under each mesh: (column, label, format).
FIGURES = [
    ("triangles", "triangles", "{:.0f}"),
    ("vertices", "vertices", "{:.0f}"),
    ("seconds", "time (ms)", "ms"),
    ("edge_ratio_mean", "edge ratio L/s mean", "{:.3f}"),
    ("edge_ratio_std", "edge ratio L/s st.dev.", "{:.3f}"),
    ("near_equilateral_fraction", "near-equilateral share", "{:.3f}"),
    ("min_angle_min_deg", "smallest angle (°)", "{:.1f}"),
    ("min_angle_mean_deg", "mean smallest angle (°)", "{:.1f}"),
    ("depth_error_relative_mean", "depth error / box diagonal", "{:.2e}"),
    ("phong_error_mean_deg", "Phong error (°)", "{:.3f}"),
    ("sharp_edges", "sharp edges (dihedral > 30°)", "{:.0f}"),
]


def fail(msg):
    sys.exit("make_viewer: " + msg)


def read_summary(model):
    try:
        with open(os.path.join(RESULTS, model, "summary.csv"), newline="") as f:
            return {row["id"]: row for row in csv.DictReader(f)}
    except OSError:
        return {}


def number(row, key):
    try:
        v = float(row.get(key, ""))
    except ValueError:
        return None
    return v if math.isfinite(v) else None


def pick_runs(model, ours):
    """Our run and, per baseline method, its run at the nearest triangle count (ratio, not difference);
    None when our run is not in the summary or did not finish."""
    rows = read_summary(model)
    if ours not in rows or rows[ours]["status"] != "ok":
        return None
    n = number(rows[ours], "triangles")
    runs = [rows[ours]]
    for method in BASELINES:
        cands = [r for r in rows.values() if r["method"] == method and r["status"] == "ok" and number(r, "triangles")]
        if cands:
            runs.append(min(cands, key=lambda r: abs(math.log(number(r, "triangles") / n))))
    return runs


def mesh_path(model, run_id):
    for base in (os.path.join(RESULTS, model), os.path.join(OUT, "runs", model)):
        path = os.path.join(base, "meshes", run_id + ".ply")
        if os.path.exists(path):
            return path
    return None


def remake(model, run_id, build):
    """The experiment's own run again, into results/viewer/runs/ (evaluation included: that is what --run does)."""
    exe = os.path.join(ROOT, build, "bin", "experiment")
    out = os.path.join(OUT, "runs", model)
    experiment = os.path.join(ROOT, "experiments", model + ".json")
    if not os.path.exists(exe):
        fail("no {}/meshes/{}.ply and no {} to make it: make build (or make viewer, which builds when needed)".format(
            model, run_id, exe))
    print("make_viewer: no results/{}/meshes/{}.ply (make reproduce writes it): running it again".format(model, run_id),
          flush=True)
    r = subprocess.run([exe, experiment, "--out", out, "--run", run_id], cwd=ROOT)
    path = os.path.join(out, "meshes", run_id + ".ply")
    if r.returncode != 0 or not os.path.exists(path):
        fail("{} {} --run {} failed ({})".format(exe, experiment, run_id, r.returncode))
    return path


def b64(array):
    return base64.b64encode(np.ascontiguousarray(array).tobytes()).decode("ascii")


def curvatures(cdp, field, V):
    """k1, k2 at each vertex; NaN where the field has no gradient (cdp.curvature refuses a whole batch then)."""
    try:
        c = cdp.curvature(field, V)
        return c["k1"], c["k2"]
    except Exception:
        k = np.full((len(V), 2), np.nan)
        for i, p in enumerate(V):
            try:
                c = cdp.curvature(field, p[None, :])
                k[i] = c["k1"][0], c["k2"][0]
            except Exception:
                pass
        return k[:, 0], k[:, 1]


def write_mesh(cdp, field, path, key, out):
    V, F, N = cdp.read_mesh(path, return_normals=True)
    if N is None:
        N = np.zeros_like(V)  # the viewer then computes normals from the triangles
    k1, k2 = curvatures(cdp, field, V)
    n = np.linalg.norm(N, axis=1, keepdims=True)
    N8 = np.round(127 * np.divide(N, n, out=np.zeros_like(N), where=n > 0)).astype(np.int8)
    index = F.astype(np.uint16 if len(V) < 65536 else np.uint32)
    data = {"key": key, "vertices": len(V), "triangles": len(F), "hasNormals": bool(np.any(N8)),
            "index_type": index.dtype.name, "position": b64(V.astype(np.float32)), "normal": b64(N8),
            "index": b64(index), "k1": b64(k1.astype(np.float32)), "k2": b64(k2.astype(np.float32))}
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out + ".tmp", "w") as f:
        f.write("(window.CDP_VIEWER_MESHES = window.CDP_VIEWER_MESHES || {{}})[{}] = {};\n".format(
            json.dumps(key), json.dumps(data)))
    os.replace(out + ".tmp", out)
    return V, k1, k2


def color_ranges(k1, k2):
    """The colour scales of render/src/color_map.cpp: 2nd-98th percentiles, at least 2% (mean) or 0.02 decades (MAC) wide."""
    ok = np.isfinite(k1) & np.isfinite(k2)
    k1, k2 = k1[ok], k2[ok]
    if not len(k1):
        return None
    mac = np.maximum(np.abs(k1), np.abs(k2))
    mac = mac[mac > 0]
    lo, hi = (np.percentile(mac, [2, 98]) if len(mac) else (1.0, 1.0))
    lo, hi = max(lo, 1e-12), max(hi, 1e-12)
    mid, f = math.sqrt(lo * hi), math.sqrt(max(hi / lo, 10 ** 0.02))
    mean = float(np.percentile(np.abs(0.5 * (k1 + k2)), 98)) or 1.0
    return {"mac": [mid / f, mid * f], "mean": [-mean, mean], "shape_index": [-1.0, 1.0]}


def figures(row):
    out = []
    for key, label, fmt in FIGURES:
        v = number(row, key)
        if v is None:
            continue
        out.append([label, "{:.1f}".format(1000 * v) if fmt == "ms" else fmt.format(v)])
    topo = [row.get(k, "") for k in ("closed", "manifold", "components", "genus")]
    if all(topo):
        out.append(["topology", "{} / {} / {} component(s), genus {}".format(
            "closed" if topo[0] == "true" else "open", "manifold" if topo[1] == "true" else "non-manifold", *topo[2:])])
    return out


def label(row):
    method = {"adaptive": "ours (adaptive)", "mt": "Marching Tetrahedra", "mc": "Marching Cubes"}.get(row["method"],
                                                                                                   row["method"])
    return "{}, {} {}".format(method, row["parameter_name"], row["parameter"])


def bundle():
    """viewer.js by esbuild from viewer/node_modules; None when it could not be made, else the reason it failed."""
    esbuild = os.path.join(VIEWER_SRC, "node_modules", ".bin", "esbuild")
    if not shutil.which("node") or not os.path.exists(esbuild):
        return ("the viewer's npm packages are not installed (viewer/node_modules); "
                "`bash scripts/install-deps.sh --viewer` installs them (npm ci: needs the npm registry)")
    r = subprocess.run(["npm", "run", "--silent", "build"], cwd=VIEWER_SRC)
    if r.returncode != 0:
        fail("npm run build in viewer/ failed ({})".format(r.returncode))
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build")
    ap.add_argument("--have-meshes", action="store_true",
                    help="exit 0 when every mesh shown is there or can be made with the built programs, else 1")
    a = ap.parse_args()
    chosen = []
    for model, title, ours in MODELS:
        runs = pick_runs(model, ours)
        if runs:
            chosen.append((model, title, runs))
        else:
            # A model whose run failed is left out rather than failing make reproduce over a picture.
            print("make_viewer: {} left out: run {} is not in results/{}/summary.csv or did not finish".format(
                model, ours, model), file=sys.stderr)
    if not chosen:
        fail("none of the models' runs finished")
    missing = [(m, r["id"]) for m, _, runs in chosen for r in runs if not mesh_path(m, r["id"])]
    if a.have_meshes:
        built = os.path.exists(os.path.join(ROOT, a.build, "bin", "experiment"))
        sys.exit(0 if not missing or built else 1)

    sys.path.insert(0, os.path.join(ROOT, a.build, "python"))
    try:
        import cdp
    except ImportError as e:
        fail("cannot import the cdp module from {}/python ({}): build it first (make build)".format(a.build, e))

    os.makedirs(OUT, exist_ok=True)
    manifest = {"generator": "scripts/make_viewer.py", "curvature": "principal curvatures of the field at each vertex "
                "(cdp.curvature: exact, from the field's Hessian); both panes share the scale", "models": []}
    total = 0
    for model, title, runs in chosen:
        field = cdp.field_from_json(os.path.join(RESULTS, model, "field.json"))
        entry = {"id": model, "title": title, "runs": []}
        ks = []
        for row in runs:
            path = mesh_path(model, row["id"]) or remake(model, row["id"], a.build)
            rel = "data/{}/{}.js".format(model, row["id"])
            key = "{}/{}".format(model, row["id"])
            _, k1, k2 = write_mesh(cdp, field, path, key, os.path.join(OUT, rel))
            if row["method"] == "adaptive":
                ks.append((k1, k2))
            total += os.path.getsize(os.path.join(OUT, rel))
            entry["runs"].append({"key": key, "file": rel, "method": row["method"], "label": label(row),
                                  "figures": figures(row)})
        entry["colors"] = color_ranges(*ks[0]) if ks else None
        manifest["models"].append(entry)
    with open(os.path.join(OUT, "data", "manifest.js"), "w") as f:
        f.write("window.CDP_VIEWER_MANIFEST = {};\n".format(json.dumps(manifest, indent=1)))
    shutil.copyfile(os.path.join(VIEWER_SRC, "index.html"), os.path.join(OUT, "index.html"))
    n = sum(len(runs) for _, _, runs in chosen)
    print("make_viewer: {} meshes of {} models, {:.1f} MB -> {}".format(n, len(chosen), total / 1e6,
                                                                       os.path.relpath(OUT, ROOT)), flush=True)
    problem = bundle()
    if problem:
        print("make_viewer: viewer.js not built: " + problem, file=sys.stderr)
        sys.exit(NO_BUNDLE)


if __name__ == "__main__":
    main()
