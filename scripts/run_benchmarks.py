#!/usr/bin/python3
"""Runs every Google Benchmark program build/bin/bench_* and merges their results into one JSON file.

Each program runs with repetitions (medians and their spread are what the dashboard compares)
and JSON output; the merged file (results/bench/latest.json by default) records the context
the numbers depend on: commit, date, compiler and flags, build type, CPU and cores. Progress
(the programs' own console tables) goes to stderr.

  scripts/run_benchmarks.py --build build --out results/bench/latest.json           # full
  scripts/run_benchmarks.py --build build --short --out results/bench/latest.json   # CI

--short: 3 repetitions, minimum time 0.01 s per repetition, and benchmarks whose name contains
"Scaling" or "Slow" are skipped (see bench/README.md). Debian's Google Benchmark (1.7) takes
--benchmark_min_time as a plain number of seconds.
"""
import argparse
import datetime
import glob
import json
import os
import subprocess
import sys
import tempfile
import time

import bench_lib as bl
import results_lib as rl

FULL = {"repetitions": 5, "min_time": 0.2, "filter": None}
SHORT = {"repetitions": 3, "min_time": 0.01, "filter": "-" + bl.SHORT_EXCLUDE}

# Keys of a Google Benchmark run entry that are not user counters.
STANDARD_KEYS = {"name", "family_index", "per_family_instance_index", "run_name", "run_type", "repetitions",
                 "repetition_index", "threads", "iterations", "real_time", "cpu_time", "time_unit", "label",
                 "aggregate_name", "aggregate_unit", "error_occurred", "error_message", "skipped", "skip_message",
                 "big_o", "rms"}


def log(*a):
    print("run_benchmarks:", *a, file=sys.stderr, flush=True)


def git(*args):
    try:
        r = subprocess.run(["git", "-C", rl.ROOT, *args], capture_output=True, text=True)
        return r.stdout.strip() if r.returncode == 0 else ""
    except OSError:
        return ""


def compiler_flags(build):
    """The C++ flags a benchmark program was compiled with, from CMake's generated flags.make
    (it holds the add_compile_options of CMakeLists.txt too, which CMakeCache.txt does not)."""
    for path in sorted(glob.glob(os.path.join(build, "bench", "CMakeFiles", "bench_*.dir", "flags.make"))):
        with open(path) as f:
            for line in f:
                if line.startswith("CXX_FLAGS"):
                    return line.split("=", 1)[1].strip()
    return ""


def context(build, mode, settings):
    env = rl.environment(build)
    commit = env.get("commit", "")
    return {
        "commit": commit,
        "commit_short": commit[:7],
        "commit_date": git("show", "-s", "--format=%cI", "HEAD"),
        "commit_subject": git("show", "-s", "--format=%s", "HEAD"),
        "dirty": env.get("dirty", False),
        "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "compiler": env.get("compiler", ""),
        "compiler_flags": compiler_flags(build),
        "build_type": env.get("build_type", ""),
        "cpu": env.get("cpu", ""),
        "cores": env.get("cores"),
        "machine": env.get("machine", ""),
        "load_average": list(os.getloadavg()),
        "mode": mode,
        "repetitions": settings["repetitions"],
        "min_time": settings["min_time"],
        "filter": settings["filter"],
    }


def collect(binary, data):
    """Benchmarks of one program's JSON output: the repetitions of each, grouped by run name."""
    out, by_name = [], {}
    for run in data.get("benchmarks", []):
        if run.get("run_type", "iteration") != "iteration":
            continue  # mean/median/stddev aggregates: we keep every repetition and recompute
        name = run.get("run_name", run["name"])
        b = by_name.get(name)
        if b is None:
            b = {"binary": binary, "name": name, "label": run.get("label", ""), "time_unit": run.get("time_unit", "ns"),
                 "threads": run.get("threads", 1), "time_kind": bl.time_kind(name, run.get("threads", 1)),
                 "samples": {"real_time": [], "cpu_time": [], "iterations": []}, "counters": {}, "error": None}
            by_name[name] = b
            out.append(b)
        if run.get("error_occurred"):
            b["error"] = run.get("error_message", "error")
            continue
        for k in ("real_time", "cpu_time", "iterations"):
            b["samples"][k].append(run.get(k))
        for k, v in run.items():
            if k not in STANDARD_KEYS and isinstance(v, (int, float)) and not isinstance(v, bool):
                b["counters"].setdefault(k, []).append(v)
    return out


