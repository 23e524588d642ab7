"""What the Python benchmarks (bench/*.py) share: Google Benchmark's flags and JSON, so that
scripts/run_benchmarks.py runs them as it runs the C++ programs. Copied to build/bin/_gbench.py
beside them (bench/CMakeLists.txt); a benchmark imports it from there."""
import argparse
import json
import re
import sys


def main(doc, names, one_repetition):
    """Runs one_repetition() (a dict of each name's figures: real_time in ms and counters, or
    {"error": text}) as many times as --benchmark_repetitions asks when a name passes
    --benchmark_filter, and writes the runs as Google Benchmark's JSON (manual time)."""
    ap = argparse.ArgumentParser(description=doc.split("\n")[0])
    ap.add_argument("--benchmark_out")
    ap.add_argument("--benchmark_out_format", default="json")
    ap.add_argument("--benchmark_repetitions", type=int, default=1)
    ap.add_argument("--benchmark_min_time", default="0")
    ap.add_argument("--benchmark_filter", default=None)
    ap.add_argument("--benchmark_report_aggregates_only", default="false")
    a = ap.parse_args()
    wanted = lambda name: True  # noqa: E731
    if a.benchmark_filter:
        negative = a.benchmark_filter.startswith("-")
        pattern = re.compile(a.benchmark_filter[1:] if negative else a.benchmark_filter)
        wanted = lambda name: bool(pattern.search(name)) != negative  # noqa: E731
    runs = []
    if any(wanted(n) for n in names):
        for repetition in range(max(1, a.benchmark_repetitions)):
            try:
                results = one_repetition()
            except Exception as e:  # a missing package, a failed run: reported, not a crash
                results = {n: {"error": f"{type(e).__name__}: {e}".splitlines()[0]} for n in names}
            for name in names:
                if not wanted(name):
                    continue
                r = results[name]
                run = {"name": name + "/manual_time", "run_name": name + "/manual_time", "run_type": "iteration",
                       "repetitions": a.benchmark_repetitions, "repetition_index": repetition, "threads": 1,
                       "iterations": 1, "time_unit": "ms"}
                if "error" in r:
                    run.update(error_occurred=True, error_message=r["error"], real_time=0.0, cpu_time=0.0)
                else:
                    run.update({k: v for k, v in r.items() if k != "real_time"}, real_time=r["real_time"],
                               cpu_time=r["real_time"])
                runs.append(run)
                print(f"{name}: " + ", ".join(f"{k} {v:.4g}" for k, v in r.items() if isinstance(v, float)),
                      file=sys.stderr)
    out = {"context": {"executable": sys.argv[0], "library_build_type": "release"}, "benchmarks": runs}
    if a.benchmark_out:
        with open(a.benchmark_out, "w") as f:
            json.dump(out, f, indent=1)
    else:
        json.dump(out, sys.stdout, indent=1)
    return 0
