#!/usr/bin/env python3
"""Writes the seed corpus of the fuzz targets (tests/fuzz/corpus/<target>/).

Each seed is a scene in the byte layout that fuzz_detect.c documents, chosen so that the
fuzzer starts from every adversarial family at once: lattices at exactly the contact
distance and on cell faces, identical points, chains at ri + rj (and one ulp off), huge
offsets up to +-1.7e308, denormal and overflowing diameters, radius ratios of 1e6, tight
cell budgets, pair limits, both sinks, 2D and 3D. The corpus is committed; run this again
only when the layout of fuzz_detect.c (or fuzz_partition.c) changes:
python3 tests/fuzz/make_seeds.py
Files of the corpus this does not write are the fuzzers' findings, kept as regressions:
step_to_front_2d (a time step that moves an element before the first of the last cell order;
nbs__cs_rekey's merge lost it), step_wider_cells_3d (a step after one whose cells took a bit
more of the key: nbs__cs_rekey sorted the old words by the new key's bits);
partition/regress_turned_axes_3d (a crowded core whose grid is stretched along z alone, so
that the keys' rows lie along z: the crowded core's AVX-512 scatter stored the coordinates in
the key's order of the axes, not the caller's); partition/regress_box_past_rows_3d (a core
box whose rows passed the grid's 2^by: the whole key of its highest position spilled y into
z, and an outlier between was put after every element).
"""
import base64
import os
import random
import struct
import zlib

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

        # a flat scene (3D: a layer two cells deep; 2D: a strip) under budgets around its
        # heads: NBS lays its layers (rows) along a wide axis, whose heads the budget counts
        # (their own generator, so that the seeds after them stay as they were)
        frng = random.Random(20261124 + dim)
        for budget in (800, 900, 1000, 1050, 1100, 1200):
            s = Seed(dim=dim, n=64, budget=BUDGET_U16, budget_value=budget, unit="d")
            for k in range(64):
                s.body += op(0, frng.randrange(32))
                if dim == 3:
                    s.body += op(0, frng.randrange(32))
                s.body += op(0, 16 + frng.randrange(2))
            seeds[f"budget_flat_{dim}d_{budget}"] = s

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

    # NBS's folded axes: a crowded lattice and one element far out at either end of every
    # axis (outside the core NBS measures), so that each axis is folded onto a few lists;
    # the lattice's origin moves it across the wrap-around from list m - 1 to list 0
    for dim in (2, 3):
        for unit in ("d", "d/2"):
            for origin in ("0", "0.5", "1"):
                s = Seed(dim=dim, n=60, unit=unit, origin=origin)
                for k in range(58):
                    for a in range(dim):
                        s.body += lattice(k, a, 8 if dim == 2 else 4)
                for v in (-5000.0, 7000.3):
                    for a in range(dim):
                        s.body += op(6) + raw(v + 0.37 * a)
                seeds[f"folded_{dim}d_{unit.replace('/', '_')}_{origin}"] = s

    # cellsort's crowded core (nbs__cs_core): a crowd, chains touching across it, and as
    # many elements far out as the core box may leave out (the sample's 1 / (16 dim)), so far
    # that the keys need more bits than a word has beside the element (about 60 of 64)
    # while the crowd's would fit: the core is sorted apart and merged with the outliers.
    # The tail variant stretches the crowd along x over 32 cells. With 64 elements the
    # histogram's bins are far wider than the crowd, so the core box's face does not cut it
    # here; test_agreement's core scene does that, and the fuzzer may find others.
    crng = random.Random(20261124)
    for dim in (2, 3):
        far = 2.6e8 if dim == 2 else 1.1e6
        for variant in ("crowd", "tail", "radii"):
            s = Seed(dim=dim, n=64, unit="d/2" if variant != "tail" else "d",
                     radii=(variant == "radii"))
            if variant == "radii":
                s.body += bytes(crng.choice((0, 2, 3, 4)) for _ in range(64))
            outliers = 2 if dim == 2 else 1
            for k in range(64 - outliers):
                for a in range(dim):
                    if k and crng.randrange(3) == 0:
                        s.body += op(crng.choice((2, 3)), crng.randrange(32))
                    elif variant == "tail" and a == 0 and k % 8 == 7:
                        s.body += op(0, crng.randrange(32))
                    else:
                        s.body += op(7) + struct.pack("<H", crng.randrange(16384))
            for k in range(outliers):
                for a in range(dim):
                    s.body += op(6) + raw((far if k == 0 else -far) * (1.0 + 0.01 * a))
            seeds[f"core_{dim}d_{variant}"] = s

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


