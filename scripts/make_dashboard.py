#!/usr/bin/python3
"""The performance dashboard: a static, self-contained HTML page from the recorded benchmark runs.

Reads results/bench/history/*.json (one run per recorded commit, scripts/record_benchmark.py)
and results/bench/latest.json (shown as an extra, unrecorded point when it is not in the
history), and results/table1.json (quality, scripts/table1.py) when present. Writes
results/dashboard/index.html (matplotlib plots embedded as base64 PNGs: no network needed) and,
beside it, the export for benchmark-tracking CI actions (github-action-benchmark):
benchmark-action.json ("customSmallerIsBetter": median times) and benchmark-action-bigger.json
("customBiggerIsBetter": rates and in-run ratios). Works with any number of runs, zero included.

  scripts/make_dashboard.py --history results/bench/history --latest results/bench/latest.json \\
      --table results/table1.json --out results/dashboard/index.html
"""
import argparse
import base64
import html
import io
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import bench_lib as bl  # noqa: E402

E = html.escape
COLUMNS = 4
MAX_PANELS = 40  # per figure; a larger family is split over several figures


def png(fig, tight=True):
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=72, bbox_inches="tight" if tight else None, metadata={"Software": None})
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def img(data, alt):
    return '<img class="plot" alt="{}" src="data:image/png;base64,{}">'.format(E(alt), data)


def fnum(v, f="{:.3g}"):
    return "—" if v is None else f.format(v)


def table(head, rows, cls=""):
    out = ['<table class="{}"><tr>'.format(cls) + "".join("<th>{}</th>".format(E(h)) for h in head) + "</tr>"]
    for r in rows:
        attrs = ""
        if isinstance(r, tuple):
            attrs, r = ' class="{}"'.format(r[0]), r[1]
        out.append("<tr{}>".format(attrs) + "".join("<td>{}</td>".format(c) for c in r) + "</tr>")
    return "".join(out) + "</table>"


def load_runs(history_dir, latest_path):
    runs = bl.load_history(history_dir)
    for r in runs:
        r["recorded"] = True
    if latest_path and os.path.exists(latest_path):
        latest = bl.load_run(latest_path)
        c = latest["context"]
        same = [r for r in runs if r["context"].get("commit") == c.get("commit") and r["context"].get("date") == c.get("date")]
        if not same:
            latest["recorded"] = False
            runs.append(latest)  # the newest run goes last even if its commit is older
    return runs


def label(run):
    return bl.run_label(run) + ("" if run.get("recorded", True) else "*")


# ---- sections ----

def context_section(runs):
    if not runs:
        return ("<h2>Runs</h2><p class=\"warn\">No benchmark runs yet. <code>make bench</code> writes "
                "results/bench/latest.json, <code>make bench-record</code> adds it to the history.</p>")
    rows = []
    for r in reversed(runs):
        c = r["context"]
        rows.append([E(label(r)), E(c.get("commit_subject", "")), E(c.get("commit_date", "")), E(c.get("date", "")),
                     E(c.get("mode", "")), str(len(r["benchmarks"])), E(c.get("cpu", "")), E(str(c.get("cores", "")))])
    c = runs[-1]["context"]
    progs = runs[-1].get("programs", {})
    prog_rows = [[E(n), fnum(i.get("seconds"), "{:.1f}"), E(i.get("error", "ok"))] for n, i in sorted(progs.items())]
    return ("<h2>Runs</h2><p>{} run(s); newest last in the plots. * marks results/bench/latest.json when it is not "
            "recorded in the history; + a run made with uncommitted changes.</p>".format(len(runs)) +
            table(["Commit", "Subject", "Commit date", "Run date", "Mode", "Benchmarks", "CPU", "Cores"], rows) +
            "<h3>Latest run</h3><ul>" +
            "".join("<li>{}: <code>{}</code></li>".format(E(k), E(str(c.get(k, ""))))
                    for k in ("commit", "date", "compiler", "compiler_flags", "build_type", "cpu", "cores", "mode",
                              "repetitions", "min_time", "filter", "load_average", "seconds")) +
            "</ul>" + (table(["Program", "Seconds", "Status"], prog_rows) if prog_rows else ""))


