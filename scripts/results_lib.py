"""Shared reading of experiment summaries and the paper's Table 1 for the reproduction scripts."""
import json
import math
import os
import platform
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAPER_TABLE = os.path.join(ROOT, "data", "paper_table1.json")
# The adaptive method's sweeps aimed at a distance (polygonize --tolerance, --chord): no paper
# row matches them, and they are drawn and tabled apart from the factor's runs.
DISTANCE_SWEEPS = ("tolerance", "chord")


def load_summary(name, results=None):
    path = os.path.join(results or os.path.join(ROOT, "results"), name, "summary.json")
    with open(path) as f:
        return json.load(f)


def load_paper_table(path=PAPER_TABLE):
    """The paper's rows as dicts keyed by its column names, per method ('adaptive', 'mt')."""
    with open(path) as f:
        t = json.load(f)
    cols = t["columns"]
    rows = {"adaptive": [dict(zip(cols, r)) for r in t["ours"]],
            "mt": [dict(zip(cols, r)) for r in t["marching_tetrahedra"]]}
    return t, rows


def get(d, *keys, default=None):
    for k in keys:
        if not isinstance(d, dict) or k not in d:
            return default
        d = d[k]
    return d


def number(x):
    return x if isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) else None


def silhouette_fraction(metrics):
    s = get(metrics, "silhouette_disagreement")
    if isinstance(s, dict):
        return number(s.get("fraction"))
    return number(s)


def per(count, n):
    count = number(count)
    return count / n if count is not None and n else None


def outside_field_us(stats, metrics, seconds, vertices):
    """Microseconds per vertex the run spent outside field evaluations (None without a price list)."""
    cost = get(metrics, "field_cost")
    ev = get(stats, "field_evaluations")
    if not isinstance(cost, dict) or not isinstance(ev, dict) or not seconds or not vertices:
        return None
    try:
        field = 1e-6 * (ev.get("value", 0) * cost["value_us"] + ev.get("value_gradient", 0) * cost["value_gradient_us"] +
                        ev.get("gradient_hessian", 0) * cost["gradient_hessian_us"])
    except (KeyError, TypeError):
        return None
    return 1e6 * (seconds - field) / vertices


def time_range_ms(stats):
    """The middle half of a repeated run's times in ms (the 2nd and 4th of 5, the extremes of 3
    or fewer), or None for a run timed once. Not the fastest and slowest: those spread further
    the more often a run is repeated, the middle half does not."""
    times = [number(t) for t in stats.get("repeat_seconds") or []]
    if len(times) < 2 or None in times:
        return None
    times.sort()
    q = (len(times) - 1) // 4
    return (1000 * times[q], 1000 * times[len(times) - 1 - q])


