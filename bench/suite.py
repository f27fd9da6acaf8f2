#!/usr/bin/python3
"""The nbs benchmark suite (run it through bench/run; see bench/README.md).

For each case (scene, dimension, element order, N) the scene is generated once by nbs_bench
with the shared scene generators and written to a raw f64 file; every nbs algorithm is
timed on it in that process, then every peer driver on the same file, one after another in
the same run. Each tool reports the number of contact pairs; all must agree.

Every nbs row is a detection from scratch (nbs_bench --fresh): the same elements detected
again are not a time step, and cellsort would find them already in order. Time steps are
rows of their own, nbs-ALG-steps (--steps; --step-scenes, uniform and huge): every element
moves by up to D diameters per axis before each detection (not timed), the context kept
from step to step, as in a simulation, for at least --step-repeats steps; they agree when
the last step's pairs are the bytes of a detection from scratch of the same coordinates
(same_as_fresh), since moved elements have other contacts.

Results: <out>/results.csv (one row per case and tool), <out>/summary.md (headline table
and targets, computed from the rows), <out>/machine.txt and PNG plots.
"""
import argparse
import csv
import datetime
import math
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
PY = "/usr/bin/python3" if os.path.exists("/usr/bin/python3") else sys.executable

PEERS = ["nanoflann", "cgal", "scipy", "lammps", "lammps-nosort"]
ALL_TOOLS = ["nbs"] + PEERS
COLUMNS = ["scene", "dim", "order", "N", "fraction", "spacing", "tool", "status", "seconds",
           "ns_per_element", "peak_bytes", "rss_extra_bytes", "work_bytes", "pair_bytes",
           "pairs", "agree", "ran", "repeats", "threads", "hash", "nbs_build", "core_ratio",
           "note"]
KEY = ("scene", "dim", "order", "N", "spacing", "tool")


def log(msg):
    print(msg, flush=True)


def parse_line(line):
    """key=value fields of one driver line, or None."""
    if not line.startswith("tool="):
        return None
    return dict(f.split("=", 1) for f in line.split() if "=" in f)


def sphere_volume(dim, d=1.0):
    return math.pi / 6 * d ** 3 if dim == 3 else math.pi / 4 * d ** 2


def fraction_for_spacing(dim, s):
    """Fraction of a uniform scene whose mean centre spacing is s diameters."""
    return sphere_volume(dim) / s ** dim


def fmt_n(n):
    e = int(round(math.log10(n))) if n > 0 else 0
    return f"1e{e}" if n == 10 ** e else str(n)