def run_binary(path, settings, tmpdir):
    name = os.path.basename(path)
    out_json = os.path.join(tmpdir, name + ".json")
    cmd = [path, "--benchmark_out=" + out_json, "--benchmark_out_format=json",
           "--benchmark_repetitions={}".format(settings["repetitions"]),
           "--benchmark_report_aggregates_only=false",
           "--benchmark_min_time={:g}".format(settings["min_time"])]
    if settings["filter"]:
        cmd.append("--benchmark_filter=" + settings["filter"])
    log("running", " ".join(cmd[:1] + cmd[3:]))
    start = time.monotonic()
    # The program's console table goes to our stderr as progress; its JSON goes to the file.
    proc = subprocess.run(cmd, stdout=sys.stderr, stderr=sys.stderr)
    seconds = time.monotonic() - start
    info = {"seconds": round(seconds, 2), "returncode": proc.returncode}
    data = {}
    try:
        with open(out_json) as f:
            text = f.read()
        # Google Benchmark leaves the file empty (and exits with 0) when the filter matches none of
        # the program's benchmarks, e.g. a program of Slow benchmarks only in the short mode.
        if text.strip() or proc.returncode != 0:
            data = json.loads(text)
        else:
            info["note"] = "no benchmark matched the filter"
    except (OSError, ValueError) as e:
        info["error"] = "no JSON output ({})".format(e)
    if proc.returncode != 0:
        info["error"] = "exit status {}".format(proc.returncode)
    lib = data.get("context", {})
    info["library_context"] = {k: lib.get(k) for k in ("num_cpus", "mhz_per_cpu", "cpu_scaling_enabled",
                                                       "load_avg", "library_build_type") if k in lib}
    benches = collect(name, data)
    log("{}: {} benchmarks in {:.1f} s{}".format(name, len(benches), seconds,
                                                 ", " + info["error"] if "error" in info else ""))
    return info, benches


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(rl.ROOT, "build"), help="CMake build directory")
    ap.add_argument("--out", default=os.path.join(rl.ROOT, "results", "bench", "latest.json"))
    ap.add_argument("--short", action="store_true", help="CI mode: few repetitions, short minimum time")
    ap.add_argument("--repetitions", type=int, help="override the mode's repetitions")
    ap.add_argument("--min-time", type=float, help="override the mode's minimum seconds per repetition")
    ap.add_argument("--filter", help="Google Benchmark filter regex for every program (replaces the mode's)")
    ap.add_argument("--programs", nargs="*", help="only these programs (names like bench_fields)")
    a = ap.parse_args()

    mode = "short" if a.short else "full"
    settings = dict(SHORT if a.short else FULL)
    if a.repetitions is not None:
        if a.repetitions < 1:
            sys.exit("run_benchmarks: --repetitions must be at least 1")
        settings["repetitions"] = a.repetitions
    if a.min_time is not None:
        settings["min_time"] = a.min_time
    if a.filter is not None:
        settings["filter"] = a.filter

    bindir = os.path.join(a.build, "bin")
    programs = sorted(p for p in glob.glob(os.path.join(bindir, "bench_*"))
                      if os.path.isfile(p) and os.access(p, os.X_OK))
    if a.programs:
        unknown = set(a.programs) - {os.path.basename(p) for p in programs}
        if unknown:
            sys.exit("run_benchmarks: no such benchmark program in {}: {}".format(bindir, ", ".join(sorted(unknown))))
        programs = [p for p in programs if os.path.basename(p) in a.programs]
    if not programs:
        sys.exit("run_benchmarks: no benchmark programs {}/bench_* (build them: make build, with "
                 "CDP_BUILD_BENCHMARKS on)".format(bindir))

    result = {"schema": bl.SCHEMA, "context": context(a.build, mode, settings), "programs": {}, "benchmarks": []}
    start = time.monotonic()
    with tempfile.TemporaryDirectory() as tmp:
        for p in programs:
            info, benches = run_binary(p, settings, tmp)
            result["programs"][os.path.basename(p)] = info
            result["benchmarks"] += benches
    result["context"]["seconds"] = round(time.monotonic() - start, 1)

    os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
    tmp_out = a.out + ".tmp"
    with open(tmp_out, "w") as f:
        json.dump(result, f, indent=1)
        f.write("\n")
    os.replace(tmp_out, a.out)  # never a half-written file
    failed = [n for n, i in result["programs"].items() if "error" in i]
    log("{} benchmarks from {} programs in {:.0f} s -> {}".format(len(result["benchmarks"]), len(programs),
                                                                  result["context"]["seconds"], a.out))
    if failed:
        log("FAILED:", ", ".join(failed))
        sys.exit(1)


if __name__ == "__main__":
    main()
