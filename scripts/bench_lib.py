"""Benchmark runs (results/bench/*.json) and the statistics the dashboard applies to them.

A run is the file scripts/run_benchmarks.py writes: {"schema", "context", "programs",
"benchmarks": [{"binary", "name", "label", "time_unit", "time_kind", "threads",
"samples": {"real_time": [...], "cpu_time": [...], "iterations": [...]},
"counters": {name: [one value per repetition]}, "error"}]}.

Noise and regressions (documented on the page too). For one benchmark in one run with n
repetitions x_i: the run's value is the median m, and its noise the robust relative spread of a
single repetition, s = 1.4826 * MAD(x) / m (1.4826 MAD estimates the standard deviation of
normal data; the MAD ignores the odd repetition disturbed by another process), floored at
NOISE_FLOOR because a MAD of three repetitions can come out as zero by chance. Between two runs,
the change is d = ln(m_new / m_old) and the threshold t = Z * sqrt(s_old^2 + s_new^2): a
regression when d > t (slower), an improvement when d < -t. We use the spread of single
repetitions rather than the smaller standard error of the median on purpose: repetitions run
back to back and miss the slower drift between runs (other jobs, clock frequency), so the
tighter bound would flag noise.
"""
import datetime
import json
import math
import os
import re

SCHEMA = "cdp-bench/1"
# Benchmarks whose name contains one of these are skipped by the short (CI) mode.
SHORT_EXCLUDE = "Scaling|Slow"
Z = 3.0
NOISE_FLOOR = 0.005
UNIT_SECONDS = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}


def time_kind(name, threads=1):
    """Which time a benchmark is judged by: wall clock for multi-threaded and manually timed
    benchmarks (Google Benchmark stores the manual time as real_time), CPU time otherwise,
    which other processes on a busy machine disturb less."""
    if name.endswith("/real_time") or name.endswith("/manual_time") or (threads or 1) > 1:
        return "real"
    return "cpu"


def median(xs):
    xs = sorted(xs)
    n = len(xs)
    if n == 0:
        return None
    return xs[n // 2] if n % 2 else 0.5 * (xs[n // 2 - 1] + xs[n // 2])


def mad(xs):
    m = median(xs)
    return median([abs(x - m) for x in xs]) if xs else None


def finite(xs):
    return [x for x in xs if isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)]


def key(bench):
    return bench["binary"] + ":" + bench["name"]


def time_samples(bench):
    """The repetitions' times in seconds (real or CPU time, see time_kind)."""
    kind = bench.get("time_kind") or time_kind(bench["name"], bench.get("threads", 1))
    scale = UNIT_SECONDS.get(bench.get("time_unit", "ns"), 1e-9)
    return [x * scale for x in finite(bench.get("samples", {}).get(kind + "_time", []))]


def relative_spread(xs):
    """1.4826 MAD / median of single repetitions; None with fewer than two repetitions."""
    xs = finite(xs)
    m = median(xs)
    if len(xs) < 2 or not m:
        return None
    return max(1.4826 * mad(xs) / abs(m), NOISE_FLOOR)


def summary(bench):
    xs = time_samples(bench)
    return {"median": median(xs), "spread": relative_spread(xs), "n": len(xs), "min": min(xs) if xs else None,
            "max": max(xs) if xs else None}


def counter_median(bench, name):
    return median(finite(bench.get("counters", {}).get(name, [])))


def compare(old, new, z=Z):
    """Latest (new) against previous (old) time samples in seconds: ratio new/old of the medians,
    the threshold on |ln ratio| and a verdict: regression, improvement, same or unknown."""
    mo, mn = median(finite(old)), median(finite(new))
    if not mo or not mn or mo <= 0 or mn <= 0:
        return {"ratio": None, "threshold": None, "verdict": "unknown", "why": "no valid time"}
    so, sn = relative_spread(old), relative_spread(new)
    ratio = mn / mo
    if so is None or sn is None:
        return {"ratio": ratio, "threshold": None, "verdict": "unknown", "why": "fewer than two repetitions"}
    t = z * math.hypot(so, sn)
    d = math.log(ratio)
    verdict = "regression" if d > t else "improvement" if d < -t else "same"
    return {"ratio": ratio, "threshold": math.exp(t), "verdict": verdict, "why": ""}


