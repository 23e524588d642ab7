#!/usr/bin/python3
"""results/plots/*.png from results/table1/summary.json, with the paper's points beside ours."""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import results_lib as rl  # noqa: E402

STYLE = {"adaptive": ("Ours (factor)", "C0", "o"), "adaptive_paper": ("Ours, paper mode (factor)", "C4", "D"),
         "adaptive_tolerance": ("Ours (tolerance)", "C2", "s"), "adaptive_chord": ("Ours (chord)", "C5", "P"),
         "mt": ("Marching Tetrahedra", "C3", "^"), "mc": ("Marching Cubes", "C1", "v")}
PAPER = {"adaptive": ("Paper: ours", "C0"), "mt": ("Paper: MT", "C3")}


def series(rows, key):
    pts = [(r["triangles"], r[key]) for r in rows if r["status"] == "ok" and r["triangles"] and r[key]]
    return [p[0] for p in pts], [p[1] for p in pts]


def error_plot(rows, paper, key, paper_key, ylabel, path, title):
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for m, rs in rows.items():
        x, y = series(rs, key)
        if x:
            label, color, marker = STYLE.get(m, (m, "k", "x"))
            ax.plot(x, y, marker=marker, color=color, label=label)
    if paper_key:
        for m, rs in paper.items():
            label, color = PAPER[m]
            ax.plot([r["triangles"] for r in rs], [r[paper_key] for r in rs], ls="--", marker="x", color=color,
                    alpha=0.6, label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("triangles")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def histogram_plot(rows, path):
    methods = [m for m in ("adaptive", "mt", "mc") if m in rows]
    fig, axes = plt.subplots(1, len(methods), figsize=(4 * len(methods), 3.4), squeeze=False)
    for ax, m in zip(axes[0], methods):
        for r in rows[m]:
            h = r.get("edge_ratio_histogram")
            if not isinstance(h, dict) or "counts" not in h or "edges" not in h:
                continue
            total = sum(h["counts"]) or 1
            centers = [0.5 * (a + b) for a, b in zip(h["edges"], h["edges"][1:])]
            ax.plot(centers, [c / total for c in h["counts"]], label="{} {:g}".format(r["parameter_name"], r["parameter"]))
        ax.set_title(STYLE[m][0])
        ax.set_xlabel("longest / shortest edge")
        ax.set_ylabel("share of triangles")
        ax.legend(fontsize=7)
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def angle_plot(rows, path, factor=3, precision=3):
    """Cumulative histogram of the triangles' smallest angles: the adaptive default and paper mode at
    `factor`, MT and MC at `precision` (rows of similar triangle counts on the bunny VIS-800)."""
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for m, want in (("adaptive", factor), ("adaptive_paper", factor), ("mt", precision), ("mc", precision)):
        for r in rows.get(m, []):
            c = r.get("angle_cumulative")
            if r["parameter"] != want or r["status"] != "ok" or not isinstance(c, list) or not c or not c[-1]:
                continue
            label, color, _ = STYLE[m]
            ax.step(range(1, len(c) + 1), [v / c[-1] for v in c], where="post", color=color,
                    label="{} {} {:g}".format(label, r["parameter_name"], r["parameter"]))
    ax.set_xlabel("smallest angle of a triangle (degrees)")
    ax.set_ylabel("share of triangles with a smaller one")
    ax.set_yscale("symlog", linthresh=1e-3)
    ax.set_title("Smallest angles, bunny VIS-800 (cumulative)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--results", default=os.path.join(rl.ROOT, "results"))
    ap.add_argument("--paper", default=rl.PAPER_TABLE)
    a = ap.parse_args()
    rows = rl.rows_by_method(rl.load_summary("table1", a.results))
    _, paper = rl.load_paper_table(a.paper)
    out = os.path.join(a.results, "plots")
    os.makedirs(out, exist_ok=True)
    error_plot(rows, paper, "phong_error", "phong_error", "mean Phong error (degrees)",
               os.path.join(out, "phong_error.png"), "Phong error against triangle count")
    error_plot(rows, paper, "depth_error", "depth_error", "mean depth error (model units)",
               os.path.join(out, "depth_error.png"), "Depth error (the paper's units are unknown)")
    error_plot(rows, paper, "time_ms", "time_ms", "time (ms)", os.path.join(out, "time.png"),
               "Polygonization time (paper: P4 1.8 GHz)")
    histogram_plot(rows, os.path.join(out, "edge_ratio_histograms.png"))
    angle_plot(rows, os.path.join(out, "min_angle_cumulative.png"))
    print("plots: wrote", ", ".join(sorted(os.listdir(out))))


if __name__ == "__main__":
    main()
