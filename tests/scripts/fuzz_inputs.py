#!/usr/bin/python3
"""Mutation fuzz of the programs' JSON inputs (make test runs it through ctest).

A few hundred field and experiment files are derived from valid ones by deleting, duplicating,
retyping and corrupting keys and values, and by cutting and garbling the text. Each goes through
the programs with a short timeout, and every run must end cleanly: exit 0, or exit 1 with one
line "program: ..." on stderr; never a signal, a timeout or a partial output, and nothing left in
the folder but what a successful run writes. Deterministic: the cases come from a fixed seed.

usage: fuzz_inputs.py BIN_DIR [--cases N] [--seed S]
"""
import argparse
import copy
import json
import os
import random
import shutil
import subprocess
import sys
import tempfile

# Per run: far above what any of these small inputs needs (a few tenths of a second), so that a
# timeout means a hang, not a slow machine.
TIMEOUT_SECONDS = 60

# The valid starting points: one of each field type the programs read, small and quick to mesh.
FIELDS = [
    {"type": "sphere", "radius": 1, "center": [0.1, 0, 0]},
    {"type": "ellipsoid", "radii": [1, 0.6, 0.4]},
    {"type": "torus", "major_radius": 1, "minor_radius": 0.4},
    {"type": "blobs", "threshold": 0.5, "kernel": "wyvill",
     "blobs": [{"center": [0, 0, 0], "radius": 1}, {"center": [0.8, 0, 0], "radius": 0.8, "strength": 1}]},
    {"type": "expression", "value": "x^2 + y^2 + z^2 - r^2 + 0.1*sin(3*x)", "params": {"r": 1},
     "bounds": [[-1.5, -1.5, -1.5], [1.5, 1.5, 1.5]]},
    {"type": "vis", "points": "points.off", "constraints": 40},
    {"type": "mpu", "points": "points.off", "max_error": 0.01, "min_points": 10, "max_depth": 4},
]

EXPERIMENT = {
    "description": "fuzz",
    "field": "field.json",
    "seed": 1,
    "runs": [{"method": "adaptive", "factor": [1, 2], "min_edge": 0.05, "max_edge": 0.5, "label": "a"},
             {"method": "mt", "cell": 0.2, "traversal": "grid"}],
    "evaluation": {"views": 1, "resolution": 8, "projection": "orthographic"},
    "keep_meshes": True,
}

ODD_VALUES = [None, True, False, 0, -1, 1e-300, 1e300, -1e300, 2 ** 31, 2 ** 63, 0.5, "", "x", "nan", "1e999",
              [], [1], [1, 2, 3], [[0, 0, 0], [1, 1, 1]], {}, {"a": 1}, "../../../etc/passwd", "a" * 300]


def paths_of(value, prefix=()):
    """Every (path, value) in a JSON value, the root included."""
    yield prefix, value
    if isinstance(value, dict):
        for k, v in value.items():
            yield from paths_of(v, prefix + (k,))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from paths_of(v, prefix + (i,))


def set_at(doc, path, value):
    if not path:
        return value
    parent = doc
    for p in path[:-1]:
        parent = parent[p]
    parent[path[-1]] = value
    return doc


def mutate(rng, doc):
    """One mutation of a JSON document; returns the text of the file."""
    doc = copy.deepcopy(doc)
    kind = rng.choice(["delete", "retype", "corrupt", "duplicate", "cut", "garble", "nest", "rename"])
    spots = [p for p, _ in paths_of(doc) if p]
    path = rng.choice(spots)
    if kind == "delete":
        parent = doc
        for p in path[:-1]:
            parent = parent[p]
        del parent[path[-1]]
        return json.dumps(doc)
    if kind == "retype":
        return json.dumps(set_at(doc, path, rng.choice(ODD_VALUES)), allow_nan=True)
    if kind == "corrupt":
        value = copy.deepcopy(dict(paths_of(doc))[path])
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            value = rng.choice([value * 1e6, -value, value * 1e-9, 0, value + 1e-12, float("nan"), float("inf")])
        elif isinstance(value, str):
            value = rng.choice([value[: len(value) // 2], value + ")", "(" * 5000 + "x" + ")" * 5000, value * 50,
                                value.replace("x", "q")])
        elif isinstance(value, list):
            value = value + value if value else [None]
        else:
            value = None
        text = json.dumps(set_at(doc, path, value), allow_nan=True)
        return text.replace("NaN", "nan") if rng.random() < 0.5 else text
    if kind == "duplicate":
        # The same key twice in one object: textual, since json.dumps cannot say it.
        key = [p for p in path if isinstance(p, str)]
        text = json.dumps(doc)
        if not key:
            return text
        k = json.dumps(key[-1])
        at = text.find(k + ":")
        end = at + len(k) + 1
        return text[:at] + k + ": 7, " + text[at:] if at >= 0 and end <= len(text) else text
    if kind == "cut":
        text = json.dumps(doc)
        return text[: rng.randrange(len(text))]
    if kind == "garble":
        text = list(json.dumps(doc))
        for _ in range(rng.randint(1, 4)):
            text[rng.randrange(len(text))] = rng.choice(["\x00", "{", "]", '"', "\\", "\u00e9", ",", "9"])
        return "".join(text)
    if kind == "nest":
        depth = rng.choice([100, 5000, 100000])
        return json.dumps(set_at(doc, path, "NEST")).replace('"NEST"', "[" * depth + "1" + "]" * depth)
    # rename: a misspelt key
    parent = doc
    for p in path[:-1]:
        parent = parent[p]
    if isinstance(path[-1], str):
        parent[path[-1] + "x"] = parent.pop(path[-1])
    return json.dumps(doc)


OUTCOMES = {}


def check(result, program, expected_outputs, folder, case, failures):
    """A clean end: exit 0 with the outputs, or exit 1, one line, and no outputs."""
    key = (program, "timeout" if result is None else result.returncode)
    OUTCOMES[key] = OUTCOMES.get(key, 0) + 1
    problems = []
    if result is None:
        problems.append("timed out after {} s".format(TIMEOUT_SECONDS))
    else:
        code, err = result.returncode, result.stderr.decode("utf-8", "replace")
        if code < 0:
            problems.append("killed by signal {}".format(-code))
        elif code not in (0, 1):
            problems.append("exit status {}".format(code))
        elif code == 1:
            if not (err.startswith(program + ": ") and err.count("\n") == 1):
                problems.append("not one line '{}: ...': {!r}".format(program, err[:300]))
            for out in expected_outputs:
                if os.path.exists(out):
                    problems.append("left output {} after an error".format(out))
        else:
            for out in expected_outputs:
                if not os.path.exists(out) or os.path.getsize(out) == 0:
                    problems.append("exit 0 without {}".format(out))
    hidden = [f for f in os.listdir(folder) if f.startswith(".")]
    if hidden:
        problems.append("temporaries left: {}".format(hidden))
    if problems:
        failures.append("{}: {}\n    input: {}".format(program, "; ".join(problems), case[:400]))


def run(cmd, cwd):
    try:
        return subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=TIMEOUT_SECONDS)
    except subprocess.TimeoutExpired:
        return None