class Suite:
    def __init__(self, a):
        self.a = a
        self.rows = []
        self.failures = []
        self.bin = a.build + "/bench"
        self.build_id = nbs_build_id(a.build)

    # ---- running tools -------------------------------------------------------------------
    def run_cmd(self, cmd, tool_hint, timeout):
        t0 = time.time()
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return [{"tool": tool_hint, "status": "timeout"}], f"timeout after {timeout} s"
        except OSError as e:
            return [{"tool": tool_hint, "status": "missing"}], str(e)
        lines = [x for x in (parse_line(l) for l in p.stdout.splitlines()) if x]
        err = p.stderr.strip()
        if not lines:
            lines = [{"tool": tool_hint, "status": "failed"}]
        if self.a.verbose:
            log(f"    {' '.join(cmd)}  ({time.time() - t0:.1f} s)")
        return lines, err

    def case(self, scene, dim, order, n, fraction, spacing="", tools=None):
        a = self.a
        tools = tools if tools is not None else a.tools
        tag = f"{scene} {dim}D {order} N={fmt_n(n)}" + (f" S/D={spacing}" if spacing else "")
        log(f"== {tag}")
        path = os.path.join(a.workdir, f"{scene}-{dim}d-{order}-{n}-{spacing or 'x'}.f64")
        gen_scene = "uniform" if scene == "density" else scene
        timing = ["--repeats", str(a.repeats), "--min-time", str(a.min_time), "--direct-max",
                  str(a.direct_max), "--fresh"]
        cmd = [f"{self.bin}/nbs_bench", "--scene", gen_scene, "--dim", str(dim), "--n", str(n),
               "--fraction", repr(fraction), "--seed", str(a.seed), "--write", path] + timing
        algs = []
        if "nbs" not in tools:
            algs = ["--algorithms", "none"]
        elif a.algorithms != ["all"]:
            algs = ["--algorithms", ",".join(x for x in a.algorithms
                                             if x != "direct" or n <= a.direct_max)]
        cmd += algs
        if order == "sorted":
            cmd.append("--sorted")
        results, err = self.run_cmd(cmd, "nbs", a.timeout)
        if not os.path.exists(path):
            self.fail(tag, "nbs_bench", f"no scene written: {err}")
            return
        if err and a.verbose:
            log(f"    {err}")
        # The same algorithms with more threads, on the same file: time and identical output.
        # The speed-up is measured side by side: one thread (rows nbs-ALG-1t) and each
        # thread count alternate in processes of their own, --thread-rounds times, and each
        # row keeps its fastest round, so that a disturbance of one process (on a shared
        # machine, the second core taken for a while) does not decide the ratio. The time
        # steps (--step-scenes) alternate with them the same way.
        have = {r["tool"][4:] for r in results if r.get("status") == "ok"}
        talgs = [x for x in a.thread_algorithms if x in have]
        salgs = [x for x in a.step_algorithms if x in have]
        # one-thread twins of other algorithms (--twin-algorithms), alternating with the rest
        walgs = [x for x in a.twin_algorithms if x in have and x not in talgs]
        if not ("nbs" in tools and a.steps > 0 and scene in a.step_scenes):
            salgs = []
        if not ("nbs" in tools and talgs and n >= a.threads_min_n and a.threads):
            talgs = []
        if not ("nbs" in tools and talgs):
            walgs = []
        counts = [1] + (a.threads if n >= a.threads_min_n else [])
        best, procs = {}, {}

        def keep(res, suffix=""):
            for r in res:
                if suffix and r.get("tool", "").startswith("nbs-"):
                    r["tool"] += suffix
                procs[r["tool"]] = procs.get(r["tool"], 0) + 1
                old = best.get(r["tool"])
                if old is None or (r.get("status") == "ok" and (
                        old.get("status") != "ok" or
                        float(r["seconds"]) < float(old["seconds"]))):
                    best[r["tool"]] = r

        def one_round():
            for t in counts if talgs else []:
                # the cores' balance just before a process with threads (probe_cores)
                ratio = self.probe_cores() if t > 1 else None
                res, err = self.run_cmd([f"{self.bin}/nbs_bench", "--file", path, "--dim",
                                         str(dim), "--threads", str(t), "--algorithms",
                                         ",".join(talgs)] + timing, f"nbs-threads{t}",
                                        a.timeout)
                for r in res if ratio else []:
                    r["core_ratio"] = f"{ratio:.2f}"
                keep(res, "-1t" if t == 1 else "")
            # at least --step-repeats steps: a context that times its first steps from the
            # last order against from scratch (nbs.h, "time steps") has chosen by the sixth
            steps = [x for x in timing if x != "--fresh"] + ["--move", repr(a.steps)]
            steps[steps.index("--repeats") + 1] = str(max(a.repeats, a.step_repeats))
            for t in counts if salgs else []:
                res, err = self.run_cmd([f"{self.bin}/nbs_bench", "--file", path, "--dim",
                                         str(dim), "--threads", str(t), "--algorithms",
                                         ",".join(salgs)] + steps, f"nbs-steps{t}", a.timeout)
                keep(res)
            if walgs:
                res, err = self.run_cmd([f"{self.bin}/nbs_bench", "--file", path, "--dim",
                                         str(dim), "--threads", "1", "--algorithms",
                                         ",".join(walgs)] + timing, "nbs-twins", a.timeout)
                keep(res, "-1t")

        for _ in range(a.thread_rounds if talgs or salgs else 0):
            one_round()
        # Disturbed: a one-thread row and its -1t twin (the same code on the same file) more
        # than DISTURBED apart. The machine was disturbed during one of them; the nbs rows
        # of this case (every algorithm of the first process, and a round of the
        # alternation) are measured again after a pause, up to --retries times, each row
        # keeping its fastest process.
        first = {r["tool"]: r for r in results}

        def disturbed():
            out = []
            for x in talgs + walgs:
                r, twin = first.get(f"nbs-{x}"), best.get(f"nbs-{x}-1t")
                if r and twin and r.get("status") == "ok" and twin.get("status") == "ok":
                    u, v = float(r["seconds"]), float(twin["seconds"])
                    if max(u, v) > DISTURBED * min(u, v):
                        out.append(x)
            # Likewise the rows of one thread count whose algorithms ran the same code (auto
            # runs cellsort) in the same processes: the second core taken from all of one
            # algorithm's rounds and from none of the other's. Seen once (2D, N = 1e5, S/D
            # 10, 2026-11-29): cellsort with two threads 11.8 ns per element in each of its
            # three processes, as slow as one thread, auto in the same processes 6.3; the
            # case again, 6.2 and 6.3.
            for t in counts[1:]:
                same = {}
                for x in talgs:
                    r = best.get(f"nbs-{x}-{t}t")
                    if r and r.get("status") == "ok" and r.get("ran"):
                        same.setdefault(r["ran"], []).append((float(r["seconds"]), x))
                for rows in same.values():
                    if len(rows) > 1 and max(rows)[0] > DISTURBED * min(rows)[0]:
                        out.append(f"{max(rows)[1]}-{t}t")
            return out

        retried = 0
        while retried < a.retries:
            which = disturbed()
            if not which:
                break
            retried += 1
            log(f"   disturbed ({', '.join(which)}): measured again, {retried} of {a.retries}")
            time.sleep(a.retry_wait)
            res, err = self.run_cmd([f"{self.bin}/nbs_bench", "--file", path, "--dim",
                                     str(dim)] + algs + timing, "nbs", a.timeout)
            for r in res:
                old = first.get(r.get("tool"))
                if old is not None and r.get("status") == "ok" and old.get("status") == "ok":
                    if float(r["seconds"]) < float(old["seconds"]):
                        results[results.index(old)] = r
                        first[r["tool"]] = r
            one_round()
        if retried:
            for r in results:
                if r.get("status") == "ok" and r.get("tool", "").startswith("nbs-"):
                    r["note"] = f"fastest of {retried + 1} processes (the case was disturbed)"
        for r in best.values():
            if r.get("status") == "ok":
                what = ("time steps: " if "-steps" in r["tool"] else "")
                twin = r["tool"][4:-3] in walgs and r["tool"].endswith("-1t")
                r["note"] = (what + f"fastest of {procs[r['tool']]} processes alternating "
                             + ("with the thread runs" if twin else
                                "with the other thread counts") +
                             (f" ({retried} more rounds: the case was disturbed)"
                              if retried else ""))
                if "-steps" in r["tool"]:
                    r["note"] += (f"; steps of {a.steps:g} diameters per axis; the last "
                                  f"re-sorted {r.get('moved', '?')} elements "
                                  f"(reused order: {r.get('reused', '?')})")
        # The one-thread rows of the thread algorithms keep the fastest of their processes:
        # the first and its -1t twins run the same code on the same file, one thread each,
        # and LAMMPS, the peer of the targets, keeps the fastest of as many processes
        # (--lammps-rounds, by default 1 + --thread-rounds), so that neither side's ratio
        # rests on one process of a shared machine.
        for x in talgs + walgs:
            r, twin = first.get(f"nbs-{x}"), best.get(f"nbs-{x}-1t")
            if not (r and twin and r.get("status") == "ok" and twin.get("status") == "ok"):
                continue
            k = 1 + retried + procs.get(twin["tool"], 0)
            if float(twin["seconds"]) < float(r["seconds"]):
                fast = dict(twin)
                fast["tool"] = r["tool"]
                results[results.index(r)] = fast
                r = fast
            r["note"] = (f"fastest of {k} one-thread processes (its own and those of "
                         f"nbs-{x}-1t" + (", alternating with the thread runs" if x in walgs
                                          else "") + ")" +
                         (" (the case was disturbed)" if retried else ""))
        results += list(best.values())
        for peer in [t for t in PEERS if t in tools]:
            skip = self.skip_peer(peer, scene, dim, n, path)
            if skip:
                results.append({"tool": peer, "status": "skipped", "note": skip})
                continue
            res, err = self.run_peer(peer, path, dim)
            if err and any(r.get("status") != "ok" for r in res):
                res[0]["note"] = err.splitlines()[-1][:200]
            # LAMMPS, the peer of the targets, in --lammps-rounds processes, keeping the
            # fastest: a disturbed process would otherwise flatter nbs's ratio to it, and
            # no twin row shows a peer's disturbance
            rounds = a.lammps_rounds if peer.startswith("lammps") else 1
            measured = 1  # processes that gave a time
            for _ in range(rounds - 1):
                if len(res) != 1 or res[0].get("status") != "ok":
                    break
                more, _ = self.run_peer(peer, path, dim)
                if len(more) == 1 and more[0].get("status") == "ok":
                    measured += 1
                    if float(more[0]["seconds"]) < float(res[0]["seconds"]):
                        res = more
            if measured > 1:
                res[0]["note"] = f"fastest of {measured} processes"
            results += res
        if not a.keep_files:
            os.remove(path)
            if os.path.exists(path + ".data"):
                os.remove(path + ".data")
        self.record(tag, dict(scene=scene, dim=dim, order=order, N=n, fraction=fraction,
                              spacing=spacing), results)

    def probe_cores(self):
        """How far apart the first two cores this process may use run at this moment: the
        same small detection (nbs_bench, cellsort, one thread, N = PROBE_N) pinned to each
        in turn (sched_setaffinity), the slower one's time over the faster one's. This
        machine's virtual cores have run the same work up to 2x apart for spells of
        minutes, with no load of ours (bench/README.md); two threads can then give about
        1 + 1/ratio times one thread's speed on the faster core, however the work is shared
        (about: the probe is a few percent noisy, and the one-thread row may have run on
        the slower core).
        Each threaded process's rows keep the ratio measured just before it (column
        core_ratio), and the summary's threads target shows it. None where the process may
        not run on two cores or a probe fails."""
        if not hasattr(os, "sched_getaffinity"):
            return None
        cpus = sorted(os.sched_getaffinity(0))[:2]
        if len(cpus) < 2:
            return None
        ns = []
        for cpu in cpus:
            cmd = [f"{self.bin}/nbs_bench", "--scene", "uniform", "--n", str(PROBE_N),
                   "--algorithms", "cellsort", "--repeats", "10", "--fresh"]
            try:
                p = subprocess.run(cmd, capture_output=True, text=True, timeout=120,
                                   preexec_fn=lambda c=cpu: os.sched_setaffinity(0, {c}))
            except (OSError, subprocess.SubprocessError):
                return None
            r = next((x for x in map(parse_line, p.stdout.splitlines()) if x), None)
            if not r or r.get("status") != "ok":
                return None
            ns.append(float(r["ns_per_element"]))
        if self.a.verbose:
            log(f"    cores: {ns[0]:.2f} and {ns[1]:.2f} ns per element (cpus {cpus})")
        return max(ns) / min(ns)

    def skip_peer(self, peer, scene, dim, n, path):
        a = self.a
        if n > a.peer_max_n:
            return f"N > --peer-max-n {fmt_n(a.peer_max_n)}"
        if scene not in ("uniform", "density") and n > a.peer_max_n_other:
            return f"N > --peer-max-n-other {fmt_n(a.peer_max_n_other)}"
        if peer.startswith("lammps"):
            if peer == "lammps-nosort" and n > a.nosort_max_n:
                return f"N > --nosort-max-n {fmt_n(a.nosort_max_n)}"
            # LAMMPS bins the whole box (bins of half the cutoff) and clears every bin at
            # every build: a spread-out domain needs more bins than memory holds.
            bins = self.lammps_bins(path, dim)
            if bins > a.lammps_max_bins:
                return f"LAMMPS would need {bins:.3g} bins (> --lammps-max-bins)"
        return ""

    @staticmethod
    def lammps_bins(path, dim):
        import numpy as np
        p = np.fromfile(path, dtype="<f8").reshape(-1, dim)
        if len(p) == 0:
            return 0
        ext = p.max(axis=0) - p.min(axis=0) + 2.0  # the data file's box: bounds +- d
        return float(np.prod(np.ceil(ext / 0.5)))

    def run_peer(self, peer, path, dim):
        a = self.a
        common = ["--file", path, "--dim", str(dim), "--repeats", str(a.peer_repeats)]
        if peer in ("nanoflann", "cgal"):
            exe = f"{self.bin}/{peer}_pairs"
            if not os.path.exists(exe):
                return [{"tool": peer, "status": "missing"}], f"{exe} not built"
            return self.run_cmd([exe] + common, peer, a.timeout)
        if peer == "scipy":
            return self.run_cmd([PY, f"{HERE}/scipy_pairs.py"] + common, peer, a.timeout)
        extra = ["--data", path + ".data"]
        if peer == "lammps-nosort":
            extra.append("--no-sort")
        return self.run_cmd([PY, f"{HERE}/lammps_pairs.py"] + common + extra, peer, a.timeout)

    # ---- agreement -------------------------------------------------------------------------
    def record(self, tag, base, results):
        ok = [r for r in results if r.get("status") == "ok"]
        ref = next((r for r in ok if r["tool"] == "nbs-direct"), None) or \
            next((r for r in ok if r["tool"] == "nbs-auto"), None) or (ok[0] if ok else None)
        for r in results:
            row = dict(base)
            row.update({k: r.get(k, "") for k in COLUMNS if k in r})
            row["tool"] = r["tool"]
            row["status"] = r.get("status", "failed")
            row["nbs_build"] = self.build_id
            m = re.match(r"(nbs-.*)-\d+t$", r["tool"])
            one = next((x for x in results if m and x["tool"] == m.group(1)), None)
            if r["tool"].startswith("nbs-"):
                row["peak_bytes"] = r.get("peak_bytes", "")
            elif r["tool"] in ("nanoflann", "cgal", "scipy"):
                row["peak_bytes"] = r.get("rss_extra_bytes", "")
            if row["status"] == "ok" and "same_as_fresh" in r:
                # time steps: other coordinates, checked against a detection from scratch
                row["agree"] = "yes" if r["same_as_fresh"] == "1" else "NO"
                if row["agree"] == "NO":
                    self.fail(tag, r["tool"], "after time steps, the pairs differ from a "
                              "detection from scratch of the same coordinates")
                if one and one.get("hash") and one.get("hash") != r.get("hash"):
                    row["agree"] = "NO"
                    self.fail(tag, r["tool"], f"pair list differs from {one['tool']} "
                              f"(hash {r.get('hash')} vs {one['hash']})")
            elif row["status"] == "ok":
                if int(r["pairs"]) == int(ref["pairs"]):
                    row["agree"] = "yes"
                else:
                    row["agree"] = "NO"
                    self.fail(tag, r["tool"], f"{r['pairs']} pairs, but {ref['tool']} found "
                              f"{ref['pairs']}")
                if one and one.get("hash") and one.get("hash") != r.get("hash"):
                    row["agree"] = "NO"
                    self.fail(tag, r["tool"], f"pair list differs from {one['tool']} "
                              f"(hash {r.get('hash')} vs {one['hash']})")
            elif row["status"] in ("failed", "timeout", "missing"):
                self.fail(tag, r["tool"], f"status {row['status']} {r.get('note', '')}")
            self.rows.append(row)
            if row["status"] == "ok":
                log(f"   {row['tool']:14s} {float(row['ns_per_element']):10.1f} ns/el "
                    f"{int(row['pairs']):>11d} pairs  {row['agree']}"
                    + (f"  (ran {row.get('ran')})" if r["tool"] == "nbs-auto" else ""))
            else:
                log(f"   {row['tool']:14s} {row['status']} {row.get('note', '')}")

    def floors(self):
        """The memory's own cost per element at each N (nbs_floor: a random gather of the
        input, and one streaming copy of it), rows of the scene "floor", for the summary's
        linear target: how much of auto's and nbs's growth with N no preparation that reads
        random-order elements can avoid on this machine."""
        a = self.a
        for dim in a.dims:
            for n in sorted(a.n):
                tag = f"floor {dim}D N={fmt_n(n)}"
                log(f"== {tag}")
                cmd = [f"{self.bin}/nbs_floor", "--n", str(n), "--dim", str(dim),
                       "--repeats", str(a.repeats), "--min-time", str(a.min_time)]
                lines, err = self.run_cmd(cmd, "floor-gather", a.timeout)
                for r in lines:
                    row = {"scene": "floor", "dim": dim, "order": "random", "N": n,
                           "fraction": "", "spacing": "", "agree": "n/a",
                           "nbs_build": self.build_id}
                    row.update({k: r.get(k, "") for k in COLUMNS if k in r})
                    row["status"] = r.get("status", "failed")
                    if row["status"] != "ok":
                        row["note"] = err[:200]
                        self.fail(tag, row["tool"], f"status {row['status']} {err[:200]}")
                    else:
                        log(f"   {row['tool']:14s} {float(row['ns_per_element']):10.2f} ns/el")
                    self.rows.append(row)

    def fail(self, tag, tool, msg):
        self.failures.append(f"{tag}: {tool}: {msg}")
        log(f"!!!!!!!! {tag}: {tool}: {msg}")


