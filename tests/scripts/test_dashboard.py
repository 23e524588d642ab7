#!/usr/bin/python3
"""Tests of the benchmark scripts (scripts/bench_lib.py, record_benchmark.py, make_dashboard.py)
on synthetic runs: regression flags, in-run ratios, history naming, the export format and the
page with zero, one and several runs. Run by ctest (tests/CMakeLists.txt) with /usr/bin/python3."""
import json
import os
import re
import sys
import tempfile
import unittest

sys.dont_write_bytecode = True  # keep the source tree clean when ctest runs this

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))

import bench_lib as bl  # noqa: E402
import make_dashboard  # noqa: E402
import record_benchmark  # noqa: E402

NOISE = [1.00, 1.02, 0.98, 1.01, 0.99]  # about 1.5% spread


def bench(binary, name, times, unit="ms", label="", counters=None, kind="cpu"):
    return {"binary": binary, "name": name, "label": label, "time_unit": unit, "time_kind": kind, "threads": 1,
            "samples": {"real_time": list(times), "cpu_time": list(times), "iterations": [10] * len(times)},
            "counters": {k: list(v) for k, v in (counters or {}).items()}, "error": None}


def run(commit, date, slow=1.0):
    """A synthetic run: two field evaluations (batched 2x faster than scalar), an adaptive and two
    MT benchmarks of the same field (adaptive 2x the fastest MT), one with evaluations per vertex.
    `slow` multiplies the batched benchmark's time."""
    return {"schema": bl.SCHEMA,
            "context": {"commit": commit, "commit_short": commit[:7], "commit_date": date, "date": date,
                        "cpu": "Test CPU", "cores": 2, "mode": "full", "commit_subject": "synthetic"},
            "programs": {"bench_fields": {"seconds": 1.0, "returncode": 0}},
            "benchmarks": [
                bench("bench_fields", "BM_Field/torus/values_batched", [slow * 10 * x for x in NOISE], "us",
                      counters={"evaluations_per_second": [4e8 / slow] * 5}),
                bench("bench_fields", "BM_Field/torus/values_scalar", [20 * x for x in NOISE], "us",
                      counters={"evaluations_per_second": [2e8] * 5}),
                bench("bench_adaptive", "BM_Adaptive/torus/factor:3/manual_time", [50 * x for x in NOISE], kind="real",
                      counters={"triangles_per_second": [2e6] * 5, "evals_per_vertex": [7.5] * 5}),
                bench("bench_marching", "BM_Marching/shape:0/method:1/traversal:0/manual_time",
                      [40 * x for x in NOISE], label="torus/mt/continuation", kind="real",
                      counters={"triangles_per_second": [1e6] * 5}),
                bench("bench_marching", "BM_Marching/shape:0/method:1/traversal:1/manual_time",
                      [80 * x for x in NOISE], label="torus/mt/grid", kind="real",
                      counters={"triangles_per_second": [5e5] * 5}),
            ]}


def write_json(path, data):
    with open(path, "w") as f:
        json.dump(data, f)


def tta_benchmarks(depth_reached=False):
    """bench_time_to_accuracy entries of one field: adaptive and MT reach the Phong target (the
    adaptive method in half MT's time); nobody reaches the depth target unless depth_reached."""
    name = "BM_SlowTimeToAccuracy/bunny_vis800/{}/{}/iterations:1/manual_time"
    ok = [bench("bench_time_to_accuracy", name.format("adaptive_factor", "phong"), [10 * x for x in NOISE], kind="real",
                label="k=3", counters={"triangles": [9000] * 5, "factor": [3] * 5, "phong_deg": [0.45] * 5,
                                       "depth_relative": [2e-4] * 5, "vs_mt": [0.5] * 5,
                                       "overhead_us_per_vertex": [6.5] * 5, "budget_us_per_vertex": [-0.75] * 5}),
          bench("bench_time_to_accuracy", name.format("mt", "phong"), [20 * x for x in NOISE], kind="real",
                label="P4", counters={"triangles": [30000] * 5, "precision": [4] * 5, "phong_deg": [0.4] * 5,
                                      "depth_relative": [3e-4] * 5})]
    depth = bench("bench_time_to_accuracy", name.format("mt", "depth"), [], kind="real")
    if depth_reached:
        depth = bench("bench_time_to_accuracy", name.format("mt", "depth"), [50 * x for x in NOISE], kind="real",
                      counters={"triangles": [90000] * 5, "cell_per_diag": [1 / 256] * 5, "depth_relative": [9e-5] * 5})
    else:
        depth["error"] = "depth target not reached up to h=d/512 (bound reached at h=d/512)"
    return ok + [depth]