# ---- fuzz_readers: 3 option bytes (see fuzz_readers.c), then a file -------------------

R_MODE = {"read": 0, "csv": 1, "f64": 2, "dump": 3, "vtk": 4, "vtp": 5, "stdin": 6, "all": 7}
R_DIMS = {0: 0, 2: 1, 3: 2, "each": 3}
R_DUMP = {0: 0, 1: 1, 2: 2, "last": 3, "t0": 4, "t1000": 5, "t1": 6, 7: 7}
R_COLUMNS = {None: 0, "1,2": 1, "1,2,3": 2, "1,2,3,4": 3, "x,y,z,radius": 4, "5,4,3,2": 5,
             "px,py,rad": 6, "x,y,diameter": 7}
R_RADIUS = {None: 0, "radius": 1, "diameter": 2, "mass": 3}
R_DIAM = {1.0: 0, 0.5: 1, 2.0: 2, 2.6: 3, 1e-3: 4}
R_EXT = ["", ".csv", ".txt", ".xyz", ".f64", ".bin", ".raw", ".vtk", ".vtp", ".vtu", ".dump",
         ".lammpstrj", ".liggghts", ".CSV", ".VTK", ".dat"]


def partition_seeds():
    """Seeds of fuzz_partition (the layout of fuzz_partition.c): scenes large enough for the
    partitions, uniform and on the lattice, 2D and 3D, with and without radii, with outliers
    far out that stretch the grid (the crowded core's partition) and just past the box."""

    def scene(flags, n, frac, seed, groups):
        b = bytes([flags]) + struct.pack("<HBI", (n - 1024) % 64513, frac, seed)
        b += bytes([len(groups)])
        for g in groups:
            b += bytes(g)
        return b

    TD, RADII, CAND, STEP, LATTICE, CONSEC = 1, 2, 4, 128, 32, 64

    def threads(t):
        return (t - 1) << 3

    # group: (axis | below << 2, distance, count - 1, gap index | chain axis << 2, where)
    far = [(0, 0x80 | 20, 4, 1, 0), (1 | 4, 0x80 | 20, 4, 2, 0), (2, 0x80 | 20, 3, 0, 1)]
    near = [(0, 10, 30, 2 | 1 << 2, 1), (0, 40, 20, 1 | 2 << 2, 3)]
    seeds = {
        "uniform_2d": scene(0, 60000, 0, 1, []),
        "uniform_3d": scene(TD, 60000, 0, 2, []),
        "lattice_radii_2d_step": scene(RADII | LATTICE | STEP | threads(2), 50000, 0, 3, []),
        "core_3d": scene(TD, 60000, 0, 4, far),
        "core_2d_radii": scene(RADII | threads(3), 60000, 0, 5, far[:2]),
        "core_near_3d_step": scene(TD | STEP | threads(2), 60000, 0, 6, far + near),
        "core_consecutive_3d": scene(TD | CONSEC | CAND, 40000, 0, 7, far),
        "sparse_3d": scene(TD, 30000, 4, 8, far[:1]),
    }
    for name, b in seeds.items():
        write("partition", name, b)
    return len(seeds)


def ropts(mode, dims="each", diameter=None, both=True, also_file=False, dump=0, columns=None,
          radius=None, diam=2.0, ext=""):
    b0 = R_MODE[mode] | R_DIMS[dims] << 3 | (32 if diameter else 0) | (64 if both else 0)
    b0 |= 128 if also_file else 0
    b1 = R_DUMP[dump] | R_COLUMNS[columns] << 3 | R_RADIUS[radius] << 6
    b2 = R_DIAM[diam] | R_EXT.index(ext) << 4
    return bytes([b0, b1, b2])