def write_points(folder):
    """An octahedron subdivided once: a small closed mesh for the data-driven models' points."""
    v = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    f = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
    mids = {}
    verts = [list(p) for p in v]
    faces = []

    def mid(a, b):
        key = (min(a, b), max(a, b))
        if key not in mids:
            m = [(verts[a][i] + verts[b][i]) / 2 for i in range(3)]
            n = sum(c * c for c in m) ** 0.5
            verts.append([c / n for c in m])
            mids[key] = len(verts) - 1
        return mids[key]

    for a, b, c in f:
        ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
        faces += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
    with open(os.path.join(folder, "points.off"), "w") as out:
        out.write("OFF\n{} {} 0\n".format(len(verts), len(faces)))
        out.writelines("{} {} {}\n".format(*p) for p in verts)
        out.writelines("3 {} {} {}\n".format(*t) for t in faces)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("bin")
    ap.add_argument("--cases", type=int, default=240)
    ap.add_argument("--seed", type=int, default=13)
    a = ap.parse_args()
    a.bin = os.path.abspath(a.bin)
    rng = random.Random(a.seed)
    failures = []
    work = tempfile.mkdtemp(prefix="cdp_fuzz_")
    try:
        for i in range(a.cases):
            folder = os.path.join(work, str(i))
            os.makedirs(folder)
            write_points(folder)
            if i % 4 == 3:
                # An experiment file: read-only modes must write nothing; a full run of a few
                # mutations goes through polygonize and evaluate too.
                with open(os.path.join(folder, "field.json"), "w") as out:
                    json.dump(FIELDS[2], out)
                text = mutate(rng, EXPERIMENT)
                with open(os.path.join(folder, "exp.json"), "w") as out:
                    out.write(text)
                for mode in (["--list"], ["--commands"]):
                    r = run([os.path.join(a.bin, "experiment"), "exp.json", "--out", "out"] + mode, folder)
                    check(r, "experiment", [], folder, text, failures)
                    if os.path.exists(os.path.join(folder, "out")):
                        failures.append("experiment {} wrote out/\n    input: {}".format(mode[0], text[:400]))
                        shutil.rmtree(os.path.join(folder, "out"))
                if i % 16 == 3:
                    r = run([os.path.join(a.bin, "experiment"), "exp.json", "--out", "out", "--jobs", "1"], folder)
                    # 2: the experiment ran and some runs failed, which mutations may well cause.
                    if r is not None and r.returncode == 2:
                        r.returncode = 0
                    check(r, "experiment", [], folder, text, failures)
            else:
                base = FIELDS[i % len(FIELDS)]
                text = mutate(rng, base)
                with open(os.path.join(folder, "field.json"), "w") as out:
                    out.write(text)
                method = ["adaptive", "mt", "mc"][i % 3]
                size = ["--factor", "1"] if method == "adaptive" else ["--cell", "0.15"]
                # Bounds keep the valid-but-huge mutations (a radius of 1e300) short and clean.
                r = run([os.path.join(a.bin, "polygonize"), "field.json", "-o", "out.ply", "--method", method,
                         "--stats", "stats.json", "--max-triangles", "200000"] + size, folder)
                check(r, "polygonize", [os.path.join(folder, "out.ply"), os.path.join(folder, "stats.json")], folder,
                      text, failures)
                r = run([os.path.join(a.bin, "curvature"), "field.json", "--at", "0.5,0.5,0.5"], folder)
                check(r, "curvature", [], folder, text, failures)
            shutil.rmtree(folder)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    if failures:
        print("{} of {} cases did not end cleanly:".format(len(failures), a.cases))
        print("\n".join(failures))
        return 1
    print("fuzz_inputs: {} cases, every run ended cleanly; exits: {}".format(
        a.cases, ", ".join("{} {}: {}".format(p, c, n) for (p, c), n in sorted(OUTCOMES.items(), key=str))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