def regression_section(runs):
    out = ["<h2>Latest against previous</h2>"]
    if len(runs) < 2:
        return out[0] + "<p>Needs two runs; there {} {}.</p>".format("is" if len(runs) == 1 else "are", len(runs))
    old, new = runs[-2], runs[-1]
    co, cn = old["context"], new["context"]
    out.append("<p>{} against {}. Time ratio latest/previous of the medians; flagged when |ln ratio| exceeds "
               "{:g}·√(s<sub>old</sub>² + s<sub>new</sub>²), s = 1.4826·MAD/median of each run's repetitions "
               "(at least {:g}%). The threshold column is that bound as a ratio.</p>".format(
                   E(label(new)), E(label(old)), bl.Z, 100 * bl.NOISE_FLOOR))
    if co.get("cpu") != cn.get("cpu") or co.get("cores") != cn.get("cores"):
        out.append('<p class="warn">The two runs are on different machines ({} / {}): absolute times do not '
                   'compare; see the in-run ratios.</p>'.format(E(str(co.get("cpu"))), E(str(cn.get("cpu")))))
    if co.get("mode") != cn.get("mode"):
        out.append('<p class="warn">Different modes ({} / {}).</p>'.format(E(str(co.get("mode"))), E(str(cn.get("mode")))))
    olds = {bl.key(b): b for b in old["benchmarks"] if not b.get("error")}
    rows, counts = [], {"regression": 0, "improvement": 0, "same": 0, "unknown": 0}
    for b in new["benchmarks"]:
        k = bl.key(b)
        if bl.unreached(b) and k not in olds:
            # A time-to-accuracy target the ladder does not reach: a result, not a failure, unless
            # the previous run reached it (then it is a regression, below).
            rows.append(("unknown", [E(k), "", "", "", "missing: " + E(b["error"])]))
            counts["unknown"] += 1
            continue
        if b.get("error"):
            rows.append(("regression", [E(k), "", "", "", "error: " + E(b["error"])]))
            counts["regression"] += 1
            continue
        if k not in olds:
            continue
        c = bl.compare(bl.time_samples(olds[k]), bl.time_samples(b))
        counts[c["verdict"]] += 1
        rows.append((c["verdict"], [E(k), fnum(c["ratio"], "{:.3f}"), fnum(c["threshold"], "{:.3f}"),
                                    E(b.get("time_kind", "")), E(c["verdict"] + (" (" + c["why"] + ")" if c["why"] else ""))]))
    order = {"regression": 0, "improvement": 1, "unknown": 2, "same": 3}
    rows.sort(key=lambda r: (order[r[0]], r[1][0]))
    added = sorted(set(bl.key(b) for b in new["benchmarks"]) - set(olds))
    removed = sorted(set(olds) - set(bl.key(b) for b in new["benchmarks"]))
    out.append('<p class="summary">{regression} regression(s), {improvement} improvement(s), {same} within noise, '
               '{unknown} unknown.</p>'.format(**counts))
    flagged = [r for r in rows if r[0] in ("regression", "improvement")]
    head = ["Benchmark", "Ratio", "Threshold", "Time", "Verdict"]
    if flagged:
        out.append(table(head, flagged))
    out.append("<details><summary>All {} compared benchmarks</summary>{}</details>".format(len(rows), table(head, rows)))
    if added or removed:
        out.append("<p>New: {}. Gone: {}.</p>".format(E(", ".join(added)) or "none", E(", ".join(removed)) or "none"))
    return "".join(out)


def ratio_plot(runs, series, title, ylabel):
    """series: {line name: [value or None per run]}."""
    fig, ax = plt.subplots(figsize=(9, 3.2))
    x = list(range(len(runs)))
    for name, ys in sorted(series.items()):
        pts = [(i, y) for i, y in zip(x, ys) if y is not None]
        if pts:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label=name, ms=4)
    ax.set_xticks(x)
    ax.set_xticklabels([label(r) for r in runs], rotation=45, ha="right", fontsize=7)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.axhline(1.0, color="gray", lw=0.8, ls=":")
    ax.grid(alpha=0.3)
    if len(series) <= 12:
        ax.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.0, 0.5))
    return png(fig)