# ---- the plan ---------------------------------------------------------------------------
def plan(a):
    """(scene, dim, order, N, fraction, spacing, tools) for every case, cheapest first."""
    cases = []
    for n in sorted(a.n):
        for dim in a.dims:
            for scene in a.scenes:
                if scene != "uniform" and n > a.other_max_n:
                    continue
                for order in a.orders:
                    frac = {"uniform": a.fraction, "sparse": a.sparse_fraction}.get(scene, 0.5)
                    cases.append((scene, dim, order, n, frac, "", None))
    if a.sweep_n > 0:
        for dim in a.dims:
            for s in a.spacings:
                cases.append(("density", dim, "random", a.sweep_n,
                              fraction_for_spacing(dim, s), s, None))
    return cases


def number_list(text, conv=float):
    return [conv(float(x)) for x in text.split(",") if x.strip()]


def machine_name():
    model = "unknown-cpu"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    slug = re.sub(r"[^a-z0-9]+", "-", model.lower()).strip("-")
    return f"{slug}-{os.cpu_count()}cpu"


def nbs_build_id(build):
    """The commit the drivers were linked from, '+' when src/ or include/ had changes then:
    written by the build after each link of nbs_bench (bench/build_id.cmake). A tree linked
    before that existed has no record: "unknown", since the work tree's state now need not
    be the one it was built from."""
    try:
        return open(os.path.join(build, "nbs_build_id")).read().strip()
    except OSError:
        return "unknown"


