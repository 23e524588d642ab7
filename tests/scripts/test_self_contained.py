#!/usr/bin/python3
"""The repository is self-contained: no tracked file refers to a folder outside it for data.

The scans and the paper's Table 1 numbers live in data/; a clone must build, test and reproduce
with nothing beside it. Checks every tracked text file for the paths of the old layout
(../shared/data, ../shared/paper/table1.json), and that every file an experiment's field names
exists inside the repository.
"""
import json
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# What a clone does not have. The paper's text stays outside (not ours to redistribute) and may
# be mentioned, but nothing may read data or Table 1 from there.
FORBIDDEN = re.compile(r"shared/data|shared/paper/table1|\.\./shared/(?!paper/?\b)")
THIS = os.path.relpath(os.path.abspath(__file__), ROOT)


def main():
    files = subprocess.run(["git", "ls-files"], cwd=ROOT, check=True, stdout=subprocess.PIPE,
                           text=True).stdout.split("\n")
    problems = []
    for f in filter(None, files):
        if f == THIS:
            continue
        try:
            with open(os.path.join(ROOT, f), encoding="utf-8") as fh:
                text = fh.read()
        except (UnicodeDecodeError, IsADirectoryError, FileNotFoundError):
            continue  # binary files (the scans) and files deleted in the work tree
        for n, line in enumerate(text.split("\n"), 1):
            if FORBIDDEN.search(line):
                problems.append("{}:{}: {}".format(f, n, line.strip()[:120]))
    fields = os.path.join(ROOT, "experiments", "fields")
    for name in sorted(os.listdir(fields)):
        with open(os.path.join(fields, name)) as fh:
            spec = json.load(fh)
        points = spec.get("points")
        if points is not None:
            path = os.path.normpath(os.path.join(fields, points))
            if not path.startswith(ROOT + os.sep) or not os.path.isfile(path):
                problems.append("experiments/fields/{}: points {} is not a file of the repository".format(name, points))
    for name in ("bunny.ply", "horse.ply", "igea.ply", "paper_table1.json", "README.md"):
        if not os.path.isfile(os.path.join(ROOT, "data", name)):
            problems.append("data/{} is missing".format(name))
    if problems:
        print("the repository refers to data outside it:\n" + "\n".join(problems))
        return 1
    print("test_self_contained: {} tracked files, no reference to data outside the repository".format(len(files)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
