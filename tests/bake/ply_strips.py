#!/usr/bin/env python3
"""ply_strips.py MESH.obj OUT_DIR: writes the OBJ's triangles as PLY files of the same mesh, for
tests/bake/mesh_cli_tests.sh: OUT_DIR/{faces,strips}-{ascii,binary}/m.ply, a face list and a
`tristrips` element (one list, -1 between strips, a degenerate strip first), ASCII and binary
little-endian. The strips are greedy: a triangle extends the strip when one of its rotations is
what the alternating winding gives; the face list holds each triangle as its strip gives it, so
both files describe the same triangles in the same order."""
import os
import struct
import sys

verts, tris = [], []
for line in open(sys.argv[1]):
    w = line.split()
    if w and w[0] == "v":
        verts.append(tuple(struct.unpack("<f", struct.pack("<f", float(x)))[0] for x in w[1:4]))
    elif w and w[0] == "f":
        idx = [int(t.split("/")[0]) - 1 for t in w[1:]]
        for i in range(1, len(idx) - 1):
            tris.append((idx[0], idx[i], idx[i + 1]))

strips = [[0, 0, 1]]  # one degenerate triangle only: skipped
faces = []


def rotations(t):
    return [t[k:] + t[:k] for k in range(3)]


def extends(s, t):
    """The rotation of t that the strip s gives next, or None."""
    i = len(s) - 2
    edge = (s[i], s[i + 1]) if i % 2 == 0 else (s[i + 1], s[i])
    match = [r for r in rotations(t) if (r[0], r[1]) == edge]
    return match[0] if match else None


for n, t in enumerate(tris):
    r = extends(strips[-1], t) if len(strips) > 1 else None
    if r:
        strips[-1].append(r[2])
        faces.append(r)
        continue
    # A new strip, turned so that the next triangle can extend it.
    start = rotations(t)
    if n + 1 < len(tris):
        start.sort(key=lambda r: extends(list(r), tris[n + 1]) is None)
    strips.append(list(start[0]))
    faces.append(start[0])
tris = faces
flat = []
for s in strips:
    flat += s + [-1]
flat.pop()


def write(path, binary, element):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    head = ["ply", "format " + ("binary_little_endian" if binary else "ascii") + " 1.0",
            "element vertex %d" % len(verts), "property float x", "property float y", "property float z"]
    if element == "face":
        head += ["element face %d" % len(tris), "property list uchar int vertex_indices"]
    else:
        head += ["element tristrips 1", "property list int int vertex_indices"]
    with open(path, "wb") as f:
        f.write(("\n".join(head + ["end_header"]) + "\n").encode())
        for v in verts:
            f.write(struct.pack("<3f", *v) if binary else ("%r %r %r\n" % v).encode())
        rows = [[3] + list(t) for t in tris] if element == "face" else [[len(flat)] + flat]
        for r in rows:
            if binary:
                f.write(struct.pack("<B" if element == "face" else "<i", r[0]) + struct.pack("<%di" % (len(r) - 1), *r[1:]))
            else:
                f.write((" ".join(map(str, r)) + "\n").encode())


for kind in ("ascii", "binary"):
    write(os.path.join(sys.argv[2], "faces-" + kind, "m.ply"), kind == "binary", "face")
    write(os.path.join(sys.argv[2], "strips-" + kind, "m.ply"), kind == "binary", "tristrips")
print(len(tris), len(strips) - 1)