def vtp_binary(values, fmt, hsize=4, big=False, z=False, split=True):
    """The bytes of a VTK XML binary array: header + data, optionally zlib in blocks."""
    e = ">" if big else "<"
    data = struct.pack(e + fmt * len(values), *values)
    hw = "Q" if hsize == 8 else "I"
    if not z:
        return struct.pack(e + hw, len(data)), data
    bs = 32
    blocks = [data[k:k + bs] for k in range(0, len(data), bs)] or [b""]
    comp = [zlib.compress(b) for b in blocks]
    last = len(blocks[-1]) if len(blocks[-1]) != bs else 0
    head = struct.pack(e + hw * (3 + len(comp)), len(comp), bs, last, *[len(c) for c in comp])
    return head, b"".join(comp)


def vtp_file(points, radii, enc="ascii", z=False, hsize=4, big=False, ptype="Float64",
             rtype="Float64", rname="radius", kind="PolyData", pieces=1, comment=False):
    """A small .vtp / .vtu in one of the encodings: ascii, binary (base64 inline), raw or
    base64 appended."""
    pf = {"Float64": "d", "Float32": "f", "Int32": "i", "Int8": "b", "UInt16": "H"}
    flat = [c for p in points for c in p]
    attrs = 'type="%s" version="1.0" byte_order="%s"' % (kind, "BigEndian" if big else "LittleEndian")
    if hsize == 8:
        attrs += ' header_type="UInt64"'
    if z:
        attrs += ' compressor="vtkZLibDataCompressor"'
    appended = b""
    arrays = []
    for name, vals, t, nc in (("points", flat, ptype, 3), (rname, radii, rtype, 1)):
        if t.startswith("Int") or t.startswith("UInt"):
            vals = [int(v) for v in vals]
        head = '<DataArray type="%s" Name="%s" NumberOfComponents="%d" ' % (t, name, nc)
        if enc == "ascii":
            body = " ".join(repr(v) for v in vals)
            arrays.append(head + 'format="ascii">\n%s\n</DataArray>' % body)
        elif enc == "binary":
            h, d = vtp_binary(vals, pf[t], hsize, big, z)
            body = (base64.b64encode(h) + base64.b64encode(d)).decode()
            arrays.append(head + 'format="binary">\n%s\n</DataArray>' % body)
        else:
            h, d = vtp_binary(vals, pf[t], hsize, big, z)
            chunk = h + d
            if enc == "appended64":
                chunk = base64.b64encode(h) + base64.b64encode(d)
            arrays.append(head + 'format="appended" offset="%d"/>' % len(appended))
            appended += chunk
    out = '<?xml version="1.0"?>\n'
    if comment:
        out += "<!-- written by hand -->\n"
    out += "<VTKFile %s>\n<%s>\n" % (attrs, kind)
    for _ in range(pieces):
        out += '<Piece NumberOfPoints="%d" NumberOfCells="0">\n' % len(points)
        out += "<PointData>%s</PointData>\n<Points>%s</Points>\n</Piece>\n" % (arrays[1], arrays[0])
    out += "</%s>\n" % kind
    out = out.encode()
    if enc.startswith("appended"):
        out += b'<AppendedData encoding="%s">\n_' % (b"base64" if enc == "appended64" else b"raw")
        out += appended + b"\n</AppendedData>\n"
    return out + b"</VTKFile>\n"


