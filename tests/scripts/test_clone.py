#!/usr/bin/python3
"""A clone works with nothing beside it: clones the repository (its committed state, HEAD) into a
fresh temporary folder that holds nothing else (no ../shared), configures it with CMake, and runs
`make reproduce`'s script there on the torus experiment with the programs of an existing build
(building the clone would take the ten minutes `make test` has in all): the experiment, Table 1
and its claims, the plots, the figures and results/README.md must all be regenerated from files
of the clone. tests/scripts/test_self_contained.py checks the text of every file; this one runs.

usage: test_clone.py SOURCE_DIR BUILD_DIR
"""
import os
import shutil
import subprocess
import sys
import tempfile


def run(cmd, cwd, what):
    r = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        sys.exit("test_clone: {} failed ({}):\n{}".format(what, r.returncode, r.stdout[-4000:]))
    return r.stdout


def main():
    source, build = (os.path.abspath(p) for p in sys.argv[1:3])
    top = tempfile.mkdtemp(prefix="cdp_clone_")
    try:
        clone = os.path.join(top, "clone")
        run(["git", "clone", "-q", "--no-hardlinks", source, clone], top, "git clone")
        if os.listdir(top) != ["clone"]:
            sys.exit("test_clone: the clone's parent folder is not empty")
        run(["cmake", "-S", clone, "-B", os.path.join(top, "configure"), "-DCDP_BUILD_PYTHON=OFF"], top,
            "configuring the clone")
        results = os.path.join(clone, "results")
        # What the run must write again: remove it from the clone first.
        for path in ("torus/summary.csv", "table1.md", "README.md"):
            os.remove(os.path.join(results, path))
        shutil.rmtree(os.path.join(results, "figures"))
        out = run(["/usr/bin/python3", "scripts/reproduce.py", "--build", build, "--only", "torus", "--jobs", "2"],
                  clone, "reproduce.py --only torus in the clone")
        missing = [p for p in ("torus/summary.csv", "table1.md", "README.md", "figures")
                   if not os.path.exists(os.path.join(results, p))]
        if missing:
            sys.exit("test_clone: reproduce did not write " + ", ".join(missing) + "\n" + out[-2000:])
        if len(os.listdir(os.path.join(results, "figures"))) == 0:
            sys.exit("test_clone: no figure written")
        print("test_clone: a clone in {} with nothing beside it configured and reproduced the torus "
              "experiment, Table 1, plots and figures".format(top))
    finally:
        shutil.rmtree(top, ignore_errors=True)


if __name__ == "__main__":
    main()
