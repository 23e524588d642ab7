#!/usr/bin/python3
"""results/claims_by_model.md and results/plots/by_model_*.png: the paper's claims judged on every
model of the Table 1 protocol, not on the bunny alone (a claim that holds on one model may be luck).

Models: the bunny VIS-800 (Table 1, results/table1/), the Igea VIS-4004, the horse MPU, tanglecube
and a random blob field (results/NAME/, experiments/NAME.json: factors 1-5, MT and MC at cells that
match the adaptive triangle counts). Each claim gets one verdict per model, as table1.py judges it
(the paper's Table 1 numbers only where the paper measured: the bunny), and an overall verdict:
holds everywhere, holds on some, fails everywhere, within noise everywhere (times whose repeated
runs overlap), fails or within noise everywhere (no model where it holds), or not measurable.
"""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import results_lib as rl  # noqa: E402
import table1  # noqa: E402

MODELS = [("table1", "Bunny VIS-800"), ("igea_vis4004", "Igea VIS-4004"), ("horse_mpu", "Horse MPU"),
          ("tanglecube", "Tanglecube"), ("random_blobs", "Random blobs")]
STYLE = {"adaptive": ("Ours (factor)", "C0", "o"), "mt": ("MT", "C3", "^"), "mc": ("MC", "C1", "v")}


def overall(verdicts):
    """One verdict over models: True/False/'partly'/'noise'/None per model (None: not measurable,
    'noise': the times compared were within the machine's noise)."""
    judged = [v for v in verdicts if v is not None]
    if not judged:
        return "not measurable"
    where = " it was measured" if len(judged) < len(verdicts) else ""
    if all(v is True for v in judged):
        return "holds everywhere" + where
    if all(v is False for v in judged):
        return "fails everywhere" + where
    if all(v == "noise" for v in judged):
        return "within noise everywhere" + where
    if not any(v is True or v == "partly" for v in judged):
        return "fails or within noise everywhere" + where
    return "holds on some"


def judge(results, paper):
    """[(model title, claims list)] for the models whose results exist."""
    out = []
    for name, title in MODELS:
        path = os.path.join(results, name, "summary.json")
        if not os.path.exists(path):
            continue
        rows = rl.rows_by_method(rl.load_summary(name, results))
        if name == "table1":
            cl = table1.claims(rows, paper)
        else:
            cl = table1.claims(rows, None, threshold_rows=paper.get("adaptive", []))
        out.append((title, cl))
    return out


def markdown(judged):
    titles = [t for t, _ in judged]
    # Claims are matched by their text: every model yields the same list, in the same order,
    # except where a claim could not be stated at all (no rows).
    texts = []
    for _, cl in judged:
        for c in cl:
            if c[0] not in texts:
                texts.append(c[0])
    lines = ["# The paper's claims on every model", "",
             "The claims of `results/claims.md` (the bunny, beside the paper's Table 1), judged the same way on "
             "every model of the same protocol: factors 1–5 of the adaptive method, Marching Tetrahedra and Marching "
             "Cubes at cells chosen to match those triangle counts, the same metrics (`experiments/NAME.json`, "
             "`results/NAME/summary.csv`). The paper measured only the bunny, so elsewhere the Phong claim is judged "
             "at our factor 5; \"equilateral\" uses the thresholds the paper's bunny rows allow. A run that failed "
             "counts against \"no cracks\".", "",
             "| # | Claim | " + " | ".join(titles) + " | Overall |",
             "|---|---|" + "---|" * len(titles) + "---|"]
    for i, text in enumerate(texts, 1):
        per = []
        for _, cl in judged:
            found = [c for c in cl if c[0] == text]
            per.append(found[0][2] if found else None)
        lines.append("| {} | {} | {} | **{}** |".format(i, text, " | ".join(table1.verdict(v) for v in per),
                                                       overall(per)))
    for title, cl in judged:
        lines += ["", "## " + title, "", "| Claim | Test | Verdict | Numbers |", "|---|---|---|---|"]
        for text, test, ok, nums in cl:
            lines.append("| {} | {} | **{}** | {} |".format(text, test, table1.verdict(ok), nums))
    return "\n".join(lines) + "\n"


def plots(results, out):
    """Phong error and time against triangle count, and time against Phong error (time to accuracy),
    one panel per model and one line per method."""
    models = [(n, t) for n, t in MODELS if os.path.exists(os.path.join(results, n, "summary.json"))]
    if not models:
        return []
    written = []
    for key, xlabel, ylabel, fname in (
            (("triangles", "phong_error"), "triangles", "mean Phong error (degrees)", "by_model_phong_error.png"),
            (("phong_error", "time_ms"), "mean Phong error (degrees)", "time (ms)", "by_model_time_to_phong.png"),
            (("depth_error_relative", "time_ms"), "mean depth error / box diagonal", "time (ms)",
             "by_model_time_to_depth.png")):
        fig, axes = plt.subplots(1, len(models), figsize=(3.6 * len(models), 3.4), squeeze=False)
        for ax, (name, title) in zip(axes[0], models):
            rows = rl.rows_by_method(rl.load_summary(name, results))
            for m in ("adaptive", "mt", "mc"):
                pts = sorted((r[key[0]], r[key[1]]) for r in rows.get(m, [])
                             if r["status"] == "ok" and r["parameter_name"] not in rl.DISTANCE_SWEEPS
                             and r.get(key[0]) and r.get(key[1]))
                if pts:
                    label, color, marker = STYLE[m]
                    ax.plot([p[0] for p in pts], [p[1] for p in pts], marker=marker, color=color, label=label)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_title(title, fontsize=9)
            ax.set_xlabel(xlabel, fontsize=8)
            ax.grid(True, which="both", alpha=0.3)
        axes[0][0].set_ylabel(ylabel, fontsize=8)
        axes[0][0].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(os.path.join(out, fname), dpi=100)
        plt.close(fig)
        written.append(fname)
    return written


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--results", default=os.path.join(rl.ROOT, "results"))
    ap.add_argument("--paper", default=rl.PAPER_TABLE)
    a = ap.parse_args()
    _, paper = rl.load_paper_table(a.paper)
    judged = judge(a.results, paper)
    with open(os.path.join(a.results, "claims_by_model.md"), "w") as f:
        f.write(markdown(judged))
    out = os.path.join(a.results, "plots")
    os.makedirs(out, exist_ok=True)
    written = plots(a.results, out)
    print("claims_by_model: wrote claims_by_model.md ({} models) and {}".format(len(judged), ", ".join(written)))


if __name__ == "__main__":
    main()