def vtk_file(points, radii, binary=False, version="2.0", cells="", extra=b"", radius="SCALARS"):
    """A small legacy .vtk file."""
    out = b"# vtk DataFile Version %s\nhand made\n%s\nDATASET POLYDATA\n" % (
        version.encode(), b"BINARY" if binary else b"ASCII")
    flat = [c for p in points for c in p]
    out += b"POINTS %d double\n" % len(points)
    if binary:
        out += struct.pack(">%dd" % len(flat), *flat) + b"\n"
    else:
        out += " ".join(repr(v) for v in flat).encode() + b"\n"
    out += cells.encode()
    out += b"POINT_DATA %d\n" % len(points)
    if radius == "SCALARS":
        out += b"SCALARS radius double 1\nLOOKUP_TABLE default\n"
    else:
        out += b"FIELD FieldData 1\nradius 1 %d double\n" % len(points)
    if binary:
        out += struct.pack(">%dd" % len(radii), *radii) + b"\n"
    else:
        out += " ".join(repr(v) for v in radii).encode() + b"\n"
    return out + extra


def dump_file(snapshots, columns="id type x y z radius", box="pp pp pp", bounds=None,
              time=False):
    """A small LAMMPS dump: snapshots is a list of (timestep, rows)."""
    out = ""
    for step, rows in snapshots:
        if time:
            out += "ITEM: UNITS\nsi\nITEM: TIME\n0.5\n"
        out += "ITEM: TIMESTEP\n%d\nITEM: NUMBER OF ATOMS\n%d\n" % (step, len(rows))
        out += "ITEM: BOX BOUNDS %s\n" % box
        out += "".join(b + "\n" for b in (bounds or ["0 4", "0 4", "0 4"]))
        out += "ITEM: ATOMS %s\n" % columns
        out += "".join(" ".join(str(v) for v in r) + "\n" for r in rows)
    return out.encode()


