#!/usr/bin/python3
"""make reproduce: every experiment, then Table 1, the claims, the plots, the figures and
results/README.md. Each step prints what it does; a failing step stops the run with its message."""
import argparse
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PY = sys.executable or "/usr/bin/python3"

# Table 1 first: the others reuse its cached ground truth where they share a model.
EXPERIMENTS = ["table1", "torus", "blobs_example", "double_torus"]


def step(title, cmd):
    t0 = time.time()
    print("reproduce: " + title, flush=True)
    r = subprocess.run(cmd, cwd=ROOT)
    if r.returncode != 0:
        sys.exit("reproduce: step failed ({}): {}".format(r.returncode, " ".join(cmd)))
    print("reproduce: {} done in {:.0f} s".format(title, time.time() - t0), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--build", default="build")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--only", nargs="*", help="experiments to run (default: all)")
    a = ap.parse_args()
    start = time.time()
    exe = os.path.join(a.build, "bin", "experiment")
    for name in a.only or EXPERIMENTS:
        step("experiment " + name, [exe, os.path.join("experiments", name + ".json"), "--jobs", str(a.jobs),
                                    "--out", os.path.join("results", name)])
    step("Table 1 and claims", [PY, "scripts/table1.py", "--build", a.build])
    step("plots", [PY, "scripts/plots.py"])
    if os.path.exists(os.path.join(ROOT, "scripts", "figures.py")):
        step("figures", [PY, "scripts/figures.py", "--build", a.build, "--jobs", str(a.jobs)])
    step("results/README.md", [PY, "scripts/results_readme.py", "--seconds", str(round(time.time() - start))])
    print("reproduce: finished in {:.1f} min".format((time.time() - start) / 60))


if __name__ == "__main__":
    main()