def load_run(path):
    """A run file, checked enough that the dashboard can trust its shape."""
    try:
        with open(path) as f:
            run = json.load(f)
    except ValueError as e:
        raise ValueError("{}: not valid JSON ({})".format(path, e))
    if not isinstance(run, dict) or run.get("schema") != SCHEMA or not isinstance(run.get("benchmarks"), list):
        raise ValueError("{}: not a benchmark run (expected schema {!r} with a benchmarks list)".format(path, SCHEMA))
    run.setdefault("context", {})
    run["path"] = path
    return run


def utc(stamp):
    """An ISO 8601 time as UTC "YYYYMMDDTHHMMSSZ" (sorts as text); "" when missing or unreadable."""
    try:
        t = datetime.datetime.fromisoformat((stamp or "").replace("Z", "+00:00"))
    except ValueError:
        return ""
    if t.tzinfo is None:
        t = t.replace(tzinfo=datetime.timezone.utc)
    return t.astimezone(datetime.timezone.utc).strftime("%Y%m%dT%H%M%SZ")


def sort_key(run):
    """Commit order (by commit date), then run date."""
    c = run["context"]
    return (utc(c.get("commit_date")), utc(c.get("date")))


def load_history(directory):
    if not directory or not os.path.isdir(directory):
        return []
    runs = [load_run(os.path.join(directory, n)) for n in sorted(os.listdir(directory)) if n.endswith(".json")]
    return sorted(runs, key=sort_key)


def record_name(run):
    """history/<commit date>-<short commit>.json: one file per commit, in commit order by name."""
    c = run["context"]
    date = utc(c.get("commit_date")) or utc(c.get("date")) or "undated"
    short = (c.get("commit_short") or (c.get("commit") or "")[:7]) or "nocommit"
    return "{}-{}.json".format(date, re.sub(r"[^0-9A-Za-z]", "", short) or "nocommit")


def run_label(run):
    c = run["context"]
    s = c.get("commit_short") or "?"
    return s + ("+" if c.get("dirty") else "")


# ---- ratios measured inside one run ----

POLYGONIZERS = ("adaptive", "mc", "mt")
_NAME_METHODS = {"adaptive": "adaptive", "marchingcubes": "mc", "mc": "mc", "marchingtetrahedra": "mt", "mt": "mt"}


def polygonizer_of(bench):
    """(field, method, variant) of a polygonizer benchmark, or None. The label
    "<field>/<method>[/<variant>]" (method adaptive, mc or mt, as bench_marching writes) wins;
    otherwise a name "BM_<Method>/<field>/<rest>" with Method Adaptive, MC, MT, MarchingCubes or
    MarchingTetrahedra (bench/README.md)."""
    parts = (bench.get("label") or "").split("/")
    if len(parts) >= 2 and parts[1] in POLYGONIZERS and parts[0]:
        return parts[0], parts[1], "/".join(parts[2:])
    parts = bench["name"].split("/")
    head = parts[0][3:].lower() if parts[0].startswith("BM_") else ""
    if head in _NAME_METHODS and len(parts) >= 2:
        return parts[1], _NAME_METHODS[head], "/".join(parts[2:])
    return None


def adaptive_vs_marching(run, counter="triangles_per_second"):
    """Per field and adaptive benchmark: its triangles per second against the fastest MT and MC
    benchmark of the same field in the same run."""
    by_field = {}
    for b in run["benchmarks"]:
        p = polygonizer_of(b)
        v = counter_median(b, counter) if p else None
        if p and v:
            by_field.setdefault(p[0], {}).setdefault(p[1], []).append((v, b))
    rows = []
    for field in sorted(by_field):
        m = by_field[field]
        best = {meth: max(m[meth], key=lambda t: t[0]) for meth in ("mt", "mc") if meth in m}
        for v, b in m.get("adaptive", []):
            row = {"field": field, "benchmark": key(b), "adaptive": v}
            for meth, (mv, mb) in best.items():
                row[meth] = mv
                row[meth + "_benchmark"] = key(mb)
                row["vs_" + meth] = v / mv
            rows.append(row)
    return rows


_BATCHED = ("values_batched", "batched", "vectorized")
_SCALAR = ("values_scalar", "scalar")


def _rate(b):
    for k in sorted(b.get("counters", {})):
        if k.endswith("per_second") or k.endswith("per_s"):
            v = counter_median(b, k)
            if v:
                return v, k
    return None, None