def reader_seeds():
    """Seeds of fuzz_readers: every file of tests/cli/data (read by cli_read with its name,
    and by its format's reader on memory and a file), and small hand-made files of every
    format and encoding."""
    data = os.path.join(HERE, "..", "cli", "data")
    fmt_of = {".csv": "csv", ".txt": "csv", ".f64": "f64", ".dump": "dump", ".vtk": "vtk",
              ".vtp": "vtp", ".vtu": "vtp"}
    seeds = {}
    for sub in ("golden", "formats", "bad"):
        for name in sorted(os.listdir(os.path.join(data, sub))):
            base, ext = os.path.splitext(name)
            if ext not in fmt_of or name.endswith(".pairs.csv") and name != "scene.pairs.csv":
                continue
            with open(os.path.join(data, sub, name), "rb") as f:
                body = f.read()
            kw = {}
            if base == "named3d":
                kw["columns"] = "5,4,3,2"
            if base in ("snapshots", "last"):
                kw["dump"] = "last"
            if base == "pieces3_raw_zlib" or base == "scene.pairs":
                kw["diam"] = 1e-3
            key = "%s_%s" % (sub, name.replace(".", "_"))
            # cli_read with the file's name, compared with the reader of the format it
            # recognises on the bytes in memory; raw f64 also on a regular file.
            seeds[key] = ropts("read", ext=ext, **kw) + body
            if ext == ".f64":
                seeds[key + "_file"] = ropts("f64", also_file=True, **kw) + body
    seeds["golden_snapshots_timestep"] = ropts("dump", dump="t1000") + open(
        os.path.join(data, "formats", "snapshots.dump"), "rb").read()

    # CSV
    seeds["csv_bom_semicolons"] = ropts("read", ext=".csv") + (
        b"\xef\xbb\xbfx;y;z;diameter\n0;0;0;1\n1;0;0;1\n0;2;0;2\n")
    seeds["csv_blanks_comments"] = ropts("csv", dims=2, diameter=True, both=False, diam=1.0) + (
        b"# a lattice\n0 0\n1\t0\n\n  # comment\n0 1\n1 1  \n")
    seeds["csv_quoted_header_crlf"] = ropts("csv") + b'"x","y","r"\r\n0,0,0.5\r\n1,0,0.5\r\n'
    seeds["csv_hex_and_nan"] = ropts("csv", dims=2) + b"0x1p-3,1e-308,0x1.8p1\n1,2,nan(12)\n"
    seeds["csv_infinity"] = ropts("csv", dims=3) + b"1,2,3,4\n1,2,infinity,4\n"
    seeds["csv_columns_names"] = ropts("csv", dims=2, columns="px,py,rad") + (
        b"id,px,py,pz,rad\n1,0,0,0,0.5\n2,1,0,0,0.5\n")
    seeds["csv_columns_index"] = ropts("csv", dims=3, columns="1,2,3,4") + (
        b"0,0,0,1,9\n2,0,0,1,9\n")
    seeds["csv_xy_no_z"] = ropts("csv", dims=3) + b"x,y,radius\n0,0,1\n"
    seeds["csv_ragged"] = ropts("csv", dims=2) + b"0,0,1\n1,1\n2,2,2,2\n"
    seeds["csv_diameter_header"] = ropts("csv", columns="x,y,diameter", dims=2) + (
        b"x,y,diameter\n0,0,1\n1,0,1\n")
    seeds["csv_tiny_radii"] = ropts("csv", dims=2) + b"0,0,5e-324\n1e300,-1e300,1.7e308\n"
    seeds["csv_many_columns"] = ropts("csv", dims=3) + (",".join(["1"] * 40) + "\n").encode()

    # raw f64
    seeds["f64_2d"] = ropts("f64") + struct.pack("<6d", 0, 0, 0.5, 1, 0, 0.5)
    seeds["f64_3d_diameter"] = ropts("f64", dims=3, diameter=True, both=False) + struct.pack(
        "<6d", 0, 0, 0, 1, 1, 1)
    seeds["f64_nan_radius"] = ropts("f64", dims=2) + struct.pack("<6d", 0, 0, 1, 0, 0, float("nan"))
    seeds["f64_negative_zero"] = ropts("f64", dims=3, also_file=True) + struct.pack(
        "<4d", 0, 0, 0, -0.0)
    seeds["f64_denormal"] = ropts("f64", dims=2, also_file=True) + struct.pack(
        "<3d", 5e-324, -5e-324, 5e-324)
    seeds["f64_truncated"] = ropts("f64", dims=3) + struct.pack("<5d", 1, 2, 3, 4, 5) + b"\x01"

    # dumps
    rows = [(1, 1, 0.5, 0.5, 0.5, 0.25), (2, 1, 1.0, 0.5, 0.5, 0.25)]
    seeds["dump_minimal"] = ropts("dump") + dump_file([(0, rows)])
    seeds["dump_three_snapshots"] = ropts("dump", dump=2) + dump_file(
        [(0, rows), (1, rows[:1]), (1000, rows)], time=True)
    seeds["dump_timestep1"] = ropts("dump", dump="t1") + dump_file([(0, rows), (1, rows[:1])])
    seeds["dump_last"] = ropts("dump", dump="last") + dump_file([(0, rows), (5, rows[::-1])])
    # Regression: with --dim 2, xs and ys of a cell tilted in z were unscaled without zs
    # (found by this target; fixed in apps/read_dump.c).
    seeds["dump_triclinic_scaled"] = ropts("dump") + dump_file(
        [(0, [(1, 1, 0.1, 0.2, 0.3, 0.5), (2, 1, 0.9, 0.8, 0.7, 0.5)])],
        columns="id type xs ys zs radius", box="xy xz yz pp pp pp",
        bounds=["-0.5 4.5 0.5", "0 4 -0.5", "0 4 0.25"])
    # Regression: a file ending without a newline inside a snapshot was reported at a line
    # past its end (found by this target; fixed in apps/read_dump.c).
    seeds["dump_truncated_no_newline"] = ropts("dump") + dump_file(
        [(0, rows + rows)])[:-len(b"2 1 1.0 0.5 0.5 0.25\n") - 1]
    seeds["dump_atom_style"] = ropts("dump", diameter=True, both=False) + dump_file(
        [(0, [(1, 1, 0.1, 0.2, 0.3), (2, 1, 0.9, 0.8, 0.7)])], columns="id type xs ys zs")
    seeds["dump_diameter_unwrapped"] = ropts("dump", radius="diameter") + dump_file(
        [(0, [(1, 1, -4.5, 0.5, 9, 0.5), (2, 1, -4, 0.5, 9, 0.5)])],
        columns="id type xu yu zu diameter")
    seeds["dump_2d_mass"] = ropts("dump", dims=2, radius="mass") + dump_file(
        [(0, [(1, 2, 0.5, 0.5, 1.0), (2, 2, 1.0, 0.5, 1.5)])], columns="id type x y mass")

    # legacy VTK
    pts = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 2.5, 0.0)]
    rad = [0.5, 0.5, 1.0]
    seeds["vtk_ascii"] = ropts("vtk") + vtk_file(pts, rad, cells="VERTICES 3 6\n1 0\n1 1\n1 2\n")
    seeds["vtk_binary"] = ropts("vtk", also_file=True) + vtk_file(pts, rad, binary=True)
    seeds["vtk_51_offsets"] = ropts("vtk") + vtk_file(
        pts, rad, version="5.1", cells="VERTICES 4 3\nOFFSETS vtktypeint64\n0 1 2 3\n"
        "CONNECTIVITY vtktypeint64\n0 1 2\nMETADATA\nINFORMATION 0\n\n")
    seeds["vtk_field"] = ropts("vtk", radius="radius") + vtk_file(
        pts, rad, radius="FIELD",
        extra=b"VECTORS v float\n0 0 0 1 1 1 2 2 2\nCOLOR_SCALARS c 2\n0 1 0 1 0 1\n"
              b"TEXTURE_COORDINATES t 2 float\n0 0 1 1 2 2\n")
    seeds["vtk_lookup_table"] = ropts("vtk") + vtk_file(
        pts, rad, extra=b"SCALARS s int 1\nLOOKUP_TABLE mytable\n1 2 3\n"
                        b"LOOKUP_TABLE mytable 2\n0 0 0 1 1 1 1 1\nNORMALS n double\n"
                        b"1 0 0 0 1 0 0 0 1\nCELL_DATA 0\n")
    seeds["vtk_unstructured_binary"] = ropts("vtk") + (
        b"# vtk DataFile Version 4.2\nt\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 2 float\n"
        + struct.pack(">6f", 0, 0, 0, 1, 0, 0) + b"\nCELLS 2 4\n" + struct.pack(">4i", 1, 0, 1, 1)
        + b"\nCELL_TYPES 2\n" + struct.pack(">2i", 1, 1) + b"\nPOINT_DATA 2\n"
        b"SCALARS diameter float\nLOOKUP_TABLE default\n" + struct.pack(">2f", 1, 1) + b"\n")
    # Regression: a file of two lines was refused at line 3 (found by this target; fixed in
    # apps/read_vtk.c).
    seeds["vtk_no_third_line"] = ropts("vtk") + b"# vtk DataFile Version 2.0\ntitle"
    seeds["vtk_binary_integers"] = ropts("vtk") + (
        b"# vtk DataFile Version 3.0\ni\nBINARY\nDATASET POLYDATA\nPOINTS 2 short\n"
        + struct.pack(">6h", -3, 0, 0, -2, 0, 0) + b"\nPOINT_DATA 2\nSCALARS radius unsigned_char\n"
        b"LOOKUP_TABLE default\n\x01\x02\nTENSORS t vtktypeuint64\n" + bytes(144)
        + b"\nTENSORS6 t6 unsigned_int\n" + bytes(48) + b"\nGLOBAL_IDS g long\n" + bytes(16) + b"\n")
    seeds["vtk_structured"] = ropts("vtk", diameter=True, both=False) + (
        b"# vtk DataFile Version 3.0\ng\nASCII\nDATASET STRUCTURED_GRID\nDIMENSIONS 2 1 1\n"
        b"POINTS 2 float\n0 0 0 1 0 0\n")

    # VTK XML
    for enc in ("ascii", "binary", "appended", "appended64"):
        for z in (False, True):
            if enc == "ascii" and z:
                continue
            for hsize in (4, 8):
                name = "vtp_%s%s_h%d" % (enc, "_zlib" if z else "", hsize)
                seeds[name] = ropts("vtp") + vtp_file(pts, rad, enc=enc, z=z, hsize=hsize)
    seeds["vtp_bigendian_float32"] = ropts("vtp") + vtp_file(
        pts, rad, enc="binary", big=True, ptype="Float32", rtype="Float32")
    seeds["vtp_int_types"] = ropts("vtp") + vtp_file(
        [(0, 0, 0), (1, 0, 0)], [1, 2], enc="appended", ptype="Int8", rtype="UInt16")
    seeds["vtp_pieces_diameter"] = ropts("vtp", radius="diameter") + vtp_file(
        pts, [1.0, 1.0, 2.0], enc="binary", z=True, rname="diameter", pieces=3, comment=True)
    seeds["vtu_read"] = ropts("read", ext=".vtu") + vtp_file(
        pts, rad, enc="appended", z=True, kind="UnstructuredGrid")
    # Regression: an ascii value that is not a number was quoted with the 20 bytes after it,
    # newlines included, and names from the file were printed as they are: messages of more
    # than one line (found by this target; fixed in apps/read_vtp.c).
    seeds["vtp_ascii_not_a_number"] = ropts("vtp") + vtp_file(pts, rad, enc="ascii").replace(
        b"0.0 0.0 0.0", b"0.0 0.0x\n0.0", 1)
    vtp = vtp_file(pts, rad, enc="binary").replace(b'Name="points"', b'Name="po\nints"', 1)
    head, tail = vtp.rsplit(b'format="binary">\n', 1)
    seeds["vtp_name_newline"] = ropts("vtp") + head + b'format="binary">\n!' + tail
    # Regression: a zlib block of compressed size 0 was read with memcpy(NULL, ..., 0),
    # undefined behaviour (found by this target; fixed in apps/read_vtp.c).
    seeds["vtp_zlib_empty_block"] = ropts("vtp") + (
        b'<?xml version="1.0"?>\n<VTKFile type="PolyData" version="1.0" '
        b'byte_order="LittleEndian" compressor="vtkZLibDataCompressor">\n<PolyData>'
        b'<Piece NumberOfPoints="1">\n<PointData><DataArray type="Float64" Name="radius" '
        b'format="appended" offset="0"/></PointData>\n<Points><DataArray type="Float64" '
        b'NumberOfComponents="3" format="appended" offset="16"/></Points>\n</Piece>'
        b'</PolyData>\n<AppendedData encoding="raw">_' + struct.pack("<4I", 1, 8, 0, 0)
        + b"".join(vtp_binary([0.0, 0.0, 0.0], "d", z=True)) + b"\n</AppendedData></VTKFile>\n")
    seeds["vtp_all_readers"] = ropts("all") + vtp_file(pts, rad, enc="ascii")

    # the format from the content, the name and standard input
    seeds["read_noext_dump"] = ropts("read") + dump_file([(0, rows)])
    seeds["read_txt_vtk"] = ropts("read", ext=".txt") + vtk_file(pts, rad)
    seeds["stdin_csv"] = ropts("stdin") + b"x,y,r\n0,0,1\n1,1,1\n"
    seeds["stdin_f64"] = ropts("stdin", dims=2) + struct.pack("<3d", 0, 0, 1)
    seeds["all_readers_csv"] = ropts("all") + b"x,y,r\n0,0,1\n"
    # Regression: an empty standard input was read as one byte of uninitialised memory
    # (found by this target; fixed in apps/read.c).
    seeds["regress_stdin_empty"] = ropts("stdin", dims=3)

    for name, b in seeds.items():
        write("readers", name, b)
    return len(seeds)


if __name__ == "__main__":
    print(f"{detect_seeds()} detect seeds, {partition_seeds()} partition seeds, "
          f"{sort_seeds()} sort_pairs seeds, {reader_seeds()} readers seeds")
