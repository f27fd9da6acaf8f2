#!/usr/bin/python3
"""Writes the format fixtures of tests/cli/data/formats with VTK itself (Debian's
python3-vtk9, run with /usr/bin/python3), so that the reader is tested on files exactly as VTK
and ParaView write them, and the expected pairs by brute force in Python, independently of
nbs. The outputs are committed; run this again only to change them.

    cd tests/cli/data/formats && /usr/bin/python3 make_fixtures.py
"""
import random
import struct

import vtk

random.seed(20240601)
N = 60
pts = []
rad = []
for k in range(N):
    pts.append((random.uniform(0, 4), random.uniform(0, 4), random.uniform(0, 4)))
    rad.append(random.uniform(0.2, 0.6))
# Two pairs that touch exactly (distance = ri + rj, exact in binary).
pts[10] = (1.0, 1.0, 1.0); rad[10] = 0.25
pts[11] = (1.5, 1.0, 1.0); rad[11] = 0.25
pts[12] = (3.0, 3.0, 3.0); rad[12] = 0.5
pts[13] = (3.0, 3.0, 2.0); rad[13] = 0.5


def pairs(p, r, dim=3):
    out = []
    for i in range(len(p)):
        for j in range(i + 1, len(p)):
            s = 0.0
            for a in range(dim):
                d = p[i][a] - p[j][a]
                s = s + d * d
            rr = r[i] + r[j]
            if s <= rr * rr:
                out.append((i, j))
    return out


def write_pairs(name, pr):
    with open(name, "w") as f:
        for i, j in pr:
            f.write("%d,%d\n" % (i, j))


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


write_pairs("scene.pairs.csv", pairs(pts, rad))
write_pairs("scene2d.pairs.csv", pairs(pts, rad, 2))
p32 = [tuple(f32(c) for c in p) for p in pts]
r32 = [f32(r) for r in rad]
write_pairs("scene32.pairs.csv", pairs(p32, r32))


def polydata(float32=False, name="radius", factor=1.0, scalars=False):
    points = vtk.vtkPoints()
    points.SetDataTypeToFloat() if float32 else points.SetDataTypeToDouble()
    verts = vtk.vtkCellArray()
    for k, p in enumerate(pts):
        points.InsertNextPoint(p)
        verts.InsertNextCell(1)
        verts.InsertCellPoint(k)
    pd = vtk.vtkPolyData()
    pd.SetPoints(points)
    pd.SetVerts(verts)
    arr = vtk.vtkFloatArray() if float32 else vtk.vtkDoubleArray()
    arr.SetName(name)
    for r in rad:
        arr.InsertNextValue(r * factor)
    ids = vtk.vtkIntArray()
    ids.SetName("id")
    vel = vtk.vtkDoubleArray()
    vel.SetName("velocity")
    vel.SetNumberOfComponents(3)
    for k in range(N):
        ids.InsertNextValue(k + 1)
        vel.InsertNextTuple3(k, -k, 0.5)
    pd.GetPointData().AddArray(ids)
    pd.GetPointData().AddArray(vel)
    if scalars:
        pd.GetPointData().SetScalars(arr)
    else:
        pd.GetPointData().AddArray(arr)
    cd = vtk.vtkIntArray()
    cd.SetName("cellid")
    for k in range(N):
        cd.InsertNextValue(k)
    pd.GetCellData().AddArray(cd)
    return pd


def xml(name, pd, mode, encode=True, compress=True, header64=False, big=False, pieces=1,
        writer=vtk.vtkXMLPolyDataWriter):
    w = writer()
    w.SetFileName(name)
    w.SetInputData(pd)
    if mode == "ascii":
        w.SetDataModeToAscii()
    elif mode == "binary":
        w.SetDataModeToBinary()
    else:
        w.SetDataModeToAppended()
        w.SetEncodeAppendedData(1 if encode else 0)
    if not compress:
        w.SetCompressorTypeToNone()
    if header64:
        w.SetHeaderTypeToUInt64()
    if big:
        w.SetByteOrderToBigEndian()
    if pieces > 1:
        w.SetNumberOfPieces(pieces)
    w.Write()


pd = polydata()
xml("vtk_default.vtp", pd, "appended")                                    # VTK's default
xml("paraview_raw_zlib_u64.vtp", pd, "appended", encode=False, header64=True)
xml("appended_raw_none.vtp", pd, "appended", encode=False, compress=False)
xml("appended_base64_none_u64.vtp", pd, "appended", compress=False, header64=True)
xml("binary_zlib.vtp", pd, "binary")
xml("binary_none.vtp", pd, "binary", compress=False)
xml("ascii.vtp", pd, "ascii")
xml("bigendian_raw_zlib.vtp", pd, "appended", encode=False, big=True)
xml("bigendian_binary_none_u64.vtp", pd, "binary", compress=False, header64=True, big=True)
# VTK repeats the whole data set in each piece of an unstreamed input: 3 copies, read one
# after the other.
xml("pieces3_raw_zlib.vtp", pd, "appended", encode=False, pieces=3)
write_pairs("pieces3.pairs.csv", pairs(pts * 3, rad * 3))
xml("float32.vtp", polydata(float32=True), "appended", encode=False)
xml("diameter.vtp", polydata(name="diameter", factor=2.0), "appended", encode=False)

