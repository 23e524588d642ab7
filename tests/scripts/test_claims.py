#!/usr/bin/python3
"""Unit tests of the claim logic of scripts/table1.py on synthetic tables, including the
borderline cases the claims were once judged wrongly on (ctest scripts.claims)."""
import os
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "scripts"))
import results_lib as rl  # noqa: E402
import table1  # noqa: E402
import claims_by_model  # noqa: E402

_, PAPER = rl.load_paper_table()


def row(method, k, **kw):
    r = {"id": "{}_{}".format(method, k), "method": method, "parameter_name": "factor" if method == "adaptive" else
         "precision", "parameter": k, "status": "ok", "triangles": 1000 * k, "vertices": 500 * k + 2, "seconds": 1.0,
         "ratio_ls": 1.3, "deviation": 0.2, "phong_error": 1.0 / k, "depth_error": 0.001 / k,
         "triangles_per_s": 1000.0, "curvature_seconds": 0.2, "hessian_seconds": 0.19, "hessian_evaluations": 500 * k,
         "closed": True, "manifold": True, "components": 1, "genus": 0, "self_intersections": 0,
         "shares_at_most": {"1.1": 0.1, "1.2": 0.3, "1.25": 0.45, "1.3": 0.6}}
    r.update(kw)
    return r


def verdicts(rows):
    return {text: ok for text, _, ok, _ in table1.claims(rows, PAPER)}


def find(v, start):
    return next(ok for text, ok in v.items() if text.startswith(start))