def ratio_series(runs, rows_of, name, value):
    """{benchmark name without its program: [row[value] per run, None where missing]} of the rows
    rows_of(run) gives for each run, named by row[name]."""
    series = {}
    for i, run in enumerate(runs):
        for r in rows_of(run):
            series.setdefault(r[name].split(":", 1)[1], [None] * len(runs))[i] = r[value]
    return series


def inrun_section(runs):
    out = ["<h2>Ratios measured in one run</h2><p>Absolute times drift between machines; these ratios of two "
           "benchmarks of the same run do not (much).</p>"]
    if not runs:
        return out[0] + "<p>No runs.</p>"
    latest = runs[-1]

    # Adaptive against MT and MC.
    rows = bl.adaptive_vs_marching(latest)
    out.append("<h3>Adaptive against Marching Tetrahedra and Marching Cubes, triangles per second</h3>")
    if rows:
        out.append(table(["Field", "Adaptive benchmark", "Adaptive tri/s", "MT tri/s (fastest)", "Adaptive/MT",
                          "MC tri/s (fastest)", "Adaptive/MC"],
                         [[E(r["field"]), E(r["benchmark"]), fnum(r["adaptive"], "{:.4g}"), fnum(r.get("mt"), "{:.4g}"),
                           fnum(r.get("vs_mt"), "{:.3f}"), fnum(r.get("mc"), "{:.4g}"), fnum(r.get("vs_mc"), "{:.3f}")]
                          for r in rows]))
        series = {}
        for i, run in enumerate(runs):
            for r in bl.adaptive_vs_marching(run):
                for m in ("mt", "mc"):
                    if "vs_" + m in r:
                        series.setdefault("{} /{}".format(r["benchmark"].split(":", 1)[1], m), [None] * len(runs))[i] = r["vs_" + m]
        out.append(img(ratio_plot(runs, series, "adaptive / marching, triangles per second", "ratio"),
                       "adaptive vs marching ratio over commits"))
    else:
        fields = sorted({p[0] for b in latest["benchmarks"] for p in [bl.polygonizer_of(b)] if p})
        out.append('<p class="note">Not available: the latest run has no adaptive benchmark with a '
                   '<code>triangles_per_second</code> counter on a field that also has an MT or MC benchmark '
                   '(polygonizer benchmarks found on fields: {}). See bench/README.md for the naming.</p>'.format(
                       E(", ".join(fields)) or "none"))

    # Vectorized against scalar.
    rows = bl.batched_vs_scalar(latest)
    out.append("<h3>Batched (vectorized) against scalar field evaluation</h3>")
    if rows:
        out.append(table(["Batched", "Scalar", "Gain", "By"],
                         [[E(r["batched"]), E(r["scalar"]), fnum(r["gain"], "{:.3f}"), E(r["by"])] for r in rows]))
        series = ratio_series(runs, bl.batched_vs_scalar, "batched", "gain")
        out.append(img(ratio_plot(runs, series, "batched / scalar evaluation rate", "gain"),
                       "batched vs scalar gain over commits"))
    else:
        out.append('<p class="note">Not available: no pair of benchmarks named …/values_batched and …/values_scalar '
                   'in the latest run.</p>')

    # An expression run by cell against the whole formula (the same bits).
    rows = bl.regions_vs_whole(latest)
    out.append("<h3>Expressions by cell against the whole formula (the same bits)</h3>")
    if rows:
        out.append(table(["Benchmark", "Whole formula", "Speedup"],
                         [[E(r["benchmark"]), E(r["whole"]), fnum(r["speedup"], "{:.3f}")] for r in rows]))
        series = ratio_series(runs, bl.regions_vs_whole, "benchmark", "speedup")
        out.append(img(ratio_plot(runs, series, "evaluations per second, by cell / whole", "speedup"),
                       "expression by cell vs whole formula over commits"))
    else:
        out.append('<p class="note">Not available: no pair of benchmarks named BM_Field/&lt;field&gt;/… and '
                   'BM_Field/&lt;field&gt;_whole/… in the latest run.</p>')

    # One thread against two (the same mesh, bit for bit, or the benchmark fails).
    rows = bl.thread_speedups(latest)
    out.append("<h3>Speedup from one thread to two (the same mesh on both)</h3>")
    if rows:
        out.append('<p class="note">Projected from the measured block times (greedy, longest first): with all '
                   'the time outside the blocks serial, and with the run\'s data-parallel passes shared as they '
                   'scaled from one thread to two (that speedup in the last column).</p>')
        out.append(table(["Benchmark", "Label", "1 thread (s)", "2 threads (s)", "Speedup", "Projected at 8",
                          "Projected at 16", "At 8, passes shared", "At 16, passes shared", "Passes 1 to 2"],
                         [[E(r["benchmark"]), E(r["label"]), fnum(r["one"], "{:.4g}"), fnum(r["two"], "{:.4g}"),
                           fnum(r["speedup"], "{:.3f}"), fnum(r["p8"], "{:.2f}"), fnum(r["p16"], "{:.2f}"),
                           fnum(r["q8"], "{:.2f}"), fnum(r["q16"], "{:.2f}"), fnum(r["passes"], "{:.2f}")]
                          for r in rows]))
        series = ratio_series(runs, bl.thread_speedups, "benchmark", "speedup")
        out.append(img(ratio_plot(runs, series, "time on 1 thread / time on 2", "speedup"),
                       "thread speedup over commits"))
    else:
        out.append('<p class="note">Not available: no benchmark reports speedup_1_to_2 in the latest run.</p>')

    # Blocks on a cluster: a run of 10^9 triangles on 64 workers projected from one measured run.
    rows = bl.cluster_projections(latest)
    if rows:
        out.append("<h3>Blocks on a cluster: 10<sup>9</sup> triangles on 64 workers, projected (s)</h3>")
        out.append('<p class="note">From one run\'s measured client time, task times and bytes (bench/README.md, '
                   'BM_BlocksClusterProjectionSlow); the run takes the client\'s part plus the longer of the blocks\' '
                   'makespan and the pieces\' transfer.</p>')
        out.append(table(["Benchmark", "Label", "Projected", "One worker", "Client", "Blocks", "Transfer",
                          "Largest block", "Bound by", "Client mesh (GB)", "Piece bytes / triangle"],
                         [[E(r["benchmark"]), E(r["label"]), fnum(r["seconds"], "{:.4g}"), fnum(r["one_worker"], "{:.4g}")]
                          + [fnum(r["parts"][p], "{:.4g}") for p in bl.CLUSTER_PARTS]
                          + [E(r["bound"] or ""), fnum(r["client_mesh_gb"], "{:.3g}"), fnum(r["piece_bytes"], "{:.3g}")]
                          for r in rows]))

    # Peak memory at two sizes of one surface (issue 58's streaming aim: at most 1.3 times).
    rows = bl.peak_memory(latest)
    if rows:
        out.append("<h3>Peak memory of the polygonize program at two sizes of the torus</h3>")
        out.append('<p class="note">Peak resident memory of the whole program, writing its PLY file '
                   '(bench/README.md, BM_PeakMemorySlow). Streaming finished blocks would keep the ratio under '
                   '1.3; a run that holds the mesh until it writes grows with the triangles.</p>')
        out.append(table(["Benchmark", "Label", "Triangles", "Peak (MB)", "Bytes / triangle", "Triangles, large",
                          "Peak, large (MB)", "Bytes / triangle, large", "Peak ratio", "Triangle ratio"],
                         [[E(r["benchmark"]), E(r["label"]), fnum(r["small"], "{:.4g}"), fnum(r["mb_small"], "{:.4g}"),
                           fnum(r["bytes_small"], "{:.0f}"), fnum(r["large"], "{:.4g}"), fnum(r["mb_large"], "{:.4g}"),
                           fnum(r["bytes_large"], "{:.0f}"), fnum(r["ratio"], "{:.2f}"),
                           fnum(r["triangle_ratio"], "{:.2f}")] for r in rows]))

    # SDF models: the cost of following creases against ignoring them, and against a sphere.
    rows = bl.sdf_model_costs(latest)
    out.append("<h3>SDF models: creases followed against ignored, time per triangle against a sphere</h3>")
    if rows:
        out.append('<p class="note">Measured in one run at factor 3. A C1 model (rounded, smoothly united) has no '
                   'crease, so following creases should cost at most 1.5 times ignoring them; each model at most '
                   '2 times a smooth sphere\'s time per triangle.</p>')
        out.append(table(["Benchmark", "Label", "Triangles", "Follow / ignore", "Per triangle / sphere"],
                         [[E(r["benchmark"]), E(r["label"]), fnum(r["triangles"], "{:.0f}"),
                           fnum(r["creases"], "{:.3f}"), fnum(r["sphere"], "{:.3f}")] for r in rows]))
        series = ratio_series(runs, bl.sdf_model_costs, "benchmark", "creases")
        out.append(img(ratio_plot(runs, series, "time with creases followed / ignored", "creases"),
                       "SDF models' crease cost over commits"))
    else:
        out.append('<p class="note">Not available: no benchmark reports creases_cost_ratio in the latest run.</p>')

    # Where the bookkeeping goes: microseconds per vertex outside the field, by phase.
    rows = bl.bookkeeping_by_phase(latest)
    if rows:
        prev = {r["benchmark"]: r["total"] for r in bl.bookkeeping_by_phase(runs[-2])} if len(runs) > 1 else {}
        out.append("<h3>Time per vertex outside the field, by phase (µs)</h3>")
        out.append('<p class="note">The run\'s time less its field calls priced one by one, split by the phases '
                   'of its stats (<code>phases</code>): the seed grid, the fronts, the repair and relaxation, '
                   'the final checks. The field\'s own time per vertex beside it.</p>')
        out.append(table(["Benchmark", "Label", "Total", "Previous total"] + list(bl.BOOKKEEPING_PHASES) +
                         ["Field"],
                         [[E(r["benchmark"]), E(r["label"]), fnum(r["total"], "{:.2f}"),
                           fnum(prev.get(r["benchmark"]), "{:.2f}")] +
                          [fnum(r["phases"][p], "{:.2f}") for p in bl.BOOKKEEPING_PHASES] +
                          [fnum(r["field"], "{:.2f}")] for r in rows]))

    # Evaluations per vertex (and per triangle).
    rows = bl.evaluations_per_item(latest)
    out.append("<h3>Field evaluations per vertex and per triangle</h3>")
    if rows:
        prev = {(r["benchmark"], r["counter"]): r["value"] for r in bl.evaluations_per_item(runs[-2])} if len(runs) > 1 else {}
        out.append(table(["Benchmark", "Label", "Counter", "Latest", "Previous"],
                         [[E(r["benchmark"]), E(r["label"]), E(r["counter"]), fnum(r["value"], "{:.2f}"),
                           fnum(prev.get((r["benchmark"], r["counter"])), "{:.2f}")] for r in rows]))
    else:
        out.append('<p class="note">Not available: no benchmark reports {}.</p>'.format(
            ", ".join(bl.PER_ITEM_COUNTERS)))
    return "".join(out)


