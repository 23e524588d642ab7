#!/usr/bin/python3
"""results/sdf_sweep.md and results/sdf_sweep/: the SDF models of experiments/sdf_models/models.json
(rounded primitives, smooth and sharp booleans, fillets, creases that meet) meshed by the adaptive
method at every quarter factor from 1 to 6, every half factor from 6.5 to 10 and nine tolerances
from 1e-1 to 1e-4, each run checked against issue 55's bounds: the surface's components and genus,
creases followed (no fallback to meshing across them), at least 5 degrees at creases and 20 away
from them, judged from the field (cdp.crease_angles), and within the tolerance where one is asked.

`make test` checks these models at factors 1, 3 and 10 and four tolerances
(tests/polygonizer/adaptive/sdf_models_test.cpp); this sweep is the larger sample it leaves out.
Every mesh the polygonize program writes has passed its own final checks (closed, oriented,
manifold, no self-intersection), so a run that fails them is an error here."""
import argparse
import concurrent.futures
import csv
import json
import os
import sys
import tempfile

from sweep_lib import polygonize, topology

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODELS = os.path.join(ROOT, "experiments", "sdf_models", "models.json")

FACTORS = [str(q / 4) for q in range(4, 25)] + [str(h / 2) for h in range(13, 21)]
TOLERANCES = ("1e-1", "5e-2", "2e-2", "1e-2", "5e-3", "2e-3", "1e-3", "5e-4", "1e-4")
RUNS = [("factor", f) for f in FACTORS] + [("tolerance", t) for t in TOLERANCES]
# Issue 55's bounds on the smallest angle, at creases and away from them (degrees).
AT_CREASES, AWAY = 5.0, 20.0
# The reference of a model without closed-form topology: marching cubes at two cells (shares of
# the box's longest side), trusted only where both agree, as the topology sweep does.
REFERENCE_CELLS = (1 / 150, 1 / 200)
# A run longer than this is stopped and counted as an error (the slowest takes a few seconds).
RUN_SECONDS = 300


