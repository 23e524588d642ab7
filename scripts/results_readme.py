#!/usr/bin/python3
"""results/README.md: the table, the claims and the figures on one page."""
import argparse
import glob
import json
import os

import results_lib as rl


VIEWER = ("The meshes themselves, to turn, zoom and compare (ours beside Marching Tetrahedra and Marching Cubes at "
          "matched triangle counts, with each run's figures): [viewer/index.html](viewer/index.html), opened in a "
          "browser straight from the disk (see viewer/README.md in the repository). Its meshes and script are not "
          "committed: `make reproduce` or `make viewer` writes them.")


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--results", default=os.path.join(rl.ROOT, "results"))
    ap.add_argument("--seconds", type=float, default=None, help="how long make reproduce took")
    a = ap.parse_args()
    r = a.results
    parts = ["# Results", "",
             "Everything in this folder is produced by `make reproduce` (see the top-level README); "
             "the committed files are those of the last run." +
             (" That run took {:.1f} minutes including the experiments.".format(a.seconds / 60) if a.seconds else ""),
             ""]
    if os.path.exists(os.path.join(r, "viewer", "index.html")):
        parts += [VIEWER, ""]
    for name in ("table1.md", "claims.md", "claims_by_model.md"):
        p = os.path.join(r, name)
        if os.path.exists(p):
            with open(p) as f:
                text = f.read()
            parts += [text.replace("\n# ", "\n## ").replace("# ", "## ", 1), ""]
    sharp = os.path.join(r, "sharp_features.md")
    if os.path.exists(sharp):
        with open(sharp) as f:
            text = f.read()
        parts += [text.replace("\n## ", "\n### ").replace("# ", "## ", 1), "",
                  "![sharp features](sharp_features.png)", ""]
    for name in ("topology_sweep.md", "sdf_sweep.md"):
        p = os.path.join(r, name)
        if os.path.exists(p):
            with open(p) as f:
                text = f.read()
            parts += [text.replace("# ", "## ", 1), ""]
    plots = sorted(glob.glob(os.path.join(r, "plots", "*.png")))
    if plots:
        parts += ["## Plots", ""] + ["![{0}](plots/{0})".format(os.path.basename(p)) for p in plots] + [""]
    captions = os.path.join(r, "figures", "captions.json")
    if os.path.exists(captions):
        with open(captions) as f:
            caps = json.load(f)
        parts += ["## Figures", ""]
        for fig in caps:
            # A figure that could not be made has no file; its caption says why.
            image = ["![{}](figures/{})".format(fig["title"], fig["file"]), ""] if fig.get("file") else []
            parts += ["### " + fig["title"], ""] + image + [fig["caption"], ""]
    others = sorted(d for d in os.listdir(r) if os.path.exists(os.path.join(r, d, "summary.csv")))
    if others:
        parts += ["## Experiments", "", "Per-run metrics: `results/<experiment>/runs/<run>/metrics.json`; "
                  "summaries: " + ", ".join("[{0}]({0}/summary.csv)".format(d) for d in others) + ".", ""]
    with open(os.path.join(r, "README.md"), "w") as f:
        f.write("\n".join(parts))
    print("results_readme: wrote", os.path.join(r, "README.md"))


if __name__ == "__main__":
    main()