def command_output(cmd):
    try:
        return subprocess.run(cmd, capture_output=True, text=True, timeout=30).stdout.strip()
    except (OSError, subprocess.TimeoutExpired):
        return "(unavailable)"


def first_line(cmd):
    out = command_output(cmd).splitlines()
    return out[0] if out else "(unavailable)"


def describe_machine(a, started, load_start):
    lines = [f"date: {started}", f"command: bench/run {' '.join(a.argv)}"]
    model, flags = "?", ""
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name") and model == "?":
                model = line.split(":", 1)[1].strip()
            if line.startswith("flags") and not flags:
                fl = line.split(":", 1)[1].split()
                flags = " ".join(f for f in fl if f in ("sse4_2", "avx", "avx2", "fma", "avx512f",
                                                        "avx512vl", "bmi2"))
    except OSError:
        pass
    mem = "?"
    try:
        mem = open("/proc/meminfo").readline().split(":", 1)[1].strip()
    except OSError:
        pass
    # the family and model tell instances of one kind apart (a VM's model name may be bare)
    cache = command_output(["sh", "-c", "lscpu | grep -i 'family\\|^Model:\\|Stepping\\|cache"
                            "\\|MHz\\|Thread\\|Core\\|Socket'"])
    lines += [f"nproc: {os.cpu_count()}", f"cpu: {model}", f"cpu flags (subset): {flags}",
              f"memory: {mem}", f"kernel: {platform.release()}",
              f"load average at start: {load_start}",
              f"load average at end: {open('/proc/loadavg').read().strip()}",
              "lscpu:", *["  " + x for x in cache.splitlines()],
              f"cc: {first_line(['cc', '--version'])}",
              f"c++: {first_line(['c++', '--version'])}",
              f"cmake: {first_line(['cmake', '--version'])}",
              f"lmp: {first_line(['sh', '-c', 'lmp -h | grep -m1 Simulator'])}",
              f"python: {command_output([PY, '--version'])}",
              f"nbs build: {nbs_build_id(a.build)} (the commit nbs_bench was linked from; '+': "
              "src/ or include/ had changes then)",
              "debian packages:"]
    pk = command_output(["dpkg-query", "-W", "-f", "${Package} ${Version}\\n", "lammps",
                         "python3-scipy", "python3-numpy", "python3-matplotlib",
                         "libnanoflann-dev", "libcgal-dev", "gcc", "g++", "cmake"])
    lines += ["  " + x for x in pk.splitlines()]
    return "\n".join(lines) + "\n"


def earlier_runs(text):
    """The runs a machine.txt (its text) records, oldest first, one line each (date, build,
    command): its own run, after the earlier runs it lists.

    >>> earlier_runs("date: D1\\ncommand: bench/run --fresh\\nnbs build: abc (the commit)\\n")
    ['D1, build abc: bench/run --fresh']
    >>> earlier_runs("date: D2\\ncommand: bench/run --n 1e8\\nnproc: 2\\nnbs build: def\\n"
    ...              "earlier runs (rows):\\n  D1, build abc: bench/run --fresh\\n")
    ['D1, build abc: bench/run --fresh', 'D2, build def: bench/run --n 1e8']
    >>> earlier_runs("")
    []
    """
    lines = text.splitlines()
    own = {k: "" for k in ("date", "nbs build", "command")}
    listed, in_list = [], False
    for line in lines:
        if line.startswith("earlier runs"):
            in_list = True
        elif in_list and line.startswith("  "):
            listed.append(line.strip())
        else:
            in_list = False
            key, _, value = line.partition(": ")
            if key in own and not own[key]:
                own[key] = value.split(" (")[0] if key == "nbs build" else value
    if not own["command"]:
        return listed
    return listed + [f"{own['date']}, build {own['nbs build'] or '?'}: {own['command']}"]


# ---- results: merge, summary, plots -------------------------------------------------------
def key_of(r):
    return tuple(str(r[k]) for k in KEY)


def load_rows(path):
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


def write_rows(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in COLUMNS})


def find(rows, **kw):
    for r in rows:
        if all(str(r[k]) == str(v) for k, v in kw.items()) and r["status"] == "ok":
            return r
    return None


def nsel(r):
    return float(r["ns_per_element"]) if r else None


