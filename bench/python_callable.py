#!/usr/bin/python3
"""BM_PythonCallable: the torus of python/README.md's example as a numpy function (a black box:
cdp.callable_field(..., trace=False), derivatives by central differences) meshed by the adaptive
polygonizer at factor 8, tracked alone and with blocks (meshed in lockstep, their evaluations
gathered into one call: polygonizer/src/adaptive/lockstep.h), against the same formula as an
expression field (issue 58: at most 0.5 Python calls per vertex, and within 2x of the
expression's time). Every run on one thread (threads=1), the callable's on one core anyway.
Installed as build/bin/bench_python_callable and run by scripts/run_benchmarks.py like the C++
programs (bench/_gbench.py). Counters: vertices, triangles, calls_per_vertex (calls of the
function), time_vs_expression (the same repetition's expression run, the same mode), and for the
blocks' run lockstep_tasks.
"""
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "python"))  # build/python beside build/bin

import numpy as np  # noqa: E402

import _gbench  # noqa: E402  (bench/_gbench.py, beside this file in build/bin)

NAME = "BM_PythonCallable/torus_factor8"
BOX = ((-1.5, -1.5, -0.5), (1.5, 1.5, 0.5))
FORMULA = "(sqrt(x^2 + y^2) - 1)^2 + z^2 - 0.09"
FACTOR = 8
NAMES = [NAME + "/" + n for n in ("expression", "expression_blocks", "callable", "callable_blocks")]


def one_repetition():
    import cdp
    calls = [0]

    def torus(p):
        calls[0] += 1
        return (np.sqrt(p[:, 0] ** 2 + p[:, 1] ** 2) - 1) ** 2 + p[:, 2] ** 2 - 0.09

    fields = {"expression": cdp.expression(FORMULA, bounds=BOX), "callable": cdp.callable_field(torus, BOX, trace=False)}
    out = {}
    for kind, field in fields.items():
        for blocks in (False, True):
            calls[0] = 0
            start = time.perf_counter()
            V, F, _, stats = cdp.polygonize(field, factor=FACTOR, blocks=blocks, threads=1)
            seconds = time.perf_counter() - start
            r = {"real_time": seconds * 1e3, "vertices": float(len(V)), "triangles": float(len(F))}
            if kind == "callable":
                r["calls_per_vertex"] = calls[0] / len(V)
                if blocks:
                    r["lockstep_tasks"] = float(stats["blocks"]["lockstep_tasks"])
            out[NAME + "/" + kind + ("_blocks" if blocks else "")] = r
    for mode in ("", "_blocks"):
        out[NAME + "/callable" + mode]["time_vs_expression"] = (
            out[NAME + "/callable" + mode]["real_time"] / out[NAME + "/expression" + mode]["real_time"])
    return out


if __name__ == "__main__":
    sys.exit(_gbench.main(__doc__, NAMES, one_repetition))
