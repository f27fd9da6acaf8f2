#!/usr/bin/env python3
"""Writes the seed corpus of the fuzz targets (tests/fuzz/corpus/<target>/).

Each seed is a scene in the byte layout that fuzz_detect.c documents, chosen so that the
fuzzer starts from every adversarial family at once: lattices at exactly the contact
distance and on cell faces, identical points, chains at ri + rj (and one ulp off), huge
offsets up to +-1.7e308, denormal and overflowing diameters, radius ratios of 1e6, tight
cell budgets, pair limits, both sinks, 2D and 3D. The corpus is committed; run this again
only when the layout of fuzz_detect.c changes:  python3 tests/fuzz/make_seeds.py
"""
import os
import random
import struct

HERE = os.path.dirname(os.path.abspath(__file__))

# Indices into the tables of fuzz_detect.c.
D = {"1": 0, "0.5": 1, "2": 2, "3": 3, "0.1": 4, "1/3": 5, "1e-3": 6, "1e-6": 7, "1e6": 8,
     "7": 9, "1e-160": 10, "1e-170": 11, "1e-300": 12, "1e-310": 13, "5e-324": 14,
     "2^-498": 15, "2^-499": 16, "2^-511": 17, "2^-1022": 18, "1e150": 19, "1e154": 20,
     "sqrtmax": 21, "1.35e154": 22, "1e200": 23, "1e300": 24, "max": 25}
O = {"0": 0, "1": 1, "-1": 2, "0.5": 3, "1e9": 4, "-1e9": 5, "1e15": 6, "-1e15": 7,
     "2^52": 8, "2^53": 9, "-2^53": 10, "1e300": 11, "-1e300": 12, "1.7e308": 13,
     "-1.7e308": 14, "max": 15, "-max": 16, "1e-300": 17, "5e-324": 18, "-0": 19, "0.1": 20,
     "123456.789": 21}
# fz_unit selectors
U = {"d": 0, "d/2": 1, "edge": 2, "edge/2": 3, "2d": 4, "d/3": 5, "d+ulp": 6, "d-ulp": 7,
     "edge-ulp": 8, "one": 9, "d/4": 10, "1.5edge": 11}
BUDGET_1M, BUDGET_64K, BUDGET_U16, BUDGET_U8 = 0, 1, 2, 3


def op(kind, p=0):
    return bytes([(p & 31) << 3 | kind])


def lattice(k, axis, m):
    """Opcode 0: origin + (p - 16) * unit, element k on an m^dim lattice."""
    q = k
    for _ in range(axis):
        q //= m
    return op(0, 16 + q % m)


def raw(v):
    return struct.pack("<d", v)