def summary(rows, n_head):
    out = []
    f = lambda x: f"{x:.1f}" if x is not None else "n/a"  # noqa: E731
    for dim in (3, 2):
        head = {r["tool"]: r for r in rows if r["scene"] == "uniform" and r["dim"] == str(dim)
                and r["order"] == "random" and r["N"] == str(n_head) and r["status"] == "ok"}
        srt = {r["tool"]: r for r in rows if r["scene"] == "uniform" and r["dim"] == str(dim)
               and r["order"] == "sorted" and r["N"] == str(n_head) and r["status"] == "ok"}
        if not head:
            continue
        auto = nsel(head.get("nbs-auto"))
        out.append(f"### {dim}D, N = {fmt_n(n_head)}, uniform, fraction 0.5\n")
        out.append("| tool | ns/element (random order) | auto is x faster | "
                   "ns/element (sorted order) | peak bytes/element | pairs |")
        out.append("|---|---:|---:|---:|---:|---:|")
        for t in sorted(head, key=tool_rank):
            r = head[t]
            ratio = nsel(r) / auto if auto else None
            pb = float(r["peak_bytes"]) / n_head if r.get("peak_bytes") else None
            out.append(f"| {t}{' (ran ' + r['ran'] + ')' if t == 'nbs-auto' else ''} | "
                       f"{f(nsel(r))} | {f'{ratio:.2f}' if ratio else 'n/a'} | "
                       f"{f(nsel(srt.get(t)))} | {f(pb)} | {r['pairs']} |")
        out.append("")
    # Targets, each computed from the rows.
    t = []

    def get(tool, dim=3, scene="uniform", n=n_head, order="random"):
        return nsel(find(rows, tool=tool, dim=dim, scene=scene, N=n, order=order))

    def target(name, ok, detail):
        mark = "n/a (not measured)" if ok is None else ("met" if ok else "NOT met")
        t.append(f"| {name} | {detail} | {mark} |")

    auto3, nbs3 = get("nbs-auto"), get("nbs-nbs")
    target("auto <= 50 ns/element (3D)", None if auto3 is None else auto3 <= 50,
           f"auto {f(auto3)} ns")
    for lm in ("lammps", "lammps-nosort"):
        l3 = get(lm)
        target(f"auto >= 6x {lm} (3D)",
               None if auto3 is None or l3 is None else l3 / auto3 >= 6,
               f"auto {f(auto3)} ns, {lm} {f(l3)} ns, ratio "
               f"{f'{l3 / auto3:.2f}' if auto3 and l3 else 'n/a'}")
    sc = get("scipy")
    target("auto >= 40x scipy (3D)", None if auto3 is None or sc is None else sc / auto3 >= 40,
           f"ratio {f'{sc / auto3:.1f}' if auto3 and sc else 'n/a'}")
    # Time steps, like for like with LAMMPS, which also works on an order it keeps (its own
    # spatial sort) from step to step; the elements move between nbs's detections, LAMMPS's
    # atoms do not.
    steps3, l3, s3 = get("nbs-auto-steps"), get("lammps"), get("scipy")
    target("auto in time steps >= 6x lammps (3D)",
           None if steps3 is None or l3 is None else l3 / steps3 >= 6,
           f"auto-steps {f(steps3)} ns, lammps {f(l3)} ns, ratio "
           f"{f'{l3 / steps3:.2f}' if steps3 and l3 else 'n/a'}")
    target("auto in time steps >= 40x scipy (3D)",
           None if steps3 is None or s3 is None else s3 / steps3 >= 40,
           f"ratio {f'{s3 / steps3:.1f}' if steps3 and s3 else 'n/a'}")
    for lm in ("lammps", "lammps-nosort"):
        l3 = get(lm)
        target(f"nbs >= 1.5x {lm} (3D)", None if nbs3 is None or l3 is None else l3 / nbs3 >= 1.5,
               f"nbs {f(nbs3)} ns, ratio {f'{l3 / nbs3:.2f}' if nbs3 and l3 else 'n/a'}")
        a2, l2 = get("nbs-auto", 2), get(lm, 2)
        target(f"2D auto >= 3x {lm}", None if a2 is None or l2 is None else l2 / a2 >= 3,
               f"auto {f(a2)} ns, {lm} {f(l2)} ns, ratio "
               f"{f'{l2 / a2:.2f}' if a2 and l2 else 'n/a'}")
    for tool in ("nbs-auto", "nbs-nbs"):
        for dim in (3, 2):
            lo, hi = get(tool, dim, n=10 ** 4), get(tool, dim, n=10 ** 7)
            # what the memory alone adds from 1e4 to 1e7 (nbs_floor), against what the
            # target allows (0.3 of the time at 1e4)
            g_lo = get("floor-gather", dim, scene="floor", n=10 ** 4)
            g_hi = get("floor-gather", dim, scene="floor", n=10 ** 7)
            floor = ""
            if lo and g_lo is not None and g_hi is not None:
                floor = (f"; a bare random gather of the input {f(g_lo)} -> {f(g_hi)} ns "
                         f"(+{g_hi - g_lo:.1f}), the target allows +{0.3 * lo:.1f}")
            target(f"linear: {tool} {dim}D N=1e7 within 1.3x of N=1e4",
                   None if lo is None or hi is None else hi / lo <= 1.3,
                   f"{f(lo)} -> {f(hi)} ns, ratio {f'{hi / lo:.2f}' if lo and hi else 'n/a'}"
                   + floor)
    n_sc = max([int(r["N"]) for r in rows if r["scene"] in OTHER_SCENES
                and r["status"] == "ok"] or [0])
    others = compared_scenes(rows)
    if n_sc:
        for tool in ("nbs-auto", "nbs-nbs"):
            for dim in (3, 2):
                u = find(rows, tool=tool, dim=dim, scene="uniform", N=n_sc, order="random")
                for scene in others:
                    s = find(rows, tool=tool, dim=dim, scene=scene, N=n_sc, order="random")
                    if not (u and s):
                        target(f"{scene} within 1.5x of uniform: {tool} {dim}D", None, "")
                        continue
                    # Memory beyond the pair buffer: a crowded scene has more contacts,
                    # and the pairs are the caller's output, not the algorithm's memory.
                    rt = nsel(s) / nsel(u)
                    work = lambda r: int(r["peak_bytes"]) - int(r["pair_bytes"] or 0)  # noqa
                    mem = work(s) / work(u)
                    target(f"{scene} within 1.5x of uniform, memory <= uniform: {tool} {dim}D "
                           f"N={fmt_n(n_sc)}", rt <= 1.5 and mem <= 1.0,
                           f"time x{rt:.2f}; peak bytes beyond the pair buffer x{mem:.2f} "
                           f"({work(s) / n_sc:.1f} vs {work(u) / n_sc:.1f} per element)")
    for tool in ("nbs-auto", "nbs-nbs"):
        r = find(rows, tool=tool, dim=3, scene="uniform", N=n_head, order="random")
        if r:
            extra = (int(r["peak_bytes"]) - int(r["pair_bytes"] or 0)) / n_head
            target(f"memory: {tool} peak minus pair buffer <= 40 bytes/element (3D)",
                   extra <= 40, f"{extra:.1f} bytes/element")
    for dim in (3, 2):
        # one thread as measured alternately with the two-thread runs (else the headline's)
        one = (find(rows, tool="nbs-auto-1t", dim=dim, scene="uniform", N=n_head,
                    order="random") or
               find(rows, tool="nbs-auto", dim=dim, scene="uniform", N=n_head, order="random"))
        two = find(rows, tool="nbs-auto-2t", dim=dim, scene="uniform", N=n_head,
                   order="random")
        if one and two:
            sp = float(one["seconds"]) / float(two["seconds"])
            same = one.get("hash") and one["hash"] == two.get("hash")
            target(f"threads: auto with 2 threads >= 1.7x one thread, same output ({dim}D)",
                   sp >= 1.7 and bool(same), f"speed-up x{sp:.2f}, output "
                   f"{'identical' if same else 'DIFFERENT'} (ran {two['ran']})"
                   + cores_text(two.get("core_ratio")))
        else:
            target(f"threads: auto with 2 threads >= 1.7x one thread ({dim}D)", None, "")
    out.append("### Targets (3D unless said, uniform fraction 0.5, random order, N = "
               f"{fmt_n(n_head)})\n")
    out.append("| target | measured | status |")
    out.append("|---|---|---|")
    out += t
    out += floors(rows)
    out += consistency(rows)
    return "\n".join(out) + "\n"