class Statistics(unittest.TestCase):
    def test_twice_as_slow_is_a_regression(self):
        c = bl.compare(NOISE, [2 * x for x in NOISE])
        self.assertEqual(c["verdict"], "regression")
        self.assertAlmostEqual(c["ratio"], 2.0)

    def test_twice_as_fast_is_an_improvement(self):
        self.assertEqual(bl.compare(NOISE, [0.5 * x for x in NOISE])["verdict"], "improvement")

    def test_noise_level_change_is_not_flagged(self):
        # Medians 1.00 and 1.01 with ~1.5% spread per repetition in both runs.
        c = bl.compare(NOISE, [1.01, 0.99, 1.03, 1.00, 1.02])
        self.assertEqual(c["verdict"], "same")
        self.assertGreater(c["threshold"], 1.01)

    def test_threshold_follows_the_spread(self):
        # A 10% slowdown: a regression when repetitions agree to 0.5%, noise when they spread by 10%.
        tight = [1.0, 1.005, 0.995]
        loose = [1.0, 1.1, 0.9]
        self.assertEqual(bl.compare(tight, [1.1 * x for x in tight])["verdict"], "regression")
        self.assertEqual(bl.compare(loose, [1.1 * x for x in loose])["verdict"], "same")

    def test_one_repetition_has_no_spread(self):
        self.assertEqual(bl.compare([1.0], [2.0])["verdict"], "unknown")

    def test_median_ignores_one_disturbed_repetition(self):
        s = bl.summary(bench("b", "BM_X", [1.0, 1.0, 9.0, 1.0, 1.0], unit="s"))
        self.assertEqual(s["median"], 1.0)
        self.assertEqual(s["spread"], bl.NOISE_FLOOR)

    def test_time_kind(self):
        self.assertEqual(bl.time_kind("BM_A/1/real_time"), "real")
        self.assertEqual(bl.time_kind("BM_A/1/manual_time"), "real")
        self.assertEqual(bl.time_kind("BM_A/1", threads=4), "real")
        self.assertEqual(bl.time_kind("BM_A/1"), "cpu")