def batched_vs_scalar(run):
    """Vectorization gain: a batched benchmark against its scalar twin (names differing in one
    component, batched/values_batched/vectorized against scalar/values_scalar), by a rate
    counter both have, else by inverse time."""
    benches = {key(b): b for b in run["benchmarks"] if not b.get("error")}
    rows = []
    for k, b in benches.items():
        parts = k.split("/")
        for i, p in enumerate(parts):
            if p not in _BATCHED:
                continue
            for s in _SCALAR:
                twin = benches.get("/".join(parts[:i] + [s] + parts[i + 1:]))
                if twin is None:
                    continue
                (rb, cb), (rs, cs) = _rate(b), _rate(twin)
                if rb and rs and cb == cs:
                    gain, how = rb / rs, cb
                else:
                    tb, ts = summary(b)["median"], summary(twin)["median"]
                    gain, how = (ts / tb if tb and ts else None), "time"
                rows.append({"batched": k, "scalar": key(twin), "gain": gain, "by": how})
    return sorted(rows, key=lambda r: r["batched"])


def regions_vs_whole(run):
    """An expression's evaluation with its programs specialized to the cells of its box against the
    whole formula at the same points (BM_Field/<field>/<kind> against BM_Field/<field>_whole/<kind>,
    bench/fields.cpp), by their rate counter."""
    benches = {key(b): b for b in run["benchmarks"] if not b.get("error")}
    rows = []
    for k, whole in benches.items():
        parts = k.split("/")
        if len(parts) < 3 or not parts[1].endswith("_whole"):
            continue
        b = benches.get("/".join([parts[0], parts[1][:-len("_whole")]] + parts[2:]))
        if b is None:
            continue
        (rb, cb), (rw, cw) = _rate(b), _rate(whole)
        if rb and rw and cb == cw:
            rows.append({"benchmark": key(b), "whole": k, "speedup": rb / rw})
    return sorted(rows, key=lambda r: r["benchmark"])


def thread_speedups(run):
    """Rows {benchmark, label, speedup, one, two, p8, p16, q8, q16, passes} of the benchmarks that time
    one run on one thread and one on two (counter speedup_1_to_2; bench/adaptive.cpp's
    BM_AdaptiveThreads and BM_AdaptiveBlocks), with the speedups the latter projects at 8 and 16
    threads, all time outside the blocks serial (p) or the run's parallel passes shared as they
    scaled from one thread to two (q; passes: that measured speedup); None where not reported."""
    rows = []
    for b in run["benchmarks"]:
        v = None if b.get("error") else counter_median(b, "speedup_1_to_2")
        if v is not None:
            rows.append({"benchmark": key(b), "label": b.get("label", ""), "speedup": v,
                         "one": counter_median(b, "seconds_1_thread"), "two": counter_median(b, "seconds_2_threads"),
                         "p8": counter_median(b, "projected_speedup_8"), "p16": counter_median(b, "projected_speedup_16"),
                         "q8": counter_median(b, "projected_speedup_8_passes"),
                         "q16": counter_median(b, "projected_speedup_16_passes"),
                         "passes": counter_median(b, "pass_speedup_1_to_2")})
    return sorted(rows, key=lambda r: r["benchmark"])


# BM_BlocksClusterProjectionSlow's projection of a run of 10^9 triangles on 64 workers (seconds),
# and what bounds it: the client's part, the blocks' makespan, the pieces' transfer, the largest block.
CLUSTER_PARTS = ("client", "blocks", "transfer", "largest_block")


def cluster_projections(run):
    """Rows {benchmark, label, seconds, one_worker, parts: {part: seconds}, bound, client_mesh_gb,
    piece_bytes} of the benchmarks reporting projected_seconds (bench/adaptive.cpp's
    BM_BlocksClusterProjectionSlow); bound is the part that takes longest."""
    rows = []
    for b in run["benchmarks"]:
        v = None if b.get("error") else counter_median(b, "projected_seconds")
        if v is None:
            continue
        parts = {p: counter_median(b, "projected_" + p + "_seconds") for p in CLUSTER_PARTS}
        known = {p: t for p, t in parts.items() if t is not None}
        rows.append({"benchmark": key(b), "label": b.get("label", ""), "seconds": v,
                     "one_worker": counter_median(b, "projected_one_worker_seconds"), "parts": parts,
                     "bound": max(known, key=known.get) if known else None,
                     "client_mesh_gb": counter_median(b, "client_mesh_gb"),
                     "piece_bytes": counter_median(b, "piece_bytes_per_triangle")})
    return sorted(rows, key=lambda r: r["benchmark"])