def cores_text(ratio):
    """What the summary says of a threaded row's core_ratio (Suite.probe_cores).

    >>> cores_text("1.45")
    '; the cores ran x1.45 apart just before it (pinned probes): two threads could give about 1.69x one thread on the faster core'
    >>> cores_text("1.02")
    '; the cores ran x1.02 apart just before it (pinned probes)'
    >>> cores_text("") + cores_text(None)
    ''
    """
    if not ratio:
        return ""
    r = float(ratio)
    text = f"; the cores ran x{r:.2f} apart just before it (pinned probes)"
    if r >= 1.05:
        text += f": two threads could give about {1 + 1 / r:.2f}x one thread on the faster core"
    return text


def floors(rows):
    """The memory's floor (nbs_floor rows): per element, a random gather of the input and
    one streaming copy of it, by N."""
    fl = [r for r in rows if r["scene"] == "floor" and r["status"] == "ok"]
    if not fl:
        return []
    f = lambda x: f"{x:.2f}" if x is not None else "n/a"  # noqa: E731
    out = ["", "### The memory's floor (nbs_floor)\n",
           "Per element, without any contact detection: the input (as a caller gives it, "
           "an element's coordinates side by side) copied to one array per axis in a random "
           "order, as a preparation that puts random-order elements in cell order must read "
           "them, and in its own order, one streaming pass. The minimum over the repeats, "
           "ns per element.\n",
           "| dim | N | random gather | copy in order |", "|---|---:|---:|---:|"]
    for dim in (3, 2):
        for n in sorted({int(r["N"]) for r in fl if r["dim"] == str(dim)}):
            g = find(fl, tool="floor-gather", dim=dim, N=n)
            c = find(fl, tool="floor-copy", dim=dim, N=n)
            out.append(f"| {dim}D | {fmt_n(n)} | {f(nsel(g))} | {f(nsel(c))} |")
    return out


# Differences beyond this between two rows of one configuration mark a disturbed run.
DISTURBED = 1.15
PROBE_N = 200000  # elements of the cores' probe (Suite.probe_cores)


def consistency(rows):
    """The same configuration is measured twice in a run: nbs-auto and nbs-cellsort on their
    own, and again (-1t) alternated with their two-thread runs, all on one thread; so is
    nbs-nbs (--twin-algorithms), whose rows targets read too. With more threads, auto and
    cellsort run the same code (auto ran cellsort) in the same processes. Where two such rows
    differ by more than DISTURBED, the machine was disturbed during one of them (this VM's
    neighbours come and go), and every target read from those rows is suspect: the lines below
    say which, so that a reader does not take noise for a result."""
    ok = {(r["scene"], r["dim"], r["order"], r["N"], r["spacing"], r["tool"]): r for r in rows
          if r["status"] == "ok" and r["ns_per_element"]}

    def case(scene, dim, order, n, spacing):
        return f"{scene} {dim}D {order} N={fmt_n(int(n))}" + (f" S/D={spacing}" if spacing else "")

    bad = []
    same = {}
    for (scene, dim, order, n, spacing, tool), r in sorted(ok.items()):
        if not tool.startswith("nbs-") or tool.endswith("-1t"):
            continue
        if r.get("threads") not in ("", "1"):
            if "-steps" not in tool and r.get("ran"):
                same.setdefault((scene, dim, order, n, spacing, r["threads"], r["ran"]),
                                []).append((nsel(r), tool))
            continue
        twin = ok.get((scene, dim, order, n, spacing, tool + "-1t"))
        if not twin:
            continue
        a, b = nsel(r), nsel(twin)
        if max(a, b) > DISTURBED * min(a, b):
            bad.append(f"| {case(scene, dim, order, n, spacing)} | {tool} {a:.1f} ns, "
                       f"{tool}-1t {b:.1f} ns | x{max(a, b) / min(a, b):.2f} |")
    for (scene, dim, order, n, spacing, threads, ran), got in sorted(same.items()):
        (a, ta), (b, tb) = min(got), max(got)
        if len(got) > 1 and b > DISTURBED * a:
            bad.append(f"| {case(scene, dim, order, n, spacing)} | {ta} {a:.1f} ns, {tb} "
                       f"{b:.1f} ns (both ran {ran}) | x{b / a:.2f} |")
    if not bad:
        return []
    return ["", "### Disturbed rows\n",
            f"The same code and scene, measured twice in this run (one thread; or with threads, "
            f"auto and the algorithm it ran), more than {DISTURBED:.2f}x apart: the machine was "
            "disturbed, and targets read from these rows are not results.\n",
            "| case | the two measurements | apart |", "|---|---|---|", *bad]


STYLE = {"nbs-auto": ("C0", "o"), "nbs-auto-2t": ("C0", "1"), "nbs-auto-steps": ("navy", "+"),
         "nbs-cellsort": ("C9", "d"),
         "nbs-nbs": ("C1", "s"), "nbs-sorting": ("C2", "^"), "nbs-screening": ("C3", "v"),
         "nbs-direct": ("C7", "x"), "nanoflann": ("C4", "D"), "cgal": ("C5", "P"),
         "scipy": ("C6", "*"), "lammps": ("k", "h"), "lammps-nosort": ("C8", "<")}
SCENE_ORDER = {"uniform": 0, "sparse": 1, "clustered": 2, "huge": 3, "slab": 4, "floor": 5}
# the scenes compared with uniform (slab: a layer two diameters thick, 2D a strip)
OTHER_SCENES = ("sparse", "clustered", "huge", "slab")


def compared_scenes(rows):
    """The scenes compared with uniform: the issue's always, slab (not one of them) when run."""
    return [sc for sc in OTHER_SCENES if sc != "slab" or any(r["scene"] == sc for r in rows)]


def tool_rank(tool):
    """auto first, then the other nbs algorithms, their thread runs, then the peers."""
    order = ["nbs-auto", "nbs-auto-steps", "nbs-cellsort", "nbs-nbs", "nbs-sorting",
             "nbs-screening", "nbs-direct"]
    if tool in order:
        return (0, order.index(tool), tool)
    if tool.startswith("nbs-"):
        return (1, 0, tool)
    return (2, PEERS.index(tool) if tool in PEERS else 99, tool)


