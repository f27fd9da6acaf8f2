#!/usr/bin/python3
"""VTK itself (Debian's python3-vtk9) reads the .vtp files the nbs tool writes, in every
encoding, and finds in them what the tool says it wrote: the points, one vertex per point,
one line per contact joining the right elements, and the radii. Exit 77 (skipped) without
VTK.

    test_vtk.py NBS WORKDIR
"""
import json
import os
import subprocess
import sys

try:
    import vtk
except ImportError:
    print("python3-vtk9 is not installed: skipped")
    sys.exit(77)

nbs, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)
failures = 0
checks = 0


def run(*args):
    p = subprocess.run([nbs, *args], capture_output=True, text=True, cwd=work)
    if p.returncode != 0:
        raise SystemExit("nbs %s failed (%d): %s" % (" ".join(args), p.returncode, p.stderr))
    return p


def check(what, got, want):
    global failures, checks
    checks += 1
    if got != want:
        failures += 1
        print("FAILED: %s: got %r, expected %r" % (what, got, want))


def read_vtp(path):
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    if r.GetErrorCode() != 0:
        raise SystemExit("VTK cannot read %s" % path)
    return r.GetOutput()


def lines_of(pd):
    out = []
    cells = pd.GetLines()
    ids = vtk.vtkIdList()
    cells.InitTraversal()
    while cells.GetNextCell(ids):
        out.append(tuple(ids.GetId(k) for k in range(ids.GetNumberOfIds())))
    return out


for dim in (2, 3):
    scene = "scene%d.csv" % dim
    run("generate", "wide", "--dim", str(dim), "--n", "3000", "--size-ratio", "4", "--output", scene)
    run("detect", "--input", scene, "--output", "pairs%d.csv" % dim)
    with open(os.path.join(work, "pairs%d.csv" % dim)) as f:
        pairs = [tuple(int(v) for v in l.split(",")) for l in f if l.strip()]
    with open(os.path.join(work, scene)) as f:
        rows = [l.strip().split(",") for l in f][1:]
    radii = [float(r[-1]) for r in rows]
    coords = [[float(v) for v in r[:dim]] for r in rows]
    for enc in ("appended", "base64", "ascii"):
        for comp in ((), ("--no-compress",)):
            if enc == "ascii" and comp:
                continue
            name = "net%d_%s%s.vtp" % (dim, enc, "_raw" if comp else "")
            run("detect", "--input", scene, "--vtp", name, "--vtp-encoding", enc, *comp)
            pd = read_vtp(os.path.join(work, name))
            tag = "%dD %s%s" % (dim, enc, " uncompressed" if comp else "")
            check(tag + ": points", pd.GetNumberOfPoints(), len(rows))
            check(tag + ": verts", pd.GetNumberOfVerts(), len(rows))
            check(tag + ": lines = contacts", lines_of(pd), pairs)
            arr = pd.GetPointData().GetArray("radius")
            check(tag + ": radius array", [arr.GetValue(k) for k in range(arr.GetNumberOfTuples())],
                  radii)
            cnt = pd.GetPointData().GetArray("contacts")
            deg = [0] * len(rows)
            for i, j in pairs:
                deg[i] += 1
                deg[j] += 1
            check(tag + ": contacts array", [int(cnt.GetValue(k)) for k in range(len(rows))], deg)
            p = pd.GetPoint(len(rows) // 2)
            check(tag + ": a point", list(p[:dim]) + list(p[dim:]),
                  coords[len(rows) // 2] + [0.0] * (3 - dim))
    # generate writes element sets that VTK reads too.
    run("generate", "wide", "--dim", str(dim), "--n", "3000", "--size-ratio", "4", "--output",
        "gen%d.vtp" % dim)
    pd = read_vtp(os.path.join(work, "gen%d.vtp" % dim))
    check("generate %dD: points" % dim, pd.GetNumberOfPoints(), len(rows))
    check("generate %dD: no lines" % dim, pd.GetNumberOfLines(), 0)
    lr = vtk.vtkPolyDataReader()
    run("generate", "wide", "--dim", str(dim), "--n", "3000", "--size-ratio", "4", "--output",
        "gen%d.vtk" % dim)
    lr.SetFileName(os.path.join(work, "gen%d.vtk" % dim))
    lr.Update()
    lpd = lr.GetOutput()
    check("generate %dD legacy: points" % dim, lpd.GetNumberOfPoints(), len(rows))
    arr = lpd.GetPointData().GetArray("radius")
    check("generate %dD legacy: radii" % dim, [arr.GetValue(k) for k in range(arr.GetNumberOfTuples())],
          radii)

# The demo's file.
p = run("demo", "--n", "3000", "--subsample", "1000", "--repeat", "1", "--out", "demo", "-q",
        "--png-size", "64")
line = [l for l in p.stdout.splitlines() if "demo3d.vtp" in l][0]
words = line.split()
points, contacts = int(words[2]), int(words[words.index("contacts") - 1])
pd = read_vtp(os.path.join(work, "demo", "demo3d.vtp"))
check("demo: points", pd.GetNumberOfPoints(), points)
check("demo: lines", pd.GetNumberOfLines(), contacts)
png = vtk.vtkPNGReader()
png.SetFileName(os.path.join(work, "demo", "demo2d.png"))
png.Update()
check("demo: PNG size", png.GetOutput().GetDimensions()[:2], (64, 64))

print("%d passed, %d failed" % (checks - failures, failures))
sys.exit(1 if failures else 0)