class InRunRatios(unittest.TestCase):
    def test_adaptive_against_fastest_mt_of_the_same_field(self):
        rows = bl.adaptive_vs_marching(run("a" * 40, "2026-01-01T00:00:00+00:00"))
        self.assertEqual(len(rows), 1)
        self.assertEqual(rows[0]["field"], "torus")
        self.assertAlmostEqual(rows[0]["vs_mt"], 2.0)
        self.assertNotIn("vs_mc", rows[0])

    def test_batched_against_scalar(self):
        rows = bl.batched_vs_scalar(run("a" * 40, "2026-01-01T00:00:00+00:00"))
        self.assertEqual(len(rows), 1)
        self.assertAlmostEqual(rows[0]["gain"], 2.0)
        self.assertEqual(rows[0]["by"], "evaluations_per_second")

    def test_thread_speedup(self):
        r = run("a" * 40, "2026-01-01T00:00:00+00:00")
        self.assertEqual(bl.thread_speedups(r), [])
        r["benchmarks"].append(bench("bench_adaptive", "BM_AdaptiveThreads/shape:1/manual_time", [50 * x for x in NOISE],
                                     label="bunny_vis800/adaptive/threads", kind="real",
                                     counters={"seconds_1_thread": [0.06] * 5, "seconds_2_threads": [0.05] * 5,
                                               "speedup_1_to_2": [1.2] * 5}))
        rows = bl.thread_speedups(r)
        self.assertEqual(len(rows), 1)
        self.assertAlmostEqual(rows[0]["speedup"], 1.2)
        self.assertAlmostEqual(rows[0]["two"], 0.05)
        ratios = {e["name"]: e["value"] for e in bl.export(r)[1] if e["unit"] == "ratio"}
        self.assertAlmostEqual(ratios["ratio 1/2 threads bench_adaptive:BM_AdaptiveThreads/shape:1/manual_time"], 1.2)
        page = make_dashboard.inrun_section([r])
        self.assertIn("Speedup from one thread to two", page)
        self.assertIn("1.200", page)
        # The blocks' projections: all outside the blocks serial, and with the passes shared.
        r["benchmarks"].append(bench("bench_adaptive", "BM_AdaptiveBlocks/shape:0/manual_time", [50 * x for x in NOISE],
                                     label="torus_f40/adaptive/blocks", kind="real",
                                     counters={"seconds_1_thread": [1.4] * 5, "seconds_2_threads": [0.8] * 5,
                                               "speedup_1_to_2": [1.75] * 5, "projected_speedup_8": [3.25] * 5,
                                               "projected_speedup_16": [3.88] * 5,
                                               "projected_speedup_8_passes": [3.82] * 5,
                                               "projected_speedup_16_passes": [4.76] * 5,
                                               "pass_speedup_1_to_2": [1.48] * 5}))
        rows = {row["label"]: row for row in bl.thread_speedups(r)}
        self.assertAlmostEqual(rows["torus_f40/adaptive/blocks"]["q8"], 3.82)
        self.assertAlmostEqual(rows["torus_f40/adaptive/blocks"]["passes"], 1.48)
        self.assertIsNone(rows["bunny_vis800/adaptive/threads"]["q8"])
        page = make_dashboard.inrun_section([r])
        self.assertIn("4.76", page)
        self.assertIn("passes shared", page)

    def test_cluster_projection(self):
        r = run("a" * 40, "2026-01-01T00:00:00+00:00")
        self.assertEqual(bl.cluster_projections(r), [])
        counters = {"projected_seconds": [2000.0] * 5, "projected_one_worker_seconds": [9800.0] * 5,
                    "projected_client_seconds": [1880.0] * 5, "projected_blocks_seconds": [124.0] * 5,
                    "projected_transfer_seconds": [40.0] * 5, "projected_largest_block_seconds": [3.9] * 5,
                    "client_mesh_gb": [36.0] * 5, "piece_bytes_per_triangle": [50.0] * 5}
        r["benchmarks"].append(bench("bench_adaptive", "BM_BlocksClusterProjectionSlow/iterations:2/manual_time",
                                     [3000 * x for x in NOISE], label="torus_f40/adaptive/blocks_on_64_workers_at_1e9",
                                     kind="real", counters=counters))
        rows = bl.cluster_projections(r)
        self.assertEqual(len(rows), 1)
        self.assertAlmostEqual(rows[0]["seconds"], 2000.0)
        self.assertEqual(rows[0]["bound"], "client")
        page = make_dashboard.inrun_section([r])
        self.assertIn("64 workers, projected", page)
        self.assertIn("1880", page)

    def test_peak_memory(self):
        r = run("a" * 40, "2026-01-01T00:00:00+00:00")
        self.assertEqual(bl.peak_memory(r), [])
        counters = {"peak_ratio": [13.5], "triangle_ratio": [9.8], "triangles_small": [1.85e6],
                    "triangles_large": [1.815e7], "peak_mb_small": [334.6], "peak_mb_large": [4510.5],
                    "bytes_per_triangle_small": [180.6], "bytes_per_triangle_large": [248.5]}
        r["benchmarks"].append(bench("bench_adaptive", "BM_PeakMemorySlow/iterations:1/repeats:1/manual_time",
                                     [51795], label="torus/adaptive/polygonize_1e-5_and_1e-6", kind="real",
                                     counters=counters))
        rows = bl.peak_memory(r)
        self.assertEqual(len(rows), 1)
        self.assertAlmostEqual(rows[0]["ratio"], 13.5)
        self.assertAlmostEqual(rows[0]["bytes_large"], 248.5)
        page = make_dashboard.inrun_section([r])
        self.assertIn("Peak memory of the polygonize program", page)
        self.assertIn("<td>4510</td>", page)
        self.assertIn("<td>13.50</td>", page)

    def test_sdf_model_costs(self):
        r = run("a" * 40, "2026-01-01T00:00:00+00:00")
        self.assertEqual(bl.sdf_model_costs(r), [])
        r["benchmarks"].append(bench("bench_adaptive", "BM_AdaptiveSdf/model:1/manual_time", [40 * x for x in NOISE],
                                     label="smooth_union/adaptive/factor3", kind="real",
                                     counters={"creases_cost_ratio": [1.1] * 5, "per_triangle_vs_sphere": [1.4] * 5,
                                               "triangles": [3792] * 5}))
        rows = bl.sdf_model_costs(r)
        self.assertEqual(len(rows), 1)
        self.assertAlmostEqual(rows[0]["creases"], 1.1)
        self.assertAlmostEqual(rows[0]["sphere"], 1.4)
        costs = {e["name"]: e["value"] for e in bl.export(r)[0] if e["unit"] == "ratio"}
        self.assertAlmostEqual(costs["ratio creases follow/ignore bench_adaptive:BM_AdaptiveSdf/model:1/manual_time"], 1.1)
        page = make_dashboard.inrun_section([r])
        self.assertIn("SDF models", page)
        self.assertIn("1.100", page)
        # A model whose run with creases ignored fails reports no ratio: the row stays, without it.
        r["benchmarks"].append(bench("bench_adaptive", "BM_AdaptiveSdf/model:4/manual_time", [40 * x for x in NOISE],
                                     label="menger_level1/adaptive/factor3", kind="real",
                                     counters={"per_triangle_vs_sphere": [0.9] * 5, "triangles": [486] * 5}))
        rows = bl.sdf_model_costs(r)
        self.assertEqual([row["creases"] for row in rows], [1.1, None])
        names = {e["name"] for e in bl.export(r)[0]}
        self.assertNotIn("ratio creases follow/ignore bench_adaptive:BM_AdaptiveSdf/model:4/manual_time", names)
        self.assertIn("ratio per triangle sdf/sphere bench_adaptive:BM_AdaptiveSdf/model:4/manual_time", names)
        self.assertIn("menger_level1", make_dashboard.inrun_section([r]))

    def test_bookkeeping_by_phase(self):
        r = run("a" * 40, "2026-01-01T00:00:00+00:00")
        self.assertEqual(bl.bookkeeping_by_phase(r), [])
        r["benchmarks"].append(bench("bench_adaptive", "BM_AdaptiveBookkeeping/shape:0/manual_time", [40 * x for x in NOISE],
                                     label="torus/adaptive/bookkeeping", kind="real",
                                     counters={"us_per_vertex": [8.25] * 5, "field_us_per_vertex": [0.21] * 5,
                                               "seed_grid_us_per_vertex": [0.05] * 5,
                                               "tracking_us_per_vertex": [3.5] * 5,
                                               "quality_us_per_vertex": [3.75] * 5}))
        rows = bl.bookkeeping_by_phase(r)
        self.assertEqual(len(rows), 1)
        self.assertAlmostEqual(rows[0]["total"], 8.25)
        self.assertAlmostEqual(rows[0]["phases"]["quality"], 3.75)
        self.assertIsNone(rows[0]["phases"]["checks"])  # not reported: shown as missing, not as 0
        page = make_dashboard.inrun_section([r])
        self.assertIn("Time per vertex outside the field, by phase", page)
        self.assertIn("3.75", page)
        self.assertIn("8.25", page)

    def test_missing_benchmarks_give_no_ratio(self):
        r = run("a" * 40, "2026-01-01T00:00:00+00:00")
        r["benchmarks"] = r["benchmarks"][:1]
        self.assertEqual(bl.adaptive_vs_marching(r), [])
        self.assertEqual(bl.batched_vs_scalar(r), [])

    def test_time_to_accuracy(self):
        r = run("a" * 40, "2026-01-01T00:00:00+00:00")
        r["benchmarks"] += tta_benchmarks()
        rows = {(x["family"], x["target"]): x for x in bl.time_to_accuracy(r)}
        self.assertEqual(len(rows), 3)
        self.assertAlmostEqual(rows[("adaptive_factor", "phong")]["seconds"], 0.010)
        self.assertEqual(rows[("adaptive_factor", "phong")]["parameter_name"], "factor")
        self.assertAlmostEqual(rows[("adaptive_factor", "phong")]["error"], 0.45)
        self.assertAlmostEqual(rows[("adaptive_factor", "phong")]["vs_mt"], 0.5)
        self.assertAlmostEqual(rows[("adaptive_factor", "phong")]["overhead"], 6.5)
        self.assertAlmostEqual(rows[("adaptive_factor", "phong")]["budget"], -0.75)
        self.assertIsNone(rows[("mt", "phong")]["budget"])
        self.assertIn("not reached", rows[("mt", "depth")]["missing"])
        self.assertIsNone(rows[("mt", "depth")]["seconds"])
        # Not a polygonizer benchmark of the triangles-per-second ratios.
        self.assertEqual(len(bl.adaptive_vs_marching(r)), 1)


