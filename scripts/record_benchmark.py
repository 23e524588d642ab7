#!/usr/bin/python3
"""Records a benchmark run in the history: copies LATEST into HISTORY_DIR/<commit date>-<short commit>.json.

One file per commit: recording a commit again replaces its earlier file. The dashboard
(scripts/make_dashboard.py) draws its time series from these files.

  scripts/record_benchmark.py results/bench/latest.json results/bench/history
"""
import argparse
import glob
import json
import os
import sys

import bench_lib as bl


def record(latest, history_dir):
    """Writes the history file and returns its path; raises ValueError for a bad run file."""
    run = bl.load_run(latest)
    run.pop("path", None)
    if not run["benchmarks"]:
        raise ValueError("{}: the run has no benchmarks; nothing to record".format(latest))
    name = bl.record_name(run)
    os.makedirs(history_dir, exist_ok=True)
    short = name.rsplit("-", 1)[1][:-len(".json")]
    target = os.path.join(history_dir, name)
    tmp = target + ".tmp"
    with open(tmp, "w") as f:
        json.dump(run, f, indent=1)
        f.write("\n")
    # Earlier recordings of this commit (their date part may differ if the clock or the commit
    # date format changed) are replaced.
    for old in glob.glob(os.path.join(glob.escape(history_dir), "*-" + glob.escape(short) + ".json")):
        if os.path.abspath(old) != os.path.abspath(target):
            os.remove(old)
    os.replace(tmp, target)
    return target


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("latest", help="run file written by scripts/run_benchmarks.py")
    ap.add_argument("history_dir")
    a = ap.parse_args()
    try:
        target = record(a.latest, a.history_dir)
    except (OSError, ValueError) as e:
        sys.exit("record_benchmark: {}".format(e))
    run = bl.load_run(target)
    if run["context"].get("dirty"):
        print("record_benchmark: warning: the run was made with uncommitted changes", file=sys.stderr)
    print("record_benchmark: wrote", target)


if __name__ == "__main__":
    main()