def plots(rows, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in rows if r["status"] == "ok"]
    present = sorted({r["tool"] for r in ok}, key=tool_rank)
    tools = [t for t in present if (t in STYLE or not re.search(r"-\d+t$", t))
             and not t.startswith("floor-")]
    extra = [t for t in tools if t not in STYLE]
    for k, t in enumerate(extra):
        STYLE[t] = (f"C{k % 10}", "p")

    def series(tool, dim, scene, order, x="N", y="ns_per_element"):
        pts = sorted((float(r[x]), float(r[y]), int(r["N"])) for r in ok if r["tool"] == tool
                     and r["dim"] == str(dim) and r["scene"] == scene and r["order"] == order)
        return pts

    made = []
    # 1. ns per element against N.
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.2))
    for ax, dim in zip(axes, (3, 2)):
        for t in tools:
            c, m = STYLE[t]
            for order, ls in (("random", "-"), ("sorted", ":")):
                p = series(t, dim, "uniform", order)
                if p:
                    ax.plot([q[0] for q in p], [q[1] for q in p], ls, color=c, marker=m,
                            label=f"{t}" if order == "random" else None, ms=5)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("N (elements)")
        ax.set_ylabel("ns per element per detection")
        ax.set_title(f"{dim}D uniform, fraction 0.5 (solid: random order, dotted: sorted)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "ns_per_element.png"), dpi=110)
    plt.close(fig)
    made.append("ns_per_element.png")

    # 2. time against spacing (the book's Figs. 3.49-3.53).
    if any(r["scene"] == "density" for r in ok):
        fig, axes = plt.subplots(1, 2, figsize=(13, 5.2))
        sweep_ns = sorted({int(r["N"]) for r in ok if r["scene"] == "density"}, reverse=True)
        styles = ["-", "--", ":", "-."]
        for ax, dim in zip(axes, (3, 2)):
            for t in tools:
                c, m = STYLE[t]
                for k, n in enumerate(sweep_ns):
                    p = sorted((float(r["spacing"]), float(r["seconds"])) for r in ok
                               if r["tool"] == t and r["dim"] == str(dim)
                               and r["scene"] == "density" and r["N"] == str(n))
                    if p:
                        ax.plot([q[0] for q in p], [q[1] for q in p], styles[k % 4], color=c,
                                marker=m, label=t if k == 0 else None, ms=5)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("mean spacing S/D (density (D/S)^dim)")
            ax.set_ylabel("seconds per detection")
            ax.set_title(f"{dim}D uniform random, N = "
                         + ", ".join(f"{fmt_n(n)} ({styles[k % 4]})"
                                     for k, n in enumerate(sweep_ns))
                         + ": time vs packing density", fontsize=10)
            ax.grid(True, which="both", alpha=0.3)
        axes[0].legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(out, "density.png"), dpi=110)
        plt.close(fig)
        made.append("density.png")

    # 3. memory per element.
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.2))
    for ax, dim in zip(axes, (3, 2)):
        for t in tools:
            c, m = STYLE[t]
            p = sorted((int(r["N"]), float(r["peak_bytes"]) / int(r["N"])) for r in ok
                       if r["tool"] == t and r["dim"] == str(dim) and r["scene"] == "uniform"
                       and r["order"] == "random" and r["peak_bytes"] not in ("", "0"))
            if p:
                ax.plot([q[0] for q in p], [q[1] for q in p], "-", color=c, marker=m, label=t,
                        ms=5)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("N (elements)")
        ax.set_ylabel("peak bytes per element")
        ax.set_title(f"{dim}D uniform: nbs: library peak; LAMMPS: its own count;\n"
                     "others: peak RSS above the loaded coordinates", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "memory_per_element.png"), dpi=110)
    plt.close(fig)
    made.append("memory_per_element.png")

    # 4. scenes at the largest N that has all of them.
    scenes = ["uniform"] + compared_scenes(ok)
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.2))
    for ax, dim in zip(axes, (3, 2)):
        ns = [int(r["N"]) for r in ok if r["dim"] == str(dim) and r["scene"] == "huge"
              and r["tool"] == "nbs-auto"]
        if not ns:
            continue
        n = max(ns)
        width = 0.8 / max(1, len(tools))
        for k, t in enumerate(tools):
            vals = []
            for s in scenes:
                r = find(ok, tool=t, dim=dim, scene=s, N=n, order="random")
                vals.append(nsel(r) if r else 0)
            if any(vals):
                ax.bar([i + k * width for i in range(len(scenes))], vals, width,
                       color=STYLE[t][0], label=t)
        ax.set_xticks([i + 0.4 - width / 2 for i in range(len(scenes))], scenes)
        ax.set_yscale("log")
        ax.set_ylabel("ns per element per detection")
        ax.set_title(f"{dim}D, N = {fmt_n(n)}, random order: the scene's effect")
        ax.grid(True, axis="y", which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "scenes.png"), dpi=110)
    plt.close(fig)
    made.append("scenes.png")
    return made