TTA_FAMILIES = (("adaptive_factor", "adaptive (factor)", "o"), ("adaptive_tolerance", "adaptive (tolerance)", "s"),
                ("adaptive_chord", "adaptive (chord)", "D"), ("mt", "MT", "^"), ("mc", "MC", "v"))
TTA_TARGETS = (("phong", "mean Phong error (°)", 0.5), ("depth", "mean depth error / box diagonal", 1e-4))


def time_to_accuracy_section(runs):
    out = ["<h2>Time to accuracy</h2>"]
    rows = bl.time_to_accuracy(runs[-1]) if runs else []
    if not rows:
        return out[0] + ('<p class="note">Not available: the latest run has no <code>BM_SlowTimeToAccuracy</code> '
                         'benchmark (bench/time_to_accuracy.cpp; the short mode skips it).</p>')
    out.append("<p>Per field and method, the fastest run that reaches a mean Phong error ≤ 0.5° and a mean depth "
               "error ≤ 10<sup>−4</sup> of the box diagonal (Table 1's camera: 6 views, 200² rays, perspective), "
               "found by a parameter ladder; time = the polygonizer's own, median of the repetitions. A missing "
               "point is a target the ladder did not reach within its bounds. Adaptive/MT and adaptive/MC are "
               "time ratios for the same field and target (below 1: the adaptive method is faster). Issue 14's "
               "goal is at most 0.5 for both. Overhead is the adaptive run's time per vertex beyond the floor of its "
               "field calls (one Hessian and two value-and-gradient calls a vertex, priced by single calls) and its "
               "seed grid; budget is what it may be for the run to take half of the faster of MT's and MC's time "
               "at the same triangle count (negative: the floor alone is over that).</p>")
    by_field = {}
    for r in rows:
        by_field.setdefault(r["field"], []).append(r)
    names = dict((f, n) for f, n, _ in TTA_FAMILIES)
    order = {f: i for i, (f, _, _) in enumerate(TTA_FAMILIES)}
    for field in sorted(by_field):
        fr = sorted(by_field[field], key=lambda r: (order.get(r["family"], 9), r["target"] != "phong", r["target"]))
        fig, axes = plt.subplots(1, 2, figsize=(9, 3.0), squeeze=False)
        for ax, (target, xlabel, goal) in zip(axes.flat, TTA_TARGETS):
            for fam, name, marker in TTA_FAMILIES:
                pts = [(r["error"], 1e3 * r["seconds"]) for r in fr
                       if r["family"] == fam and r["target"] == target and r["seconds"] and r["error"] is not None]
                if pts:
                    ax.plot([p[0] for p in pts], [p[1] for p in pts], marker, ms=7, label=name)
            ax.axvline(goal, color="gray", lw=0.8, ls=":")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel(xlabel, fontsize=8)
            ax.set_ylabel("ms", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
            ax.set_title("{}: time to reach {} ≤ {:g}".format(field, target, goal), fontsize=9)
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=6)
        fig.tight_layout()
        out.append("<h3>{}</h3>".format(E(field)))
        out.append(img(png(fig), "{} time to accuracy".format(field)))
        out.append(table(["Method", "Target", "Parameter", "Triangles", "Time (ms)", "Error reached", "Adaptive/MT",
                          "Adaptive/MC", "Overhead (µs/vertex)", "Budget (µs/vertex)"],
                         [("" if not r["missing"] else "unknown",
                           [E(names.get(r["family"], r["family"])), E(r["target"]),
                            E("{} {:g}".format(r["parameter_name"], r["parameter"])) if r["parameter"] is not None else "",
                            fnum(r["triangles"], "{:.0f}"), fnum(r["seconds"] and 1e3 * r["seconds"], "{:.1f}"),
                            fnum(r["error"], "{:.3g}"), fnum(r["vs_mt"], "{:.2f}"), fnum(r["vs_mc"], "{:.2f}"),
                            fnum(r["overhead"], "{:.2f}"), fnum(r["budget"], "{:.2f}")]
                           if not r["missing"] else
                           [E(names.get(r["family"], r["family"])), E(r["target"]), "", "", "", "missing: " +
                            E(r["missing"]), "", "", "", ""])
                          for r in fr]))
    return "".join(out)