def run_row(run):
    """The numbers of one run that the tables, claims and plots use (None where missing)."""
    st, m = run.get("stats", {}), run.get("metrics", {})
    tri = number(get(st, "triangles"))
    sec = number(get(st, "seconds"))
    ev = number(get(st, "field_evaluations", "total"))
    verts = number(get(st, "vertices"))
    return {
        "id": run["id"], "method": run["method"], "parameter_name": run["parameter_name"],
        "variant": run.get("variant", ""),
        "parameter": run["parameter"], "status": run.get("status"), "reason": run.get("reason", ""),
        "time_ms": sec * 1000 if sec is not None else None,
        # With experiment "repeats" (polygonize --repeat) `time_ms` is the median of several runs
        # and this the middle half of their times, which the claims on time compare rather than
        # single times.
        "time_ms_range": time_range_ms(st),
        "triangles": tri, "vertices": verts,
        "triangles_per_s": tri / sec if tri and sec else None,
        "evaluations_per_triangle": ev / tri if ev and tri else None,
        "evaluations_per_vertex": ev / verts if ev and verts else None,
        "curvature_seconds": number(get(st, "curvature_seconds")),
        "hessian_seconds": number(get(st, "hessian_seconds")),
        "hessian_evaluations": number(get(st, "field_evaluations", "gradient_hessian")),
        # Evaluations per vertex by kind, and the time outside the field per vertex: the run's time
        # less its evaluation counts priced by evaluate's field_cost (an estimate, see
        # raytrace/include/cdp/raytrace/field_cost.h).
        "values_per_vertex": per(get(st, "field_evaluations", "value"), verts),
        "value_gradients_per_vertex": per(get(st, "field_evaluations", "value_gradient"), verts),
        "hessians_per_vertex": per(get(st, "field_evaluations", "gradient_hessian"), verts),
        "outside_field_us_per_vertex": outside_field_us(st, m, sec, verts),
        "shares_at_most": get(m, "edge_ratio", "share_at_most"),
        "self_intersections": get(m, "topology", "self_intersections", "pairs"),
        "seconds": sec,
        "ratio_ls": number(get(m, "edge_ratio", "mean")),
        "deviation": number(get(m, "edge_ratio", "std")),
        "edge_ratio_histogram": get(m, "edge_ratio", "histogram"),
        "depth_error": number(get(m, "depth_error", "mean")),
        "depth_error_relative": number(get(m, "depth_error", "relative_mean")),
        "phong_error": number(get(m, "phong_error_deg", "mean")),
        "phong_stdev": number(get(m, "phong_error_deg", "std")),
        "silhouette": silhouette_fraction(m),
        "near_equilateral": number(get(m, "near_equilateral_fraction")),
        "min_angle_min": number(get(m, "min_angle_deg", "min")),
        "angle_cumulative": get(m, "min_angle_deg", "cumulative_below_degrees"),
        "min_angle_mean": number(get(m, "min_angle_deg", "mean")),
        "closed": get(m, "topology", "closed"),
        "manifold": get(m, "topology", "manifold"),
        "components": get(m, "topology", "components"),
        "genus": get(m, "topology", "genus"),
    }


def rows_by_method(summary):
    out = {}
    for run in summary["runs"]:
        r = run_row(run)
        key = (r["method"] + ("_paper" if r["variant"] == "paper" else "") +
               ("_" + r["parameter_name"] if r["parameter_name"] in DISTANCE_SWEEPS else ""))
        out.setdefault(key, []).append(r)
    for rows in out.values():
        rows.sort(key=lambda r: r["parameter"])
    return out


def environment(build_dir):
    """Machine, compiler, build type and commit, recorded with every table."""
    env = {"machine": platform.machine(), "cpu": "", "cores": os.cpu_count()}
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    env["cpu"] = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    cache = {}
    try:
        with open(os.path.join(build_dir, "CMakeCache.txt")) as f:
            for line in f:
                if "=" in line and ":" in line.split("=", 1)[0]:
                    k, v = line.rstrip("\n").split("=", 1)
                    cache[k.split(":")[0]] = v
    except OSError:
        pass
    env["build_type"] = cache.get("CMAKE_BUILD_TYPE", "")
    compiler = cache.get("CMAKE_CXX_COMPILER", "c++")
    try:
        env["compiler"] = subprocess.run([compiler, "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        env["compiler"] = compiler
    try:
        env["commit"] = subprocess.run(["git", "-C", ROOT, "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
        # results/ itself is rewritten by the run being described: only the rest of the tree
        # says whether the code that produced it was committed.
        dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no", "--", ".",
                                ":(exclude)results"],
                               capture_output=True, text=True).stdout.strip()
        env["dirty"] = bool(dirty)
    except OSError:
        env["commit"] = ""
    return env


def interpolate_loglog(xs, ys, x):
    """y at x on the log-log polyline through (xs, ys); None outside the range."""
    pts = sorted((a, b) for a, b in zip(xs, ys) if a and b and a > 0 and b > 0)
    for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
        if x0 <= x <= x1:
            if x1 == x0:
                return y0
            t = (math.log(x) - math.log(x0)) / (math.log(x1) - math.log(x0))
            return math.exp(math.log(y0) + t * (math.log(y1) - math.log(y0)))
    return None
