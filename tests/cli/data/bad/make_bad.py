#!/usr/bin/python3
"""Writes the malformed dump, VTK and VTK XML files of tests/cli/data/bad from the good
fixtures in ../formats. The outputs are committed; test_errors.cmake holds the message and
the exit code each one must give.

    cd tests/cli/data/bad && python3 make_bad.py
"""
import re
import struct
import zlib

F = "../formats/"


def read(name):
    with open(F + name, "rb") as f:
        return f.read()


def write(name, data):
    with open(name, "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


dump = read("liggghts.dump").decode()
lines = dump.split("\n")
# A count no file of this size can hold: refused before allocating.
write("hostile_count.dump", dump.replace("ITEM: NUMBER OF ATOMS\n60", "ITEM: NUMBER OF ATOMS\n999999999999"))
# Fewer atom lines than declared, at the end of the file.
write("truncated.dump", "\n".join(lines[:9 + 30]) + "\n")
# Line 12 (the 3rd atom) with a column missing; a bad number; NaN; a negative radius.
l = lines[:]
l[11] = " ".join(l[11].split()[:-1])
write("columns.dump", "\n".join(l))
l = lines[:]
l[11] = l[11].replace(l[11].split()[3], "0.5x", 1)
write("number.dump", "\n".join(l))
l = lines[:]
l[12] = " ".join(l[12].split()[:4] + ["nan"] + l[12].split()[5:])
write("nan.dump", "\n".join(l))
l = lines[:]
l[13] = " ".join(l[13].split()[:5] + ["-0.25"])
write("negradius.dump", "\n".join(l))
write("noz.dump", dump.replace("ITEM: ATOMS id type x y z radius", "ITEM: ATOMS id type x y q radius"))
write("noradius.dump", dump.replace("ITEM: ATOMS id type x y z radius", "ITEM: ATOMS id type x y z mass"))
write("notimestep.dump", dump.replace("ITEM: TIMESTEP", "ITEM: TIMESTOP", 1))
# More atom lines than declared: the next ITEM is expected where an atom comes.
write("extra.dump", dump.replace("ITEM: NUMBER OF ATOMS\n60", "ITEM: NUMBER OF ATOMS\n59"))

vtk = read("legacy_ascii.vtk").decode()
write("hostile_points.vtk", re.sub(r"POINTS 60 double", "POINTS 2000000000 double", vtk))
write("badkeyword.vtk", vtk.replace("POINT_DATA 60", "POINT_DATTA 60"))
v = vtk.split("\n")
pi = v.index("POINTS 60 double")
v[pi + 1] = v[pi + 1].replace(v[pi + 1].split()[4], "nan", 1)
write("nan.vtk", "\n".join(v))
write("notvtk.vtk", "# vtk DataFlie\n" + vtk.split("\n", 1)[1])
write("noradius.vtk", vtk.replace("radius 1 60 double", "radios 1 60 double"))
binv = read("legacy_binary.vtk")
at = binv.index(b"POINTS 60 double\n") + len(b"POINTS 60 double\n")
write("truncated_binary.vtk", binv[:at + 700])
# A negative radius in the binary FIELD array: its first value.
ra = binv.index(b"radius 1 60 double\n") + len(b"radius 1 60 double\n")
write("negradius_binary.vtk", binv[:ra] + struct.pack(">d", -1.0) + binv[ra + 8:])

raw = read("appended_raw_none.vtp")
write("hostile_points.vtp", raw.replace(b'NumberOfPoints="60"', b'NumberOfPoints="900000000"'))
ascii = read("ascii.vtp").decode()
write("nan.vtp", re.sub(r'(Name="Points"[^>]*>\s*)(\S+)', r"\1nan", ascii, count=1))
write("unterminated.vtp", ascii[:ascii.index("<PointData") + 12])
write("nopoints.vtp", re.sub(r"<Points>.*?</Points>", "", ascii, flags=re.S))
write("lz4.vtp", read("paraview_raw_zlib_u64.vtp").replace(b"vtkZLibDataCompressor", b"vtkLZ4DataCompressor"))
# Appended raw data cut short.
write("truncated_appended.vtp", raw[:raw.index(b"_", raw.index(b"<AppendedData")) + 200])
# A corrupt zlib block in the Points array: bytes flipped after its header (4 words).
z = bytearray(read("paraview_raw_zlib_u64.vtp"))
u = z.index(b"_", z.index(b"<AppendedData")) + 1
pts = z.index(b'Name="Points"')
off = u + int(re.search(rb'offset="(\d+)"', z[pts:]).group(1))
for k in range(off + 40, off + 50):
    z[k] ^= 0x5A
write("corrupt_zlib.vtp", bytes(z))
# A compression header claiming 2^40 blocks for the Points.
z = bytearray(read("paraview_raw_zlib_u64.vtp"))
z[off:off + 8] = struct.pack("<Q", 1 << 40)
write("hostile_blocks.vtp", bytes(z))
# Inline base64 with a character that is not base64.
b64 = read("binary_none.vtp").decode()
i = b64.index('Name="radius" format="binary"')
j = b64.index(">", i) + 1
k = j + b64[j:].index("A") + 12
write("badbase64.vtp", b64[:k] + "*" + b64[k + 1:])
# A header that disagrees with NumberOfPoints.
write("wrongcount.vtp", ascii.replace('NumberOfPoints="60"', 'NumberOfPoints="61"'))
# A negative radius in an ascii array.
write("negradius.vtp", re.sub(r'(Name="radius"[^>]*>\s*)(\S+)', r"\1-0.5", ascii, count=1))