def verdict(model, ref, stats, angles):
    """What a run that wrote a mesh misses of the bounds, as a list of short reasons."""
    misses = []
    if topology(stats) != ref:
        misses.append("topology {}, {}".format(*topology(stats)))
    if model["creased"] and stats["creases"]["fallback"]:
        misses.append("creases meshed across")
    if angles["min_degrees_at_creases"] < AT_CREASES:
        misses.append("{:.1f} deg at a crease".format(angles["min_degrees_at_creases"]))
    if angles["min_degrees_away"] < AWAY:
        misses.append("{:.1f} deg away from creases".format(angles["min_degrees_away"]))
    if stats["quality"]["over_tolerance"]:
        misses.append("{} triangles over the tolerance".format(stats["quality"]["over_tolerance"]))
    return misses


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--build", default="build")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "sdf_sweep"))
    ap.add_argument("--extra", default="", help="options added to every adaptive run (\"--blocks true\")")
    a = ap.parse_args()
    sys.path.insert(0, os.path.join(os.path.abspath(a.build), "python"))
    import cdp  # the build's module: the measure of angles at creases is the library's

    exe = os.path.join(a.build, "bin", "polygonize")
    with open(MODELS) as f:
        models = json.load(f)["models"]
    os.makedirs(a.out, exist_ok=True)
    work = tempfile.TemporaryDirectory(prefix="sdf_sweep.")  # meshes and stats: only figures are kept
    paths = {}
    for m in models:
        paths[m["name"]] = os.path.join(work.name, m["name"] + ".field.json")
        with open(paths[m["name"]], "w") as f:
            json.dump(m["field"], f)

    def reference(m):
        if m["components"] is not None:
            return m["components"], m["genus"]
        side = max(hi - lo for lo, hi in zip(*m["field"]["bounds"]))
        refs = []
        for i, share in enumerate(REFERENCE_CELLS):
            base = os.path.join(work.name, "{}.mc{}".format(m["name"], i))
            stats, error = polygonize(exe, paths[m["name"]], ["--method", "mc", "--cell", repr(side * share)],
                                      base + ".ply", base + ".json", RUN_SECONDS)
            if stats is None:
                raise SystemExit("sdf_sweep: marching cubes failed on {}: {}".format(m["name"], error))
            refs.append(topology(stats))
        if refs[0] != refs[1]:
            raise SystemExit("sdf_sweep: the marching reference of {} is not stable: {}".format(m["name"], refs))
        return refs[0]

    refs = {m["name"]: reference(m) for m in models}

    def job(m, kind, value):
        base = os.path.join(work.name, "{}.{}{}".format(m["name"], kind, value))
        stats, error = polygonize(exe, paths[m["name"]], ["--" + kind, value] + a.extra.split(), base + ".ply", base + ".json",
                                  RUN_SECONDS)
        row = {"model": m["name"], "run": "{} {}".format(kind, value)}
        if stats is None:
            row.update(verdict="error", misses=error)
        else:
            V, F = cdp.read_mesh(base + ".ply")
            # A field of its own: a field's first pieces() classifies its branch points, not to be
            # shared between threads.
            angles = cdp.crease_angles(cdp.field_from_json(m["field"]), V, F)
            misses = verdict(m, refs[m["name"]], stats, angles)
            row.update(verdict="within" if not misses else "outside", misses="; ".join(misses),
                       triangles=stats["triangles"], seconds=round(stats["seconds"], 3),
                       min_at_creases=round(angles["min_degrees_at_creases"], 2),
                       min_away=round(angles["min_degrees_away"], 2),
                       blocks=stats.get("blocks", {}).get("meshed_blocks", 0))
        for ext in (".ply", ".json"):
            if os.path.exists(base + ext):
                os.remove(base + ext)
        return row

    jobs = [(m, kind, value) for m in models for kind, value in RUNS]
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        rows = list(pool.map(lambda j: job(*j), jobs))
    work.cleanup()

    # blocks: the blocks the mesh was made of (0: tracked alone; with --extra "--blocks true").
    fieldnames = ["model", "run", "verdict", "triangles", "seconds", "min_at_creases", "min_away", "blocks", "misses"]
    with open(os.path.join(a.out, "summary.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fieldnames)
        w.writeheader()
        w.writerows(rows)

    def fmt(x):
        return "{:.1f}".format(x) if x < 180 else "none"

    lines = ["# SDF models over factors and tolerances", "",
             "Regenerated by `make reproduce` (`scripts/sdf_sweep.py`): the {} models of "
             "`experiments/sdf_models/models.json`, each meshed by the adaptive method (defaults, one thread) at "
             "factors 1 to 6 by quarters and 6.5 to 10 by halves, and at tolerances {}: {} runs. A run is *within* "
             "the bounds when its mesh has the model's components and genus (closed forms, or marching cubes on two "
             "grids), follows its creases (no fallback to meshing across them), has no triangle under {:.0f} degrees "
             "at a crease nor under {:.0f} away from creases (a triangle is at a crease when a corner lies where two "
             "pieces of the field meet, `cdp.crease_angles`), and none over the tolerance; *outside* when it writes "
             "a mesh that misses one; an *error* when it exits non-zero. Every mesh written passed the program's own "
             "checks (closed, oriented, manifold, no self-intersection).".format(
                 len(models), ", ".join(TOLERANCES), len(rows), AT_CREASES, AWAY), "",
             "| model | runs | within | outside | error | smallest angle at creases | away from creases | "
             "triangles | slowest run (s) |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for m in models:
        mine = [r for r in rows if r["model"] == m["name"]]
        meshed = [r for r in mine if r["verdict"] != "error"]
        count = lambda v: sum(1 for r in mine if r["verdict"] == v)  # noqa: E731
        lines.append("| {} | {} | {} | {} | {} | {} | {} | {} | {} |".format(
            m["name"], len(mine), count("within"), count("outside"), count("error"),
            fmt(min((r["min_at_creases"] for r in meshed), default=180)),
            fmt(min((r["min_away"] for r in meshed), default=180)),
            "{}-{}".format(min(r["triangles"] for r in meshed), max(r["triangles"] for r in meshed)) if meshed else "",
            "{:.2f}".format(max(r["seconds"] for r in meshed)) if meshed else ""))
    bad = [r for r in rows if r["verdict"] != "within"]
    lines += ["", "{} of {} runs are within the bounds; {} outside, {} errors.".format(
        len(rows) - len(bad), len(rows), sum(1 for r in bad if r["verdict"] == "outside"),
        sum(1 for r in bad if r["verdict"] == "error"))]
    if bad:
        lines += ["", "| model | run | verdict | what |", "|---|---|---|---|"]
        lines += ["| {} | `--{}` | {} | {} |".format(r["model"], r["run"], r["verdict"], r["misses"].replace("|", "/"))
                  for r in bad]
    lines += ["", "Every run: `results/sdf_sweep/summary.csv`. To see one: `build/bin/polygonize --factor F FIELD.json "
              "-o out.ply`, with the model's `field` object written to FIELD.json."]
    report = os.path.join(os.path.dirname(os.path.abspath(a.out)), "sdf_sweep.md")
    with open(report, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("sdf_sweep: {} runs, {} within the bounds; {}".format(len(rows), len(rows) - len(bad), os.path.relpath(report)))


if __name__ == "__main__":
    main()