def peak_memory(run):
    """Rows {benchmark, label, small, large, mb_small, mb_large, bytes_small, bytes_large, ratio,
    triangle_ratio} of the benchmarks reporting peak_ratio (bench/adaptive.cpp's BM_PeakMemorySlow:
    the polygonize program's peak resident memory at two sizes of the same surface; issue 58's
    aim: a ratio of at most 1.3 where the triangles grow tenfold)."""
    rows = []
    for b in run["benchmarks"]:
        v = None if b.get("error") else counter_median(b, "peak_ratio")
        if v is None:
            continue
        c = {k: counter_median(b, k) for k in ("triangles_small", "triangles_large", "peak_mb_small", "peak_mb_large",
                                               "bytes_per_triangle_small", "bytes_per_triangle_large",
                                               "triangle_ratio")}
        rows.append({"benchmark": key(b), "label": b.get("label", ""), "ratio": v,
                     "small": c["triangles_small"], "large": c["triangles_large"],
                     "mb_small": c["peak_mb_small"], "mb_large": c["peak_mb_large"],
                     "bytes_small": c["bytes_per_triangle_small"], "bytes_large": c["bytes_per_triangle_large"],
                     "triangle_ratio": c["triangle_ratio"]})
    return sorted(rows, key=lambda r: r["benchmark"])


def sdf_model_costs(run):
    """Rows {benchmark, label, creases, sphere, triangles} of the benchmarks that mesh an SDF model
    with its creases followed and ignored and a sphere beside it (counters creases_cost_ratio and
    per_triangle_vs_sphere; bench/adaptive.cpp's BM_AdaptiveSdf). creases is None for a model
    that cannot be meshed with its creases ignored (a Menger sponge)."""
    rows = []
    for b in run["benchmarks"]:
        v = None if b.get("error") else counter_median(b, "per_triangle_vs_sphere")
        if v is not None:
            rows.append({"benchmark": key(b), "label": b.get("label", ""),
                         "creases": counter_median(b, "creases_cost_ratio"), "sphere": v,
                         "triangles": counter_median(b, "triangles")})
    return sorted(rows, key=lambda r: r["benchmark"])


PER_ITEM_COUNTERS = ("evals_per_vertex", "evaluations_per_vertex", "tracking_evals_per_vertex", "evaluations_per_triangle")


# BM_AdaptiveBookkeeping's microseconds per vertex outside the field: the whole run's and each
# phase's (the run's stats "phases"), with the field's own beside them.
BOOKKEEPING_PHASES = ("seed_grid", "creases", "tracking", "quality", "checks")


def bookkeeping_by_phase(run):
    """Rows {benchmark, label, total, field, phases: {phase: value}} of the benchmarks reporting
    us_per_vertex and per-phase PHASE_us_per_vertex (None where a counter is missing)."""
    rows = []
    for b in run["benchmarks"]:
        total = counter_median(b, "us_per_vertex")
        if total is None:
            continue
        rows.append({"benchmark": key(b), "label": b.get("label", ""), "total": total,
                     "field": counter_median(b, "field_us_per_vertex"),
                     "phases": {p: counter_median(b, p + "_us_per_vertex") for p in BOOKKEEPING_PHASES}})
    return sorted(rows, key=lambda r: r["benchmark"])


def evaluations_per_item(run):
    rows = []
    for b in run["benchmarks"]:
        for c in PER_ITEM_COUNTERS:
            v = counter_median(b, c)
            if v is not None:
                rows.append({"benchmark": key(b), "label": b.get("label", ""), "counter": c, "value": v})
    return rows


# ---- time to accuracy (bench/time_to_accuracy.cpp) ----

TTA_PREFIX = "BM_SlowTimeToAccuracy/"
# The message of a time-to-accuracy entry whose parameter ladder did not reach the target: a
# result (the method cannot get there within the bounds), not a broken benchmark.
UNREACHED = " not reached up to "


def unreached(bench):
    """True for a benchmark skipped because its accuracy target was not reached."""
    return bool(bench.get("error")) and UNREACHED in bench["error"]


