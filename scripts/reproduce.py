#!/usr/bin/python3
"""make reproduce: every experiment, then Table 1, the claims, the plots, the figures, the mesh viewer and
results/README.md. Each step prints what it does; a failing step stops the run with its message."""
import argparse
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PY = sys.executable or "/usr/bin/python3"

# Table 1 first: the others reuse its cached ground truth where they share a model. Then the
# same protocol beyond the bunny (claims_by_model.py), and the examples.
EXPERIMENTS = ["table1", "igea_vis4004", "horse_mpu", "tanglecube", "random_blobs", "torus", "blobs_example",
               "double_torus", "creases_cube", "creases_capped_cylinder", "creases_box_minus_ball",
               "creases_two_spheres", "creases_hollow_sphere"]


# Experiments whose failed runs are a measured result, not a broken reproduction: the adaptive
# method does not mesh every creased shape yet (acute creases, the sharp-features issue), and these
# experiments are the baseline that shows it. Their failures are listed at the end and in
# results/sharp_features.md; a failure anywhere else still fails `make reproduce`.
KNOWN_FAILURES = {
    "creases_box_minus_ball": "meshing across the creases (runs labelled smooth) stalls at the holes' acute rims "
                              "(see results/sharp_features.md)",
}

# experiment's exit status when it ran but some of its runs failed: the tables show those runs
# as failed with their reasons, so the reproduction goes on and reports them at the end.
SOME_RUNS_FAILED = 2


def step(title, cmd, tolerate=(), env=None):
    t0 = time.time()
    print("reproduce: " + title, flush=True)
    r = subprocess.run(cmd, cwd=ROOT, env=env)
    if r.returncode != 0 and r.returncode not in tolerate:
        sys.exit("reproduce: step failed ({}): {}".format(r.returncode, " ".join(cmd)))
    print("reproduce: {} done in {:.0f} s".format(title, time.time() - t0), flush=True)
    return r.returncode


# scripts/make_viewer.py's exit status when it wrote the mesh data but not the bundle.
VIEWER_NOT_BUNDLED = 3


def viewer(build):
    """The mesh viewer (results/viewer/). Its npm packages come from the npm registry the first time:
    without it the reproduction goes on, and says at the end what is missing."""
    t0 = time.time()
    print("reproduce: viewer", flush=True)
    deps = subprocess.run(["bash", "scripts/install-deps.sh", "--viewer"], cwd=ROOT)
    r = subprocess.run([PY, "scripts/make_viewer.py", "--build", build], cwd=ROOT)
    if r.returncode not in (0, VIEWER_NOT_BUNDLED):
        sys.exit("reproduce: step failed ({}): scripts/make_viewer.py".format(r.returncode))
    print("reproduce: viewer done in {:.0f} s".format(time.time() - t0), flush=True)
    if r.returncode == VIEWER_NOT_BUNDLED:
        return ("the viewer's page has its meshes but not viewer.js ({}): `make viewer` once the npm registry "
                "is reachable".format("installing node or its npm packages failed" if deps.returncode else
                                      "its npm packages are missing"))
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--build", default="build")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--only", nargs="*", help="experiments to run (default: all, and the two sweeps and the mesh viewer: name "
                    "them as topology_sweep, sdf_sweep, viewer and volume_example)")
    a = ap.parse_args()
    start = time.time()
    exe = os.path.join(a.build, "bin", "experiment")
    with_failures = []
    named_steps = ("topology_sweep", "sdf_sweep", "viewer", "volume_example")
    for name in [n for n in a.only or EXPERIMENTS if n not in named_steps]:
        code = step("experiment " + name, [exe, os.path.join("experiments", name + ".json"), "--jobs", str(a.jobs),
                                           "--out", os.path.join("results", name)], tolerate=(SOME_RUNS_FAILED,))
        if code == SOME_RUNS_FAILED:
            with_failures.append(name)
    step("Table 1 and claims", [PY, "scripts/table1.py", "--build", a.build])
    step("claims on every model", [PY, "scripts/claims_by_model.py"])
    step("plots", [PY, "scripts/plots.py"])
    step("sharp features", [PY, "scripts/sharp_features.py"])
    # A sweep of its own (320 runs, about 1.5 minutes on 2 cores): with --only, when named.
    if not a.only or "topology_sweep" in a.only:
        step("topology sweep", [PY, "scripts/topology_sweep.py", "--build", a.build, "--jobs", str(a.jobs)])
    # The SDF models at 38 sizings each (646 runs, about 1.5 minutes on 2 cores): with --only, when named.
    if not a.only or "sdf_sweep" in a.only:
        step("SDF sweep", [PY, "scripts/sdf_sweep.py", "--build", a.build, "--jobs", str(a.jobs)])
    if os.path.exists(os.path.join(ROOT, "scripts", "figures.py")):
        step("figures", [PY, "scripts/figures.py", "--build", a.build, "--jobs", str(a.jobs)])
    # A sampled volume (a brain MRI from python3-nibabel) beside scikit-image: with --only, when named.
    if not a.only or "volume_example" in a.only:
        env = dict(os.environ, PYTHONPATH=os.path.join(os.path.abspath(a.build), "python"))
        step("volume example", [PY, "examples/mesh_volume.py", "--out", os.path.join("results", "volume_example"),
                                "--render", os.path.join(a.build, "bin", "render")], env=env)
    # Needs every shown model's meshes (missing ones are run again) and, the first time, the npm
    # registry: with --only, when named.
    viewer_note = viewer(a.build) if not a.only or "viewer" in a.only else None
    step("results/README.md", [PY, "scripts/results_readme.py", "--seconds", str(round(time.time() - start))])
    print("reproduce: finished in {:.1f} min".format((time.time() - start) / 60))
    if viewer_note:
        print("reproduce: " + viewer_note)
    for name in [n for n in with_failures if n in KNOWN_FAILURES]:
        print("reproduce: runs failed in {}: known, {}".format(name, KNOWN_FAILURES[name]))
    with_failures = [n for n in with_failures if n not in KNOWN_FAILURES]
    if with_failures:
        sys.exit("reproduce: runs failed in " + ", ".join(with_failures) +
                 " (listed as failed, with their reasons, in results/NAME/summary.csv and the tables)")


if __name__ == "__main__":
    main()
