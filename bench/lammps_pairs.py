#!/usr/bin/python3
"""LAMMPS peer: the time of one neighbour-list build for granular spheres.

The scene file becomes a LAMMPS data file (atom_style sphere, every diameter d, the box the
scene's bounds plus d, fixed boundaries; in 2D `dimension 2` with z = 0 and a periodic z).
The input uses what the field runs for granular contacts:

    pair_style gran/hooke ...         (a half, size-based neighbour list, newton on)
    neighbor 0.0 bin                   (no skin: the list holds exactly the contacts)
    neigh_modify every 1 delay 0 check no

then `run 0` (setup: one untimed build, and, unless --no-sort, LAMMPS's spatial sort of
the atoms, which it does by default every 1000 steps and at setup), then R times
`run 1 pre no post yes`: each is one step with one neighbour-list build, and LAMMPS prints
its timing breakdown. What is timed is the `Neigh` row of one step: binning the atoms and
building the list (LAMMPS's own timer). The minimum over the R steps is reported. No fix
integrates, so atoms never move and every build sees the same scene.

The pair count is LAMMPS's `Total # of neighbors` (the half list: each pair once).
peak_bytes is LAMMPS's own `Per MPI rank memory allocation` (max); rss_peak_bytes the
process's peak resident memory. Prints one key=value line (bench/README.md).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np


def lammps_binary():
    for name in ("lmp", "lmp_serial", "lmp_mpi", "lammps"):
        path = shutil.which(name)
        if path:
            return path
    return None


def write_data(path, pts, dim, d):
    n = len(pts)
    lo = pts.min(axis=0) - d if n else np.zeros(dim)
    hi = pts.max(axis=0) + d if n else np.ones(dim)
    with open(path, "w") as f:
        f.write(f"nbs scene, {n} elements, diameter {d!r}\n\n{n} atoms\n1 atom types\n\n")
        for a, ax in enumerate("xy" if dim == 2 else "xyz"):
            f.write(f"{lo[a]!r} {hi[a]!r} {ax}lo {ax}hi\n")
        if dim == 2:
            f.write("-0.5 0.5 zlo zhi\n")
        f.write("\nAtoms # sphere\n\n")
        # id type diameter density x y z, coordinates with 17 digits: read back exactly.
        chunk = 1 << 20
        for s in range(0, n, chunk):
            p = pts[s:s + chunk]
            m = len(p)
            cols = [np.arange(s + 1, s + m + 1), np.ones(m), np.full(m, d), np.ones(m), p[:, 0],
                    p[:, 1], p[:, 2] if dim == 3 else np.zeros(m)]
            np.savetxt(f, np.column_stack(cols),
                       fmt=["%d", "%d", "%.17g", "%d", "%.17g", "%.17g", "%.17g"])


def script(data, dim, repeats, sort):
    lines = [
        "units lj",
        f"dimension {dim}",
        "atom_style sphere",
        "" if sort else "atom_modify sort 0 0.0",
        "boundary f f f" if dim == 3 else "boundary f f p",
        "newton on",
        "comm_modify vel yes",
        f"read_data {data}",
        "pair_style gran/hooke 1.0 0.0 0.0 0.0 0.0 0",
        "pair_coeff * *",
        "neighbor 0.0 bin",
        "neigh_modify every 1 delay 0 check no",
        "thermo 1000000",
        "run 0",
    ] + ["run 1 pre no post yes"] * repeats
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--file", required=True)
    ap.add_argument("--dim", type=int, default=3, choices=(2, 3))
    ap.add_argument("--diameter", type=float, default=1.0)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--no-sort", action="store_true",
                    help="atom_modify sort 0 0.0: keep the file's element order")
    ap.add_argument("--data", help="data file to write (or reuse if newer than --file)")
    ap.add_argument("--keep", action="store_true", help="keep the work directory")
    a = ap.parse_args()
    tool = "lammps-nosort" if a.no_sort else "lammps"
    lmp = lammps_binary()
    if not lmp:
        print(f"tool={tool} status=missing", flush=True)
        print("lammps_pairs: no LAMMPS binary (apt-get install lammps)", file=sys.stderr)
        return 2
    pts = np.fromfile(a.file, dtype="<f8").reshape(-1, a.dim)
    n = len(pts)
    work = tempfile.mkdtemp(prefix="nbs-lammps-")
    try:
        data = a.data or os.path.join(work, "scene.data")
        if not (a.data and os.path.exists(data)
                and os.path.getmtime(data) >= os.path.getmtime(a.file)):
            write_data(data, pts, a.dim, a.diameter)
        del pts
        inp = os.path.join(work, "in.bench")
        with open(inp, "w") as f:
            f.write(script(data, a.dim, max(1, a.repeats), not a.no_sort))
        log = os.path.join(work, "log.lammps")
        env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1",
                   OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
        p = subprocess.Popen([lmp, "-in", inp, "-log", log, "-screen", "none"], cwd=work,
                             env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        _, status, usage = os.wait4(p.pid, 0)
        p.returncode = os.waitstatus_to_exitcode(status)
        err = p.stderr.read().decode(errors="replace")
        text = open(log).read() if os.path.exists(log) else ""
        if p.returncode != 0 or "Total wall time" not in text:
            tail = "\n".join((text + err).splitlines()[-15:])
            print(f"tool={tool} status=failed n={n} dim={a.dim}", flush=True)
            print(f"lammps_pairs: LAMMPS failed (exit {p.returncode}):\n{tail}", file=sys.stderr)
            return 1
        # Each `run 1` prints one breakdown; the first `Neigh` row is run 0's (no build).
        neigh = [float(m) for m in re.findall(r"^Neigh\s*\|\s*\S+\s*\|\s*(\S+)", text, re.M)]
        builds = [int(m) for m in re.findall(r"^Neighbor list builds = (\d+)", text, re.M)]
        pairs = [int(m) for m in re.findall(r"^Total # of neighbors = (\d+)", text, re.M)]
        mem = re.findall(r"memory allocation \(min/avg/max\) = \S+ \| \S+ \| (\S+) Mbytes", text)
        version = re.search(r"^LAMMPS \((.*)\)", text, re.M)
        steps = neigh[1:]
        if len(steps) != a.repeats or builds[-1] - builds[0] != a.repeats:
            print(f"tool={tool} status=failed n={n} dim={a.dim}", flush=True)
            print(f"lammps_pairs: expected {a.repeats} builds, log shows {builds}",
                  file=sys.stderr)
            return 1
        if len(set(pairs)) != 1:
            print(f"lammps_pairs: the pair count changed between steps: {pairs}",
                  file=sys.stderr)
        best = min(steps)
        peak = int(float(mem[-1]) * 1024 * 1024) if mem else 0
        ver = version.group(1).replace(" ", "_") if version else "unknown"
        print(f"tool={tool} status=ok seconds={best:.9g} "
              f"ns_per_element={1e9 * best / max(n, 1):.6g} pairs={pairs[-1]} "
              f"peak_bytes={peak} rss_peak_bytes={usage.ru_maxrss * 1024} "
              f"repeats={a.repeats} n={n} dim={a.dim} version={ver}", flush=True)
        return 0
    finally:
        if not a.keep:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