def time_to_accuracy(run):
    """Rows {field, family, target, benchmark, seconds, triangles, parameter, parameter_name, error
    (the accuracy reached), vs_mt, vs_mc, overhead, budget, missing} of the
    BM_SlowTimeToAccuracy/<field>/<family>/<target>[/...] benchmarks; missing holds the message
    when the target was not reached. overhead and budget (adaptive entries) are the counters
    overhead_us_per_vertex and budget_us_per_vertex: the run's time per vertex beyond its floor of
    field calls and its seed grid, and what that may be for half of MT's and MC's time."""
    rows = []
    for b in run["benchmarks"]:
        if not b["name"].startswith(TTA_PREFIX):
            continue
        parts = b["name"][len(TTA_PREFIX):].split("/")
        if len(parts) < 3:
            continue
        field, family, target = parts[:3]
        row = {"field": field, "family": family, "target": target, "benchmark": key(b), "missing": b.get("error"),
               "seconds": None, "triangles": None, "parameter": None, "parameter_name": None, "error": None,
               "vs_mt": None, "vs_mc": None, "overhead": None, "budget": None}
        if not b.get("error"):
            row["seconds"] = summary(b)["median"]
            row["triangles"] = counter_median(b, "triangles")
            for name in ("factor", "tolerance_per_diag", "chord_per_diag", "precision", "cell_per_diag"):
                if counter_median(b, name) is not None:
                    row["parameter"], row["parameter_name"] = counter_median(b, name), name
            row["error"] = counter_median(b, "phong_deg" if target == "phong" else "depth_relative")
            row["vs_mt"], row["vs_mc"] = counter_median(b, "vs_mt"), counter_median(b, "vs_mc")
            row["overhead"] = counter_median(b, "overhead_us_per_vertex")
            row["budget"] = counter_median(b, "budget_us_per_vertex")
        rows.append(row)
    return rows


# ---- export for benchmark-tracking CI actions ----

def export(run):
    """github-action-benchmark's custom formats: (smaller_is_better, bigger_is_better), each a
    list of {name, unit, value, range, extra}. Times are medians in the benchmark's own unit;
    rate counters (…per_second, …per_s) and the in-run gains go to the bigger-is-better list, the
    in-run costs (an SDF model's crease handling and time per triangle against a sphere) to the
    smaller-is-better one."""
    c = run["context"]
    smaller, bigger = [], []
    for b in run["benchmarks"]:
        if b.get("error"):
            continue
        s = summary(b)
        if s["median"] is None:
            continue
        unit = b.get("time_unit", "ns")
        entry = {"name": key(b), "unit": unit, "value": s["median"] / UNIT_SECONDS.get(unit, 1e-9),
                 "extra": "{} time, median of {} repetitions, commit {}".format(b.get("time_kind", "cpu"), s["n"],
                                                                              c.get("commit_short", "?"))}
        if s["spread"] is not None:
            entry["range"] = "± {:.1f}%".format(100 * s["spread"])
        smaller.append(entry)
        for cn in sorted(b.get("counters", {})):
            if cn.endswith("per_second") or cn.endswith("per_s"):
                v = counter_median(b, cn)
                if v is not None:
                    bigger.append({"name": key(b) + " " + cn, "unit": "1/s", "value": v})
    for r in adaptive_vs_marching(run):
        for meth in ("mt", "mc"):
            if "vs_" + meth in r:
                bigger.append({"name": "ratio adaptive/{} triangles_per_second {}".format(meth, r["benchmark"]),
                               "unit": "ratio", "value": r["vs_" + meth]})
    for r in batched_vs_scalar(run):
        if r["gain"]:
            bigger.append({"name": "ratio batched/scalar " + r["batched"], "unit": "ratio", "value": r["gain"]})
    for r in thread_speedups(run):
        bigger.append({"name": "ratio 1/2 threads " + r["benchmark"], "unit": "ratio", "value": r["speedup"]})
    for r in sdf_model_costs(run):  # costs: smaller is better
        if r["creases"] is not None:
            smaller.append({"name": "ratio creases follow/ignore " + r["benchmark"], "unit": "ratio",
                            "value": r["creases"]})
        smaller.append({"name": "ratio per triangle sdf/sphere " + r["benchmark"], "unit": "ratio", "value": r["sphere"]})
    return smaller, bigger