def main(argv):
    ap = argparse.ArgumentParser(prog="bench/run", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--smoke", action="store_true",
                    help="tiny N, every scene and tool; exit 1 on any disagreement or failure")
    ap.add_argument("--build", default=os.path.join(ROOT, "build-bench"))
    ap.add_argument("--n", default="1e3,1e4,1e5,1e6,1e7", help="element counts")
    ap.add_argument("--dims", default="3,2")
    ap.add_argument("--scenes", default="uniform,sparse,clustered,huge")
    ap.add_argument("--orders", default="random,sorted")
    ap.add_argument("--tools", default=",".join(ALL_TOOLS),
                    help="nbs and any of " + ",".join(PEERS))
    ap.add_argument("--algorithms", default="all",
                    help="nbs algorithms (default all the library has; direct only for "
                         "N <= --direct-max)")
    ap.add_argument("--threads", default="2",
                    help="extra thread counts for --thread-algorithms ('' for none); "
                         "every other nbs run uses one thread")
    ap.add_argument("--thread-algorithms", default="auto,cellsort")
    ap.add_argument("--twin-algorithms", default="nbs",
                    help="other nbs algorithms measured again on one thread in each round of "
                         "the thread runs (rows nbs-ALG-1t), so that their rows, which "
                         "targets read, are checked for a disturbed machine as the thread "
                         "algorithms' are and keep the fastest of the processes")
    ap.add_argument("--thread-rounds", type=int, default=3,
                    help="processes per thread count (one included), alternating; each row "
                         "keeps its fastest")
    ap.add_argument("--retries", type=int, default=3,
                    help="more rounds of a case whose one-thread rows disagree by more than "
                         f"{DISTURBED}x (a disturbed machine)")
    ap.add_argument("--retry-wait", type=float, default=10.0,
                    help="seconds of pause before each of those rounds")
    ap.add_argument("--steps", type=float, default=1e-3,
                    help="time-step rows (nbs-ALG-steps, --step-scenes): each element moves "
                         "up to this many diameters per axis per step (0: none)")
    ap.add_argument("--step-repeats", type=int, default=10,
                    help="time steps per time-step row at the fewest (more with --repeats); "
                         "the row keeps the fastest")
    ap.add_argument("--step-algorithms", default="auto")
    ap.add_argument("--step-scenes", default="uniform,huge",
                    help="scenes with time-step rows: uniform (the targets read it), and the "
                         "huge domain, whose keys are too wide for the element's half of a "
                         "word (cellsort's other start from the last order, nbs__cs_warm)")
    ap.add_argument("--threads-min-n", type=float, default=0)
    ap.add_argument("--fraction", type=float, default=0.5, help="uniform scenes")
    ap.add_argument("--sparse-fraction", type=float, default=0.005)
    ap.add_argument("--other-max-n", type=float, default=1e6,
                    help="largest N of the sparse, clustered and huge scenes")
    ap.add_argument("--peer-max-n", type=float, default=1e6,
                    help="largest N at which the peers run (nbs runs at every N)")
    ap.add_argument("--peer-max-n-other", type=float, default=1e5,
                    help="largest N at which the peers run on sparse/clustered/huge")
    ap.add_argument("--nosort-max-n", type=float, default=1e6,
                    help="largest N for lammps-nosort")
    ap.add_argument("--lammps-max-bins", type=float, default=2e8)
    ap.add_argument("--lammps-rounds", type=int, default=None,
                    help="LAMMPS processes per case (each --peer-repeats steps); the row "
                         "keeps the fastest (default 1 + --thread-rounds: as many as the "
                         "one-thread nbs-auto row has)")
    ap.add_argument("--sweep-n", type=float, default=1e5,
                    help="N of the density sweep (0: no sweep)")
    ap.add_argument("--spacings", default="1,2,5,10,20,50,100,200", help="S/D of the sweep")
    ap.add_argument("--direct-max", type=float, default=2e4)
    ap.add_argument("--repeats", type=int, default=5, help="nbs detections per algorithm")
    ap.add_argument("--min-time", type=float, default=0.2,
                    help="nbs repeats at least this many seconds per algorithm")
    ap.add_argument("--peer-repeats", type=int, default=3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=3600, help="seconds per tool run")
    ap.add_argument("--machine", default=None, help="results/<machine> (default: from the CPU)")
    ap.add_argument("--out", default=None, help="results directory (overrides --machine)")
    ap.add_argument("--workdir", default=None, help="scene files (default: a temporary dir)")
    ap.add_argument("--fresh", action="store_true",
                    help="start a new results.csv (default: replace only the cases run now)")
    ap.add_argument("--no-plots", action="store_true")
    ap.add_argument("--keep-files", action="store_true")
    ap.add_argument("--head-n", type=float, default=1e6, help="N of the headline table")
    ap.add_argument("--summary-only", action="store_true",
                    help="run nothing: rewrite summary.md and the plots from results.csv")
    ap.add_argument("-v", "--verbose", action="store_true")
    a = ap.parse_args(argv)
    a.argv = argv
    if a.smoke:
        a.n, a.sweep_n, a.spacings = "1000", 2000, "1,10,200"
        a.repeats, a.peer_repeats, a.min_time, a.thread_rounds = 2, 1, 0.0, 1
        a.retries, a.lammps_rounds = 0, 1
        a.nosort_max_n = 1000
    if a.lammps_rounds is None:
        a.lammps_rounds = 1 + a.thread_rounds
    a.n = number_list(a.n, int)
    a.dims = number_list(a.dims, int)
    a.scenes = [s for s in a.scenes.split(",") if s]
    a.orders = [s for s in a.orders.split(",") if s]
    a.tools = [s for s in a.tools.split(",") if s]
    a.algorithms = [s for s in a.algorithms.split(",") if s]
    a.threads = [int(x) for x in a.threads.split(",") if x.strip() and int(x) != 1]
    a.thread_algorithms = [s for s in a.thread_algorithms.split(",") if s]
    a.twin_algorithms = [s for s in a.twin_algorithms.split(",") if s]
    a.step_scenes = [s for s in a.step_scenes.split(",") if s]
    a.step_algorithms = [s for s in a.step_algorithms.split(",") if s]
    a.spacings = number_list(a.spacings, lambda x: int(x) if x == int(x) else x)
    a.sweep_n = int(a.sweep_n)
    for k in ("other_max_n", "peer_max_n", "peer_max_n_other", "nosort_max_n", "direct_max",
              "head_n", "threads_min_n"):
        setattr(a, k, int(getattr(a, k)))
    bad = [t for t in a.tools if t not in ALL_TOOLS]
    if bad:
        ap.error(f"unknown tools {bad}")
    if a.out is None:
        a.out = (tempfile.mkdtemp(prefix="nbs-bench-smoke-") if a.smoke else
                 os.path.join(HERE, "results", a.machine or machine_name()))
    os.makedirs(a.out, exist_ok=True)
    if a.summary_only:
        rows = load_rows(os.path.join(a.out, "results.csv"))
        with open(os.path.join(a.out, "summary.md"), "w") as f:
            f.write(f"From {os.path.basename(a.out)}/results.csv (measured by the builds in its "
                    f"nbs_build column; machine.txt); regenerate with bench/run.\n\n")
            f.write(summary(rows, a.head_n))
        made = [] if a.no_plots else plots(rows, a.out)
        log(f"wrote summary.md {' '.join(made)} in {a.out}")
        return 0
    own_workdir = a.workdir is None
    if own_workdir:
        a.workdir = tempfile.mkdtemp(prefix="nbs-bench-scenes-")
    os.makedirs(a.workdir, exist_ok=True)

    started = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")
    load_start = open("/proc/loadavg").read().strip()
    t0 = time.time()
    suite = Suite(a)
    try:
        for c in plan(a):
            suite.case(*c)
        if "nbs" in a.tools:
            suite.floors()
    finally:
        if own_workdir:
            shutil.rmtree(a.workdir, ignore_errors=True)

    csv_path = os.path.join(a.out, "results.csv")
    rows = suite.rows
    if not a.fresh and not a.smoke:
        now = {key_of(r) for r in rows}
        rows = [r for r in load_rows(csv_path) if key_of(r) not in now] + rows
        rows.sort(key=lambda r: (r["scene"] == "density", SCENE_ORDER.get(r["scene"], 9),
                                 -int(r["dim"]), r["order"], int(r["N"]),
                                 float(r["spacing"] or 0), tool_rank(r["tool"])))
    write_rows(csv_path, rows)
    rows = load_rows(csv_path)
    mpath = os.path.join(a.out, "machine.txt")
    earlier = []
    if not a.fresh and not a.smoke and os.path.exists(mpath):
        with open(mpath) as f:
            earlier = earlier_runs(f.read())
    with open(mpath, "w") as f:
        f.write(describe_machine(a, started, load_start))
        if earlier:
            # a merge keeps the earlier runs' rows that this one did not replace
            f.write("earlier runs (rows of results.csv this run did not replace):\n")
            f.writelines(f"  {x}\n" for x in earlier)
    with open(os.path.join(a.out, "summary.md"), "w") as f:
        f.write(f"Measured {started} on {os.path.basename(a.out)} (machine.txt"
                + ("; its earlier runs measured the rows this one did not" if earlier else "")
                + "); regenerate with bench/run.\n\n")
        f.write(summary(rows, a.head_n))
    made = [] if a.no_plots else plots(rows, a.out)
    log(f"\nwrote {csv_path}, summary.md, machine.txt" +
        (", " + ", ".join(made) if made else "") + f"  ({time.time() - t0:.0f} s)")
    n_ok = sum(1 for r in suite.rows if r["status"] == "ok")
    if suite.failures:
        log("\n" + "!" * 78)
        log(f"!!! {len(suite.failures)} FAILURE(S): tools disagree on pair counts or failed:")
        for x in suite.failures:
            log(f"!!!   {x}")
        log("!" * 78)
        log(f"bench: {n_ok} passed, {len(suite.failures)} failed")
        return 1
    log(f"all tools agree on every case")
    log(f"bench: {n_ok} passed, 0 failed")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