def quality_section(table_path):
    out = ["<h2>Quality: Table 1 (bunny, VIS 800 constraints)</h2>"]
    if not table_path or not os.path.exists(table_path):
        return out[0] + ('<p class="note">No {} yet: <code>make reproduce</code> writes it. Speed alone does not '
                         'show a faster but worse change.</p>'.format(E(table_path or "results/table1.json")))
    try:
        with open(table_path) as f:
            t = json.load(f)
        rows = t["rows"]
    except (OSError, ValueError, KeyError, TypeError) as e:
        return out[0] + '<p class="warn">{}: unreadable ({}).</p>'.format(E(table_path), E(str(e)))
    env = t.get("environment", {}) if isinstance(t, dict) else {}
    paper = t.get("paper", {}) if isinstance(t.get("paper"), dict) else {}

    def paper_value(r, k):
        for p in paper.get(r.get("method"), []) or []:
            if isinstance(p, dict) and p.get("precision") == r.get("parameter") and r.get("parameter_name") not in ("tolerance", "chord"):  # results_lib.DISTANCE_SWEEPS
                return p.get(k)
        return None

    body = []
    for r in rows:
        if not isinstance(r, dict):
            continue
        ok = r.get("status") == "ok"
        body.append(("" if ok else "regression",
                     [E(str(r.get("method"))), E("{} {}".format(r.get("parameter_name", ""), r.get("parameter", ""))),
                      fnum(r.get("triangles"), "{:.0f}"), fnum(r.get("triangles_per_s"), "{:.0f}"),
                      fnum(r.get("ratio_ls"), "{:.3f}"), fnum(paper_value(r, "ratio_ls"), "{:.3f}"),
                      fnum(r.get("phong_error"), "{:.3f}"), fnum(paper_value(r, "phong_error"), "{:.3f}"),
                      fnum(r.get("evaluations_per_vertex"), "{:.1f}"), E(str(r.get("status")))]))
    out.append("<p>From {} (commit {}{}, {}). Paper values in parentheses columns where the paper has the row.</p>".format(
        E(table_path), E(str(env.get("commit", "?"))[:7]), "+" if env.get("dirty") else "", E(str(env.get("cpu", "")))))
    out.append(table(["Method", "Parameter", "Triangles", "Triangles/s", "Ratio L/s", "(paper)", "Phong error (°)",
                      "(paper)", "Evaluations/vertex", "Status"], body))
    return "".join(out)