class Recording(unittest.TestCase):
    def test_one_file_per_commit(self):
        with tempfile.TemporaryDirectory() as d:
            latest, hist = os.path.join(d, "latest.json"), os.path.join(d, "history")
            write_json(latest, run("0123456789abcdef" * 2 + "01234567", "2026-03-04T05:06:07+01:00"))
            p1 = record_benchmark.record(latest, hist)
            self.assertEqual(os.path.basename(p1), "20260304T040607Z-0123456.json")
            # Recording the same commit again (a later run) replaces the file.
            r = run("0123456789abcdef" * 2 + "01234567", "2026-03-04T05:06:07+01:00", slow=2.0)
            write_json(latest, r)
            record_benchmark.record(latest, hist)
            self.assertEqual(os.listdir(hist), ["20260304T040607Z-0123456.json"])
            self.assertEqual(bl.load_run(p1)["benchmarks"][0]["samples"]["cpu_time"][0], 20.0)
            write_json(latest, run("f" * 40, "2026-03-05T00:00:00+00:00"))
            record_benchmark.record(latest, hist)
            self.assertEqual(len(os.listdir(hist)), 2)

    def test_bad_file_is_refused(self):
        with tempfile.TemporaryDirectory() as d:
            bad = os.path.join(d, "bad.json")
            write_json(bad, {"benchmarks": []})
            with self.assertRaisesRegex(ValueError, "bad.json: not a benchmark run"):
                record_benchmark.record(bad, os.path.join(d, "h"))
            self.assertFalse(os.path.exists(os.path.join(d, "h")))