class Claims(unittest.TestCase):
    def test_paper_rows_rule_out_the_threshold_1_1(self):
        # The paper's factor-5 row (mean 1.267, st.dev. 0.164) cannot have half its triangles
        # at L/s <= 1.1: that would need a deviation of at least 0.167.
        consistent, need = table1.consistent_thresholds(PAPER["adaptive"])
        self.assertAlmostEqual(need, 1.267 - 0.164, places=9)
        self.assertEqual(consistent, [1.2, 1.25, 1.3])

    def test_half_equilateral_is_judged_at_the_consistent_thresholds_only(self):
        ours = [row("adaptive", k) for k in range(1, 6)]
        self.assertEqual(find(verdicts({"adaptive": ours}), "Approximately 50 percent"), "partly")
        ours = [row("adaptive", k, shares_at_most={"1.1": 0.5, "1.2": 0.5, "1.25": 0.5, "1.3": 0.5}) for k in range(1, 6)]
        self.assertIs(find(verdicts({"adaptive": ours}), "Approximately 50 percent"), True)
        # 50% at 1.1 alone does not count: 1.1 is inconsistent with the paper's own numbers.
        ours = [row("adaptive", k, shares_at_most={"1.1": 0.5, "1.2": 0.7, "1.25": 0.8, "1.3": 0.9}) for k in range(1, 6)]
        self.assertIs(find(verdicts({"adaptive": ours}), "Approximately 50 percent"), False)

    def test_phong_under_half_a_degree_is_judged_at_the_papers_triangle_count(self):
        # Our factor 5 is under 0.5 only because it has more triangles than the paper's 29,696.
        ours = [row("adaptive", 4, triangles=22300, phong_error=0.686), row("adaptive", 5, triangles=33536, phong_error=0.468)]
        self.assertIs(find(verdicts({"adaptive": ours}), "We achieve an average Phong"), False)
        ours = [row("adaptive", 4, triangles=22300, phong_error=0.6), row("adaptive", 5, triangles=29696, phong_error=0.45)]
        self.assertIs(find(verdicts({"adaptive": ours}), "We achieve an average Phong"), True)

    def test_curvature_cost_is_the_eigen_decomposition_not_the_hessian(self):
        # 19% of the time in Hessian evaluations, 1% in the eigen-decomposition: the claim holds.
        ours = [row("adaptive", k) for k in range(1, 6)]
        self.assertIs(find(verdicts({"adaptive": ours}), "Computing the eigenvalues"), True)
        ours = [row("adaptive", k, curvature_seconds=0.3, hessian_seconds=0.2) for k in range(1, 6)]
        self.assertIs(find(verdicts({"adaptive": ours}), "Computing the eigenvalues"), False)

    def test_no_cracks_needs_no_self_intersections(self):
        ours = [row("adaptive", k) for k in range(1, 6)]
        self.assertIs(find(verdicts({"adaptive": ours}), "No cracks"), True)
        ours[2]["self_intersections"] = 3
        self.assertIs(find(verdicts({"adaptive": ours}), "No cracks"), False)

    def test_twice_as_many_triangles_is_reported_for_mt_too(self):
        ours = [row("adaptive", k) for k in range(1, 6)]
        mt = [row("mt", p, triangles=996, vertices=500) for p in (1, 2)]
        text, test, ok, numbers = [c for c in table1.claims({"adaptive": ours, "mt": mt}, PAPER)
                                   if c[0].startswith("Good meshes")][0]
        self.assertIn("topology", test)
        self.assertIn("MT: [1.992, 1.992]", numbers)

    def test_a_failed_run_counts_against_no_cracks(self):
        ours = [row("adaptive", k) for k in range(1, 6)]
        ours[0] = row("adaptive", 1, status="failed", reason="a front cannot advance")
        self.assertIs(find(verdicts({"adaptive": ours}), "No cracks"), False)

    def test_other_models_judge_phong_at_our_factor_5_and_equilateral_at_the_papers_thresholds(self):
        ours = [row("adaptive", k) for k in range(1, 5)] + [row("adaptive", 5, triangles=90000, phong_error=0.4)]
        cl = {t: ok for t, _, ok, _ in table1.claims({"adaptive": ours}, None, threshold_rows=PAPER["adaptive"])}
        self.assertIs(find(cl, "We achieve an average Phong"), True)
        # 50% at 1.1 alone still does not count on another model.
        ours = [row("adaptive", k, shares_at_most={"1.1": 0.5, "1.2": 0.7, "1.25": 0.8, "1.3": 0.9}) for k in range(1, 6)]
        cl = {t: ok for t, _, ok, _ in table1.claims({"adaptive": ours}, None, threshold_rows=PAPER["adaptive"])}
        self.assertIs(find(cl, "Approximately 50 percent"), False)

    def test_time_to_accuracy_interpolates_mt_at_our_factor_3_errors(self):
        # Ours at factor 3: Phong 1.0 deg and relative depth 1e-3 in 250 ms. MT reaches them
        # between its runs at 300 ms: ours is faster to that accuracy, whatever the triangle rates.
        ours = [row("adaptive", k, time_ms=250.0 * k / 3, depth_error_relative=1e-3 * 3 / k, phong_error=3.0 / k)
                for k in range(1, 6)]
        mt = [row("mt", p, time_ms=t, phong_error=e, depth_error_relative=d)
              for p, t, e, d in ((1, 200.0, 2.0, 2e-3), (3, 450.0, 0.5, 5e-4))]
        v = verdicts({"adaptive": ours, "mt": mt})
        self.assertIs(find(v, "For the same accuracy"), True)
        mt = [row("mt", p, time_ms=t, phong_error=e, depth_error_relative=d)
              for p, t, e, d in ((1, 100.0, 2.0, 2e-3), (3, 200.0, 0.5, 5e-4))]
        self.assertIs(find(verdicts({"adaptive": ours, "mt": mt}), "For the same accuracy"), False)
        # Out of MT's range: not measurable rather than a verdict.
        mt = [row("mt", p, time_ms=t, phong_error=e, depth_error_relative=d)
              for p, t, e, d in ((1, 100.0, 0.5, 5e-4), (3, 200.0, 0.3, 3e-4))]
        self.assertIsNone(find(verdicts({"adaptive": ours, "mt": mt}), "For the same accuracy"))

    def test_paper_mode_rows_are_judged_by_the_same_tests(self):
        ours = [row("adaptive", k) for k in range(1, 6)]
        paper_mode = [row("adaptive", k, variant="paper", self_intersections=2) for k in range(1, 6)]
        rows = {"adaptive": ours, "adaptive_paper": paper_mode}
        self.assertIs(paper_mode[0], table1.paper_mode_rows(rows)["adaptive"][0])
        md = table1.claims_markdown(table1.claims(rows, PAPER), table1.claims(table1.paper_mode_rows(rows), PAPER))
        line = next(l for l in md.split("\n") if "No cracks" in l and l.startswith("| 1") is False and "|" in l)
        self.assertIn("| **holds** | does not hold |", line)

    def test_overall_verdict_over_models(self):
        self.assertEqual(claims_by_model.overall([True, True, True]), "holds everywhere")
        self.assertEqual(claims_by_model.overall([True, None, True]), "holds everywhere it was measured")
        self.assertEqual(claims_by_model.overall([True, False]), "holds on some")
        self.assertEqual(claims_by_model.overall(["partly", "partly"]), "holds on some")
        self.assertEqual(claims_by_model.overall([False, False]), "fails everywhere")
        self.assertEqual(claims_by_model.overall([None, None]), "not measurable")
        self.assertEqual(claims_by_model.overall(["noise", "noise"]), "within noise everywhere")
        self.assertEqual(claims_by_model.overall([False, "noise"]), "fails or within noise everywhere")
        self.assertEqual(claims_by_model.overall([True, "noise"]), "holds on some")

    def test_time_to_accuracy_decides_only_where_the_repeated_runs_do_not_overlap(self):
        # The Igea's committed rows once had ours 556 ms against MT's 558 ms at the same depth
        # error: one run each, and the next regeneration said the opposite. With repeated runs
        # a verdict needs the ranges apart; overlapping ranges are within noise.
        def rows(ours_range, mt_ranges, mt_depth=(2e-3, 5e-4)):
            ours = [row("adaptive", k, time_ms=250.0 * k / 3, depth_error_relative=1e-3 * 3 / k, phong_error=3.0 / k)
                    for k in range(1, 6)]
            ours[2]["time_ms"] = sum(ours_range) / 2
            ours[2]["time_ms_range"] = ours_range
            mt = [row("mt", p, time_ms=sum(rg) / 2, phong_error=e, depth_error_relative=d, time_ms_range=rg)
                  for (p, e, d), rg in zip(((1, 2.0, mt_depth[0]), (3, 0.5, mt_depth[1])), mt_ranges)]
            return {"adaptive": ours, "mt": mt}

        # Ours at factor 3: Phong 1.0° and relative depth 1e-3. Both lie midway (log-log) between
        # MT's two runs, so MT's range there is sqrt(190 * 290) ≈ 235 to sqrt(210 * 310) ≈ 255 ms.
        mt_ranges = [(190.0, 210.0), (290.0, 310.0)]
        self.assertEqual(find(verdicts(rows((240.0, 260.0), mt_ranges)), "For the same accuracy"), "noise")
        self.assertIs(find(verdicts(rows((200.0, 230.0), mt_ranges)), "For the same accuracy"), True)
        self.assertIs(find(verdicts(rows((260.0, 280.0), mt_ranges)), "For the same accuracy"), False)
        # The two targets disagreeing: with MT's depth errors 1.25e-3 and 1e-4, our depth target
        # (1e-3) lies near its coarse run (log-log), where MT's range is about 197-217 ms, while
        # at the Phong target it stays 235-255 ms.
        deeper = (1.25e-3, 1e-4)
        # Ours 210-230: faster at the Phong target, within noise at the depth one.
        self.assertEqual(find(verdicts(rows((210.0, 230.0), mt_ranges, deeper)), "For the same accuracy"), "noise")
        # Ours 220-230: slower at the depth target, though faster at the Phong one.
        self.assertIs(find(verdicts(rows((220.0, 230.0), mt_ranges, deeper)), "For the same accuracy"), False)
        # Ours 160-170: faster at both.
        self.assertIs(find(verdicts(rows((160.0, 170.0), mt_ranges, deeper)), "For the same accuracy"), True)
        # Single runs (no ranges): a tie, which used to count as holding, is now within noise.
        self.assertEqual(table1.faster(250.0, 250.0, 250.0, 250.0), "noise")
        self.assertIs(table1.faster(249.0, 249.0, 250.0, 250.0), True)
        text = [c for c in table1.claims(rows((240.0, 260.0), mt_ranges), PAPER)
                if c[0].startswith("For the same accuracy")][0][3]
        self.assertIn("within noise", text)
        self.assertIn("middle half of the runs: ours 240–260", text)
        self.assertEqual(table1.verdict("noise"), "within noise")

    def test_a_repeated_runs_range_is_the_middle_half_of_its_times(self):
        # The 2nd and 4th of 5 times: a single slow run (the machine busy) does not widen it.
        self.assertEqual(rl.time_range_ms({"repeat_seconds": [0.5, 0.1, 0.3, 0.2, 0.4]}), (200.0, 400.0))
        self.assertEqual(rl.time_range_ms({"repeat_seconds": [0.3, 0.1, 0.2]}), (100.0, 300.0))
        self.assertIsNone(rl.time_range_ms({"repeat_seconds": [0.1]}))
        self.assertIsNone(rl.time_range_ms({}))
        self.assertIsNone(rl.time_range_ms({"repeat_seconds": [0.1, None, 0.2]}))

    def test_distance_sweeps_are_rows_of_their_own_with_no_paper_row(self):
        # An experiment's "tolerance" and "chord" runs are tabled and drawn apart from the factor's,
        # and never beside a paper row of the same number.
        def run(name, value):
            return {"id": "adaptive_{}{}".format(name, value), "method": "adaptive", "parameter_name": name,
                    "parameter": value, "status": "ok", "stats": {"triangles": 100, "seconds": 0.1}, "metrics": {}}
        summary = {"runs": [run("factor", 3), run("tolerance", 3), run("chord", 3), run("chord", 1)]}
        by = rl.rows_by_method(summary)
        self.assertEqual(sorted(by), ["adaptive", "adaptive_chord", "adaptive_tolerance"])
        self.assertEqual([r["parameter"] for r in by["adaptive_chord"]], [1, 3])
        text = table1.markdown(by, PAPER, {}, summary)
        sections = {}
        for part in text.split("\n## ")[1:]:
            head, _, body = part.partition("\n")
            sections[head] = [line for line in body.splitlines() if line.startswith("| 3 ")]
        # The factor's run at 3 has the paper's (in parentheses); neither distance sweep at 3 does.
        self.assertIn("(", sections[table1.LABELS["adaptive"]][0])
        for m in ("adaptive_tolerance", "adaptive_chord"):
            self.assertEqual(len(sections[table1.LABELS[m]]), 1, m)
            self.assertNotIn("(", sections[table1.LABELS[m]][0], m)

if __name__ == "__main__":
    unittest.main()
