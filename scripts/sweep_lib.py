"""What the two sweeps of make reproduce share (topology_sweep.py, sdf_sweep.py): one run of the
polygonize program with its statistics, and a closed mesh's topology from its counts."""
import json
import subprocess


def topology(stats):
    """Components and total genus of a closed manifold mesh from its counts (E = 3F/2)."""
    c, v, f = stats["components"], stats["vertices"], stats["triangles"]
    return c, c - (v - f // 2) // 2


def polygonize(exe, field, args, out_ply, out_stats, timeout):
    """polygonize FIELD ARGS on one thread: (the stats, "") or (None, the last line of its error,
    or that it was stopped after `timeout` seconds)."""
    cmd = [exe, "--quiet", "--threads", "1"] + args + [field, "-o", out_ply, "--stats", out_stats]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, "stopped after {} s".format(timeout)
    if r.returncode != 0:
        lines = r.stderr.strip().splitlines()
        return None, lines[-1] if lines else "exit {}".format(r.returncode)
    with open(out_stats) as f:
        return json.load(f), ""