ug = vtk.vtkUnstructuredGrid()
ug.SetPoints(pd.GetPoints())
ug.GetPointData().AddArray(pd.GetPointData().GetArray("radius"))
for k in range(N):
    ug.InsertNextCell(vtk.VTK_VERTEX, 1, [k])
xml("grid.vtu", ug, "appended", encode=False, writer=vtk.vtkXMLUnstructuredGridWriter)


def legacy(name, pd, binary=False, version=None):
    w = vtk.vtkPolyDataWriter()
    w.SetFileName(name)
    w.SetInputData(pd)
    if binary:
        w.SetFileTypeToBinary()
    if version == 42:
        w.SetFileVersion(42)
    w.Write()


legacy("legacy_ascii.vtk", pd)
legacy("legacy_binary.vtk", pd, binary=True)
legacy("legacy42_ascii_scalars.vtk", polydata(scalars=True), version=42)
legacy("legacy42_binary_scalars.vtk", polydata(scalars=True), binary=True, version=42)
legacy("legacy_diameter.vtk", polydata(name="diameter", factor=2.0))

ugw = vtk.vtkUnstructuredGridWriter()
ugw.SetFileName("legacy_grid_binary.vtk")
ugw.SetInputData(ug)
ugw.SetFileTypeToBinary()
ugw.Write()


def fmt(x):
    return repr(x)


# LAMMPS / LIGGGHTS dumps, written by hand in the format of 'dump custom'.
def dump(name, snapshots, columns, box="pp pp pp"):
    with open(name, "w") as f:
        for step, rows in snapshots:
            f.write("ITEM: TIMESTEP\n%d\nITEM: NUMBER OF ATOMS\n%d\n" % (step, len(rows)))
            f.write("ITEM: BOX BOUNDS %s\n0 4\n0 4\n0 4\n" % box)
            f.write("ITEM: ATOMS %s\n" % " ".join(columns))
            for row in rows:
                f.write(" ".join(row) + "\n")


def atoms(order, spread=1.0):
    rows = []
    for k in range(N):
        v = {"id": str(k + 1), "type": "1", "x": fmt(pts[k][0] * spread), "y": fmt(pts[k][1] * spread),
             "z": fmt(pts[k][2] * spread), "radius": fmt(rad[k]), "diameter": fmt(2 * rad[k]),
             "vx": "0", "vy": "0", "vz": "0", "mass": "1",
             "xs": fmt(pts[k][0] / 4.0), "ys": fmt(pts[k][1] / 4.0), "zs": fmt(pts[k][2] / 4.0)}
        rows.append([v[c] for c in order])
    return rows


cols = ["id", "type", "x", "y", "z", "radius"]
dump("liggghts.dump", [(0, atoms(cols))], cols)
other = ["radius", "vx", "z", "id", "vy", "x", "mass", "y", "type", "vz"]
# Three snapshots: the scene spread 3 times wider (other contacts) at steps 0 and 2000, the
# scene itself at step 1000 (index 1), to check that the right one is read.
dump("snapshots.dump", [(0, atoms(other, 3.0)), (1000, atoms(other)), (2000, atoms(other, 3.0))],
     other)
dump("last.dump", [(0, atoms(cols, 3.0)), (500, atoms(cols))], cols)
sp3 = [(p[0] * 3.0, p[1] * 3.0, p[2] * 3.0) for p in pts]
write_pairs("spread3.pairs.csv", pairs(sp3, rad))
dcols = ["id", "type", "diameter", "x", "y", "z"]
dump("diameter.dump", [(0, atoms(dcols))], dcols)
scols = ["id", "type", "xs", "ys", "zs", "radius"]
dump("scaled.dump", [(0, atoms(scols))], scols)

# xs*4 may differ from x in the last bit: the expected pairs of the scaled dump are those
# of the unscaled coordinates, 0 + xs * (4 - 0).
sp = [(0.0 + (p[0] / 4.0) * 4.0, 0.0 + (p[1] / 4.0) * 4.0, 0.0 + (p[2] / 4.0) * 4.0) for p in pts]
write_pairs("scaled.pairs.csv", pairs(sp, rad))
