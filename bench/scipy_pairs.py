#!/usr/bin/python3
"""scipy peer: cKDTree(points).query_pairs(d, output_type='ndarray') on a scene file.

Timed: building the tree and the query (scipy's defaults: leafsize 16, balanced tree),
minimum over the repeats. query_pairs keeps pairs at distance <= d, the same contract as
nbs. Prints one key=value line (bench/README.md); rss_extra_bytes is the peak resident
memory above the resident memory once the coordinates were read.
"""
import argparse
import sys
import time

import numpy as np
import scipy
from scipy.spatial import cKDTree


def status_bytes(field):
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def reset_peak():
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--file", required=True)
    ap.add_argument("--dim", type=int, default=3, choices=(2, 3))
    ap.add_argument("--diameter", type=float, default=1.0)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    pts = np.fromfile(a.file, dtype="<f8").reshape(-1, a.dim)
    n = len(pts)
    base = status_bytes("VmRSS:")
    reset_peak()
    best, pairs = None, 0
    for _ in range(max(1, a.repeats)):
        t0 = time.perf_counter()
        p = cKDTree(pts).query_pairs(a.diameter, output_type="ndarray")
        t = time.perf_counter() - t0
        pairs = len(p)
        del p
        best = t if best is None else min(best, t)
    hwm = status_bytes("VmHWM:")
    print(f"tool=scipy status=ok seconds={best:.9g} ns_per_element={1e9 * best / max(n, 1):.6g} "
          f"pairs={pairs} rss_extra_bytes={hwm - base} rss_peak_bytes={hwm} "
          f"repeats={max(1, a.repeats)} n={n} dim={a.dim} version={scipy.__version__}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