class Seed:
    def __init__(self, dim=2, n=16, diam="1", radii=False, callback=False, max_pairs=None,
                 budget=BUDGET_1M, budget_value=0, reserve=None, origin="0", unit="d",
                 fail_at=None):
        flags = (1 if dim == 3 else 0) | (2 if radii else 0) | (4 if callback else 0)
        flags |= (8 if max_pairs is not None else 0) | budget << 4
        flags |= (64 if reserve is not None else 0) | (128 if fail_at is not None else 0)
        b = bytes([flags, n, D[diam]])
        if budget == BUDGET_U16:
            b += struct.pack("<H", budget_value)
        elif budget == BUDGET_U8:
            b += bytes([budget_value // 4])
        if max_pairs is not None:
            b += struct.pack("<H", max_pairs - 1)
        if reserve is not None:
            b += bytes([reserve])
        if fail_at is not None:
            b += bytes([fail_at])
        origins = origin if isinstance(origin, list) else [origin] * dim
        for o in origins:
            b += bytes([O[o]])
        b += bytes([U[unit]])
        self.head = b
        self.dim, self.n, self.radii = dim, n, radii
        self.body = b""

    def data(self):
        return self.head + self.body


def write(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def detect_seeds():
    rng = random.Random(20261122)
    seeds = {}

    for dim in (2, 3):
        m = 6 if dim == 2 else 4
        n = m ** dim
        for unit in ("d", "edge", "edge/2", "d-ulp", "d+ulp", "d/2"):
            s = Seed(dim=dim, n=n, unit=unit)
            for k in range(n):
                for a in range(dim):
                    s.body += lattice(k, a, m)
            seeds[f"lattice_{dim}d_{unit.replace('/', '_')}"] = s
        for origin in ("1e9", "1e15", "-1e15", "2^53", "1e300", "0.1"):
            s = Seed(dim=dim, n=n, origin=origin)
            for k in range(n):
                for a in range(dim):
                    s.body += lattice(k, a, m)
            seeds[f"lattice_{dim}d_offset_{origin}"] = s

        # identical points, in the buffer with and without a pair limit, and by callback
        for variant, kw in (("plain", {}), ("max_pairs", {"max_pairs": 100}),
                            ("callback", {"callback": True}),
                            ("callback_max_pairs", {"callback": True, "max_pairs": 1000})):
            s = Seed(dim=dim, n=64, origin="123456.789", **kw)
            for k in range(64):
                for a in range(dim):
                    s.body += op(1, 0) if k else op(0, 16)
            seeds[f"identical_{dim}d_{variant}"] = s

        # chains at exactly the contact distance, and one ulp off, per-element radii
        for radii in (False, True):
            s = Seed(dim=dim, n=48, radii=radii, diam="1")
            if radii:
                s.body += bytes(rng.choice((0, 2, 3, 4, 5, 6)) for _ in range(48))
            for k in range(48):
                for a in range(dim):
                    s.body += op(rng.choice((1, 2, 2, 3, 3)), rng.randrange(32)) if k else op(0, 16)
            seeds[f"chain_{dim}d_{'radii' if radii else 'diameter'}"] = s

        # radius ratio 1e6: a few large, many small, close together
        s = Seed(dim=dim, n=64, radii=True, diam="2", unit="d/4")
        s.body += bytes(0 if k % 16 == 0 else 6 for k in range(64))
        for k in range(64):
            for a in range(dim):
                s.body += op(7) + struct.pack("<H", rng.randrange(65536)) if k % 3 else op(3, rng.randrange(32))
        seeds[f"ratio_1e6_{dim}d"] = s

        # huge coordinates: differences overflow to infinity
        for diam in ("1", "1e300", "1e200"):
            s = Seed(dim=dim, n=40, diam=diam, origin="1.7e308")
            for k in range(40):
                for a in range(dim):
                    c = rng.randrange(4)
                    s.body += [op(4, rng.randrange(32)), op(1, rng.randrange(32)),
                               op(0, 16 + rng.randrange(3)), op(2, rng.randrange(32))][c]
            seeds[f"huge_{dim}d_d{diam}"] = s

        # denormal and tiny diameters with denormal coordinates
        for diam in ("1e-310", "5e-324", "1e-160", "1e-170", "2^-498", "2^-511"):
            s = Seed(dim=dim, n=40, diam=diam, unit="d")
            for k in range(40):
                for a in range(dim):
                    c = rng.randrange(3)
                    s.body += [op(5, rng.randrange(32)), op(0, 16 + rng.randrange(4)),
                               op(2, rng.randrange(32))][c]
            seeds[f"tiny_{dim}d_d{diam.replace('^', '')}"] = s

        # diameters whose square just fits, or overflows (then every pair touches)
        for diam in ("sqrtmax", "1.35e154", "max"):
            s = Seed(dim=dim, n=30, diam=diam, unit="d")
            for k in range(30):
                for a in range(dim):
                    s.body += op(0, rng.randrange(32)) if rng.randrange(2) else op(4, rng.randrange(32))
            seeds[f"overflow_{dim}d_{diam}"] = s

        # sparse: a cluster and far outliers (grid too wide: EXTENT for screening and nbs)
        s = Seed(dim=dim, n=50, origin="0")
        for k in range(50):
            for a in range(dim):
                s.body += op(4, rng.randrange(4)) if k % 10 == 9 else op(7) + struct.pack("<H", rng.randrange(65536))
        seeds[f"outliers_{dim}d"] = s

        # all on one line (2D), or one axis (3D)
        s = Seed(dim=dim, n=64, unit="d")
        for k in range(64):
            s.body += op(0, k % 32) + b"".join(op(0, 16) for _ in range(dim - 1))
        seeds[f"line_{dim}d"] = s

        # tight cell budgets, more than 32 elements so that auto does not pick direct
        for budget in (0, 16, 52, 56, 60, 100, 400):
            s = Seed(dim=dim, n=40, budget=BUDGET_U8, budget_value=budget, unit="d/3")
            for k in range(40):
                for a in range(dim):
                    s.body += op(0, 16 + rng.randrange(4))
            seeds[f"budget_{dim}d_{budget}"] = s

        # raw doubles, some of them NaN or infinite (the input is then invalid)
        s = Seed(dim=dim, n=8, reserve=20)
        for k in range(8):
            for a in range(dim):
                v = rng.choice((float("nan"), float("inf"), 1.0, -2.5e-310, 3.0e300)) if k == 5 else rng.uniform(-4, 4)
                s.body += op(6) + raw(v)
        seeds[f"raw_{dim}d"] = s

    # one failing allocation, at each of the first few a run of every algorithm reaches
    for dim in (2, 3):
        for k in (0, 1, 2, 3, 5, 8, 13):
            s = Seed(dim=dim, n=64, fail_at=k, callback=(k % 2 == 1), reserve=(40 if k == 0 else None))
            for i in range(64):
                for a in range(dim):
                    s.body += op(1, 0) if i % 2 else op(7) + struct.pack("<H", rng.randrange(65536))
            seeds[f"nomem_{dim}d_{k}"] = s

    # invalid radii (a denormal diameter halves to 0), and a raw negative radius
    s = Seed(dim=3, n=10, radii=True, diam="5e-324")
    s.body += bytes(10)
    seeds["radius_zero_3d"] = s
    s = Seed(dim=2, n=10, radii=True)
    s.body += bytes([0, 0, 0, 255]) + raw(-1.0) + bytes(6)
    seeds["radius_negative_2d"] = s

    for name, s in seeds.items():
        write("detect", name, s.data())
    return len(seeds)


def sort_seeds():
    rng = random.Random(7)
    n = 0
    for name, pairs in (
        ("small", [(rng.randrange(32), rng.randrange(32)) for _ in range(200)]),
        ("extreme", [(rng.choice((0, 1, 2**31 - 1)), rng.choice((0, 2**31 - 2, 5))) for _ in range(100)]),
        ("sorted", [(i, j) for i in range(20) for j in range(i + 1, 20)]),
        ("reversed", [(i, j) for i in range(20) for j in range(i + 1, 20)][::-1]),
        ("equal", [(7, 9)] * 300),
    ):
        b = b""
        for i, j in pairs:
            for v in (i, j):
                if v < 32:
                    b += bytes([v])
                else:
                    b += bytes([192]) + struct.pack("<I", v)
        write("sort_pairs", name, b)
        n += 1
    return n


if __name__ == "__main__":
    print(f"{detect_seeds()} detect seeds, {sort_seeds()} sort_pairs seeds")