class Dashboard(unittest.TestCase):
    def make(self, runs, latest=None, table=None):
        d = self.tmp.name
        hist = os.path.join(d, "history")
        os.makedirs(hist, exist_ok=True)
        for r in runs:
            write_json(os.path.join(hist, bl.record_name(r)), r)
        args = ["--history", hist, "--latest", os.path.join(d, "latest.json"), "--table",
                os.path.join(d, "table1.json"), "--out", os.path.join(d, "dash", "index.html")]
        if latest:
            write_json(os.path.join(d, "latest.json"), latest)
        if table:
            write_json(os.path.join(d, "table1.json"), table)
        make_dashboard.main(args)
        with open(os.path.join(d, "dash", "index.html")) as f:
            page = f.read()
        with open(os.path.join(d, "dash", "benchmark-action.json")) as f:
            smaller = json.load(f)
        with open(os.path.join(d, "dash", "benchmark-action-bigger.json")) as f:
            bigger = json.load(f)
        return page, smaller, bigger

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()

    def tearDown(self):
        self.tmp.cleanup()

    def test_no_runs(self):
        page, smaller, bigger = self.make([])
        self.assertIn("No benchmark runs yet", page)
        self.assertEqual((smaller, bigger), ([], []))

    def test_one_run(self):
        page, smaller, _ = self.make([run("a" * 40, "2026-01-01T00:00:00+00:00")])
        self.assertIn("Needs two runs", page)
        self.assertGreater(page.count("data:image/png;base64,"), 0)
        self.assertEqual(len(smaller), 5)

    def test_slowdown_flagged_and_export_format(self):
        runs = [run("a" * 40, "2026-01-01T00:00:00+00:00"), run("b" * 40, "2026-01-02T00:00:00+00:00")]
        latest = run("c" * 40, "2026-01-03T00:00:00+00:00", slow=2.0)  # not recorded: shown as the newest run
        table = {"environment": {"commit": "d" * 40}, "rows": [
            {"method": "adaptive", "parameter_name": "factor", "parameter": 5, "status": "ok", "triangles": 1000,
             "triangles_per_s": 1e5, "ratio_ls": 1.234, "phong_error": 0.4321}],
            "paper": {"adaptive": [{"precision": 5, "ratio_ls": 1.2, "phong_error": 0.45}]}}
        page, smaller, bigger = self.make(runs, latest, table)
        self.assertIn("1 regression(s), 0 improvement(s), 4 within noise", page)
        flagged = re.findall(r'<tr class="regression"><td>([^<]*)</td>', page)
        self.assertIn("bench_fields:BM_Field/torus/values_batched", flagged)
        self.assertNotIn("bench_fields:BM_Field/torus/values_scalar", flagged)
        self.assertIn("0.4321"[:5], page)  # Table 1 Phong error beside the speed
        self.assertIn("cccccc", page)
        # github-action-benchmark's custom formats: a list of {name, unit, value}.
        for entries in (smaller, bigger):
            self.assertTrue(entries)
            for e in entries:
                self.assertIsInstance(e["name"], str)
                self.assertIsInstance(e["unit"], str)
                self.assertIsInstance(e["value"], (int, float))
        times = {e["name"]: e for e in smaller}
        self.assertAlmostEqual(times["bench_fields:BM_Field/torus/values_batched"]["value"], 20.0)
        self.assertEqual(times["bench_fields:BM_Field/torus/values_batched"]["unit"], "us")
        ratios = {e["name"]: e["value"] for e in bigger if e["unit"] == "ratio"}
        self.assertAlmostEqual(ratios["ratio adaptive/mt triangles_per_second bench_adaptive:BM_Adaptive/torus/factor:3/manual_time"], 2.0)
        self.assertAlmostEqual(ratios["ratio batched/scalar bench_fields:BM_Field/torus/values_batched"], 1.0)
        # Self-contained: nothing but embedded images, and a link to the mesh viewer beside it (loads nothing).
        viewer_link = '<a href="../viewer/index.html">'
        self.assertIn(viewer_link, page)
        self.assertIsNone(re.search(r'(src|href)="(?!data:)', page.replace(viewer_link, "")))

    def test_time_to_accuracy_section_and_unreached_targets(self):
        old = run("a" * 40, "2026-01-01T00:00:00+00:00")
        old["benchmarks"] += tta_benchmarks()
        new = run("b" * 40, "2026-01-02T00:00:00+00:00")
        new["benchmarks"] += tta_benchmarks()
        page, smaller, _ = self.make([old, new])
        self.assertIn("<h2>Time to accuracy</h2>", page)
        self.assertIn("bunny_vis800 time to accuracy", page)
        self.assertIn("missing: depth target not reached", page)
        self.assertIn("<th>Budget (µs/vertex)</th>", page)
        self.assertIn("<td>-0.75</td>", page)
        # A target not reached in both runs is a result, not a regression; the export leaves it out.
        self.assertIn("0 regression(s)", page)
        self.assertNotIn("BM_SlowTimeToAccuracy/bunny_vis800/mt/depth/iterations:1/manual_time",
                         " ".join(e["name"] for e in smaller))
        # Reached before, not now: a regression.
        old2 = run("a" * 40, "2026-01-01T00:00:00+00:00")
        old2["benchmarks"] += tta_benchmarks(depth_reached=True)
        page, _, _ = self.make([old2, new])
        self.assertIn("1 regression(s)", page)

    def test_no_time_to_accuracy(self):
        page, _, _ = self.make([run("a" * 40, "2026-01-01T00:00:00+00:00")])
        self.assertIn("no <code>BM_SlowTimeToAccuracy</code>", page)


if __name__ == "__main__":
    unittest.main(verbosity=1)