def series_section(runs):
    out = ["<h2>Time series per benchmark</h2>"]
    if not runs:
        return out[0] + "<p>No runs.</p>"
    out.append("<p>Median time of the repetitions per run (the time the benchmark is judged by: CPU time, or wall "
               "clock for multi-threaded and manually timed ones); bars span ±1.4826·MAD; red: flagged against the "
               "run before. Grouped by program and benchmark family.</p>")
    families = {}
    for r in runs:
        for b in r["benchmarks"]:
            fam = (b["binary"], b["name"].split("/")[0])
            families.setdefault(fam, [])
            if bl.key(b) not in families[fam]:
                families[fam].append(bl.key(b))
    x = list(range(len(runs)))
    index = [{bl.key(b): b for b in r["benchmarks"]} for r in runs]
    for (binary, fam), keys in sorted(families.items()):
        for start in range(0, len(keys), MAX_PANELS):
            chunk = keys[start:start + MAX_PANELS]
            nrows = (len(chunk) + COLUMNS - 1) // COLUMNS
            ncols = min(COLUMNS, len(chunk))
            width, height = 3.3 * ncols, 2.3 * nrows
            fig, axes = plt.subplots(nrows, ncols, figsize=(width, height), squeeze=False)
            for ax in axes.flat[len(chunk):]:
                ax.axis("off")
            for ax, k in zip(axes.flat, chunk):
                unit = None
                xs, ys, err, flags = [], [], [], []
                prev = None
                for i, idx in enumerate(index):
                    b = idx.get(k)
                    if b is None or b.get("error"):
                        prev = None
                        continue
                    unit = b.get("time_unit", "ns")
                    scale = bl.UNIT_SECONDS.get(unit, 1e-9)
                    s = bl.summary(b)
                    if s["median"] is None:
                        continue
                    xs.append(i)
                    ys.append(s["median"] / scale)
                    err.append((s["spread"] or 0) * s["median"] / scale)
                    samples = bl.time_samples(b)
                    flags.append(prev is not None and bl.compare(prev, samples)["verdict"] == "regression")
                    prev = samples
                ax.errorbar(xs, ys, yerr=err, fmt="o-", ms=3, lw=1, capsize=2)
                bad = [(a, c) for a, c, f in zip(xs, ys, flags) if f]
                if bad:
                    ax.plot([p[0] for p in bad], [p[1] for p in bad], "o", color="red", ms=6)
                name = k.split(":", 1)[1]
                ax.set_title(name if len(name) <= 48 else "…" + name[-47:], fontsize=7)
                ax.set_ylabel(unit or "", fontsize=7)
                ax.set_xticks(x)
                ax.set_xticklabels([label(r) for r in runs], rotation=45, ha="right", fontsize=6)
                ax.tick_params(axis="y", labelsize=6)
                ax.set_xlim(-0.5, len(runs) - 0.5)
                if ys:
                    lo, hi = min(y - e for y, e in zip(ys, err)), max(y + e for y, e in zip(ys, err))
                    pad = max(0.15 * (hi - lo), 0.05 * abs(hi), 1e-30)  # a lone point still gets a readable axis
                    ax.set_ylim(max(0, lo - pad), hi + pad)
                ax.grid(alpha=0.3)
            # Fixed margins in inches rather than tight_layout and a tight bounding box: each of those
            # lays out every label of every panel again, and the page's 600-odd panels took 50 s.
            fig.subplots_adjust(left=0.75 / width, right=1 - 0.1 / width, top=1 - 0.25 / height, bottom=0.8 / height,
                                wspace=0.3, hspace=1.05 / (2.3 - 1.05))
            part = " ({}/{})".format(start // MAX_PANELS + 1, (len(keys) + MAX_PANELS - 1) // MAX_PANELS) \
                if len(keys) > MAX_PANELS else ""
            out.append("<h3>{} {}{}</h3>".format(E(binary), E(fam), E(part)))
            out.append(img(png(fig, tight=False), "{} {} time series".format(binary, fam)))
    return "".join(out)


METHOD = """<h2>Method</h2>
<p>Every benchmark program <code>build/bin/bench_*</code> runs with several repetitions
(<code>scripts/run_benchmarks.py</code>; 5 in full mode, 3 in the CI short mode). A run's value for a
benchmark is the median of its repetitions; its noise is s = 1.4826·MAD/median of the repetitions
(a robust relative standard deviation of one repetition, at least {floor:g}%). Between two runs the change
d = ln(median<sub>new</sub>/median<sub>old</sub>) is a regression when d &gt; {z:g}·√(s<sub>old</sub>² +
s<sub>new</sub>²) and an improvement when d &lt; −{z:g}·√(…). The spread of single repetitions (rather than
the smaller standard error of the median) is used on purpose: repetitions run back to back and miss the
drift between runs. Times are CPU times except for multi-threaded and manually timed benchmarks (wall
clock). Naming conventions the ratios rely on: <code>bench/README.md</code>.</p>
<p>Export for benchmark-tracking CI actions (github-action-benchmark):
<code>benchmark-action.json</code> (tool <code>customSmallerIsBetter</code>, median times) and
<code>benchmark-action-bigger.json</code> (<code>customBiggerIsBetter</code>: rates and in-run ratios),
beside this page.</p>"""

CSS = """body{font-family:sans-serif;max-width:1400px;margin:1em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:0.5em 0;font-size:13px}td,th{border:1px solid #ccc;padding:2px 6px;text-align:left}
th{background:#eee}tr.regression td{background:#fdd}tr.improvement td{background:#dfd}tr.unknown td{color:#777}
.warn{color:#a40;font-weight:bold}.note{color:#555;font-style:italic}img.plot{max-width:100%;display:block;margin:0.5em 0}
code{background:#f4f4f4;padding:0 2px}.summary{font-weight:bold}"""


# A relative link: results/viewer/ is made by make reproduce (scripts/make_viewer.py) beside this page.
VIEWER_LINK = ('<p>The meshes themselves, to turn and compare: <a href="../viewer/index.html">the mesh viewer</a> '
               "(ours beside Marching Tetrahedra and Marching Cubes at matched triangle counts, with each run's "
               "figures).</p>")


def build_page(runs, table_path):
    title = "Performance dashboard"
    if runs:
        title += " — " + label(runs[-1])
    parts = ["<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title><style>{}</style>"
             "</head><body><h1>{}</h1>".format(E(title), CSS, E(title)), VIEWER_LINK,
             context_section(runs), regression_section(runs), inrun_section(runs), time_to_accuracy_section(runs),
             quality_section(table_path),
             series_section(runs), METHOD.format(z=bl.Z, floor=100 * bl.NOISE_FLOOR), "</body></html>\n"]
    return "".join(parts)


def write(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--history", default="results/bench/history")
    ap.add_argument("--latest", default="results/bench/latest.json")
    ap.add_argument("--table", default="results/table1.json")
    ap.add_argument("--out", default="results/dashboard/index.html")
    a = ap.parse_args(argv)
    try:
        runs = load_runs(a.history, a.latest)
    except (OSError, ValueError) as e:
        sys.exit("make_dashboard: {}".format(e))
    out_dir = os.path.dirname(os.path.abspath(a.out))
    os.makedirs(out_dir, exist_ok=True)
    write(a.out, build_page(runs, a.table))
    smaller, bigger = bl.export(runs[-1]) if runs else ([], [])
    write(os.path.join(out_dir, "benchmark-action.json"), json.dumps(smaller, indent=1) + "\n")
    write(os.path.join(out_dir, "benchmark-action-bigger.json"), json.dumps(bigger, indent=1) + "\n")
    print("make_dashboard: {} run(s) -> {} (+ benchmark-action.json, benchmark-action-bigger.json)".format(
        len(runs), a.out))


if __name__ == "__main__":
    main()
