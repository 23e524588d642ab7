#!/usr/bin/python3
"""results/topology_sweep.md and results/topology_sweep/: whether the adaptive method's meshes
have the surface's topology on random blob fields, at every factor, tolerance and chord
deviation swept, against an independent reference (marching cubes on two fine grids, trusted
only where both agree).

A run ends one of three ways: a mesh with the reference's components and genus (correct), a
non-zero exit with a one-line error (a clear error), or a mesh with another topology and exit 0
(wrong without saying so, the worst outcome; issue 12). The hard-surface suite of `make test` and `make test-slow`
checks a few such fields at every factor; this sweep is the larger sample it leaves out."""
import argparse
import concurrent.futures
import csv
import json
import os
import tempfile

import numpy as np

from sweep_lib import polygonize, topology

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Fields: 25 unions of 2-6 large blobs (the hard-surface suite's random blob fields, drawn anew)
# and 15 dense unions of 46-60 smaller ones, whose many junctions make narrow necks and handles.
FEW, DENSE = 25, 15
SEED_BASE = 1000
# The reference's two marching-cubes cells (model units; the fields' boxes are about 6 wide, so
# about 125 and 165 cells across). A field whose two grids disagree on components or genus has
# detail near the grid size and is left out (listed as such).
REFERENCE_CELLS = (0.048, 0.036)
# The chord deviations are the tolerances' values: their sizing aimed at eps instead of a share
# of it (with each edge's turn capped at a radian), nothing measured or split, so a lost handle
# or component has no refinement to hide it.
DEVIATIONS = ("1e-3", "1e-2", "3e-2", "5e-2")
RUNS = ([("factor", v) for v in ("1", "2", "3", "5")] + [("tolerance", v) for v in DEVIATIONS] +
        [("chord", v) for v in DEVIATIONS])
# A run longer than this is stopped and counted as an error (none of the current runs comes near).
RUN_SECONDS = 300


def blobs(seed):
    rng = np.random.default_rng(SEED_BASE + seed)
    if seed <= FEW:
        n, lo, hi, rmin, rmax = 2 + seed % 5, -1.6, 1.6, 0.7, 1.3
    else:
        n, lo, hi, rmin, rmax = 20 + seed, -2.0, 2.0, 0.5, 1.0
    items = [{"center": [float(x) for x in rng.uniform(lo, hi, 3)], "radius": float(rng.uniform(rmin, rmax))}
             for _ in range(n)]
    return {"type": "blobs", "kernel": "wyvill", "threshold": 0.3, "blobs": items}


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--build", default="build")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "topology_sweep"))
    ap.add_argument("--extra", default="", help="options added to every adaptive run (\"--blocks true\")")
    a = ap.parse_args()
    exe = os.path.join(a.build, "bin", "polygonize")
    fields_dir = os.path.join(a.out, "fields")
    os.makedirs(fields_dir, exist_ok=True)
    work = tempfile.TemporaryDirectory(prefix="topology_sweep.")  # meshes and stats: only counts are kept
    fields = {"blobs{:02d}".format(seed): blobs(seed) for seed in range(1, FEW + DENSE + 1)}
    names = list(fields)
    for name, field in fields.items():
        with open(os.path.join(fields_dir, name + ".json"), "w") as f:
            json.dump(field, f, indent=1)

    def job(name, key, args):
        field = os.path.join(fields_dir, name + ".json")
        base = os.path.join(work.name, "{}.{}".format(name, key))
        stats, error = polygonize(exe, field, args, base + ".ply", base + ".json", RUN_SECONDS)
        for ext in (".ply", ".json"):
            if os.path.exists(base + ext):
                os.remove(base + ext)
        return name, key, stats, error

    jobs = []
    for name in names:
        for i, cell in enumerate(REFERENCE_CELLS):
            jobs.append((name, "mc{}".format(i), ["--method", "mc", "--cell", str(cell)]))
        for kind, value in RUNS:
            jobs.append((name, kind + value, ["--" + kind, value] + a.extra.split()))
    done = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        for name, key, stats, error in pool.map(lambda j: job(*j), jobs):
            done[(name, key)] = (stats, error)

    rows = []
    for name in names:
        refs = []
        for i in range(len(REFERENCE_CELLS)):
            stats, error = done[(name, "mc{}".format(i))]
            if stats is None:
                raise SystemExit("topology_sweep: marching cubes failed on {}: {}".format(name, error))
            refs.append(stats)
        ref = topology(refs[0])
        stable = all(topology(r) == ref for r in refs)
        for kind, value in RUNS:
            stats, error = done[(name, kind + value)]
            got = topology(stats) if stats else (None, None)
            if not stable:
                verdict = "reference unstable"
            elif stats is None:
                verdict = "error"
            else:
                verdict = "correct" if got == ref else "wrong"
            rows.append({"field": name, "blobs": len(fields[name]["blobs"]), "run": "{} {}".format(kind, value),
                         "verdict": verdict, "components": got[0], "genus": got[1],
                         "reference_components": ref[0], "reference_genus": ref[1],
                         "triangles": stats["triangles"] if stats else "",
                         "seconds": round(stats["seconds"], 3) if stats else "",
                         # The tightest bend the run's tracker met (-1: none with a finite radius) and
                         # the shortest edge it could make: below it the surface has detail its
                         # edges cannot follow, outside what issue 12 promises.
                         "min_radius": stats["curvature"]["min_radius"] if stats else "",
                         "min_edge": stats["edge_length"]["min"] if stats else "",
                         "blocks": stats.get("blocks", {}).get("meshed_blocks", 0) if stats else "", "error": error})
    with open(os.path.join(a.out, "summary.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)

    verdicts = ["correct", "error", "wrong", "reference unstable"]
    lines = ["# Topology on random blob fields", "",
             "Regenerated by `make reproduce` (`scripts/topology_sweep.py`): {} random Wyvill blob fields ({} unions of "
             "2-6 large blobs, {} dense unions of 46-60 smaller ones; `results/topology_sweep/fields/`), each meshed "
             "by the adaptive method at every factor, tolerance and chord deviation below. The reference is "
             "marching cubes at cells {} and {}: a field whose two grids disagree on its components or genus is left out. A run is "
             "*correct* when its mesh has the reference's components and total genus, a *clear error* when it "
             "exits non-zero with a one-line message, *wrong* when it exits 0 with another topology: a mesh that "
             "is wrong without saying so.".format(len(names), FEW, DENSE, *REFERENCE_CELLS), "",
             "| run | " + " | ".join(verdicts) + " |", "|---|" + "---:|" * len(verdicts)]
    for kind, value in RUNS:
        run = "{} {}".format(kind, value)
        counts = [sum(1 for r in rows if r["run"] == run and r["verdict"] == v) for v in verdicts]
        lines.append("| `--{} {}` | ".format(kind, value) + " | ".join(str(c) for c in counts) + " |")
    wrong = [r for r in rows if r["verdict"] == "wrong"]
    lines += ["", "{} of {} runs on fields with a stable reference are wrong without saying so.".format(
        len(wrong), sum(1 for r in rows if r["verdict"] != "reference unstable"))]
    lines += ["", "Every run is checked after meshing for the two ways runs were seen to lose surface with exit 0: "
              "a neck the fronts closed on both sides (two components facing each other across the solid, "
              "`polygonizer/src/adaptive/surface_gaps.h`) and a neck or tunnel they stepped over, a handle lost "
              "within one component (a saddle of F close to zero on the wrong side of the mesh, "
              "`polygonizer/src/adaptive/missed_necks.h`). A run caught so is meshed again by the careful run, "
              "with short edges around the necks it stepped over, and ends with a clear error when that fails "
              "too."]
    if wrong:
        lines += ["", "| field | run | components, genus | reference | tightest bend met | min_edge |",
                  "|---|---|---|---|---:|---:|"]
        lines += ["| {} | `--{}` | {}, {} | {}, {} | {} | {:.4f} |".format(
            r["field"], r["run"], r["components"], r["genus"], r["reference_components"], r["reference_genus"],
            "{:.4f}".format(r["min_radius"]) if r["min_radius"] >= 0 else "none", r["min_edge"]) for r in wrong]
        below = sum(1 for r in wrong if 0 <= r["min_radius"] < r["min_edge"])
        correct_below = sum(1 for r in rows if r["verdict"] == "correct" and 0 <= r["min_radius"] < r["min_edge"])
        lines += ["", "To see one: `build/bin/polygonize --factor 1 results/topology_sweep/fields/FIELD.json -o "
                  "out.ply` (or the run's `--tolerance` or `--chord`). Open (issue 12). {} of these {} runs met a bend tighter "
                  "than their shortest edge (`curvature.min_radius` of the stats below `edge_length.min`): the "
                  "junctions of the dense fields bend with radii down to 0.006 where min_edge is 0.02, detail that "
                  "issue 12 leaves out of its promise, though the run does not say so; {} correct runs met such a "
                  "bend too. The bend is the tightest at a vertex the run placed: a run that steps over a junction "
                  "does not meet it (blobs30 met 0.023 at factors 1 and 2, 0.0094 at `--tolerance 1e-2`). Where "
                  "examined: blobs19 at `--factor 1` and 2 and the fifty blobs of the hard-surface "
                  "suite at `--tolerance 3e-2` closed a front on each side of a junction, two closed pieces where "
                  "the surface has one (found after the run: `polygonizer/src/adaptive/surface_gaps.h`, a clear "
                  "error when the careful run cannot mesh them either); blobs33 at `--factor 1` spanned a tunnel "
                  "narrower than its edges with triangles whose corners' normals were up to 162 degrees apart "
                  "(expansions that fold so are now placed again: `Tracker::folds_across`); blobs30 stepped "
                  "over a neck 0.044 wide at five factors and tolerances (found since by `missed_necks.h`). The "
                  "runs listed have not been located one by one.".format(below, len(wrong), correct_below)]
    errors = [r for r in rows if r["verdict"] == "error"]
    if errors:
        lines += ["", "Clear errors (a run that cannot be completed is a defect too, issue 12, but not a silent one):",
                  "", "| field | run | error |", "|---|---|---|"]
        lines += ["| {} | `--{}` | {} |".format(r["field"], r["run"],
                                               r["error"].split(": adaptive: ", 1)[-1].replace("|", "/"))
                  for r in errors]
    work.cleanup()
    # Beside the folder, like results/sharp_features.md.
    report = os.path.join(os.path.dirname(os.path.abspath(a.out)), "topology_sweep.md")
    with open(report, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("topology_sweep: {} runs, {} wrong; {}".format(len(rows), len(wrong), os.path.relpath(report)))


if __name__ == "__main__":
    main()
