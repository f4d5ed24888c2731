#!/usr/bin/env python3
"""Write Mitsuba's `serialized` mesh files (format version 4, or 3 with --v3), for tests.

usage: write_serialized.py OUT.serialized [--v3]
       write_serialized.py --bad DIR

Writes the two meshes of tests/data/mitsuba/features/mesh.serialized: shape 0 a tetrahedron
(positions only), shape 1 an octahedron with per-vertex normals and texture coordinates.
The layout follows Mitsuba 3's src/shapes/serialized.cpp (`load_legacy`): per mesh the
uncompressed header (uint16 0x041C, uint16 version), then a zlib stream holding the flags
(uint32: 0x1 normals, 0x2 texture coordinates, 0x1000 single precision), the shape's name
(NUL-terminated, version 4 only), the vertex and triangle counts (uint64), positions,
normals, texture coordinates (float32) and the triangles (3 uint32 each); after the last
mesh the offset of each mesh (uint64 in version 4, uint32 in version 3) and their count
(uint32). Little endian throughout. Needs only the standard library.
"""
import struct, sys, zlib

HAS_NORMALS, HAS_TEXCOORDS, SINGLE = 0x1, 0x2, 0x1000


def mesh_bytes(version, name, positions, faces, normals=None, uvs=None):
    flags = SINGLE | (HAS_NORMALS if normals else 0) | (HAS_TEXCOORDS if uvs else 0)
    body = struct.pack("<I", flags)
    if version == 4:
        body += name.encode() + b"\0"
    body += struct.pack("<QQ", len(positions), len(faces))
    for arr in (positions, normals, uvs):
        for v in arr or []:
            body += struct.pack("<%df" % len(v), *v)
    for f in faces:
        body += struct.pack("<3I", *f)
    return struct.pack("<HH", 0x041C, version) + zlib.compress(body)


def tetrahedron():
    p = [(1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)]
    f = [(0, 1, 2), (0, 3, 1), (0, 2, 3), (1, 3, 2)]
    return p, f


def octahedron():
    p = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    f = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4),
         (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
    # Normals of the sphere through the vertices (smooth shading), planar uvs.
    uv = [(0.5 * x + 0.5, 0.5 * z + 0.5) for x, y, z in p]
    return p, f, list(p), uv


def bad_corpus(d):
    """The broken files of tests/bad-inputs/ (tests/bad_inputs.rs): each ends with the
    `expect:` line of its test, after the mesh data, where the reader does not look."""
    tp, tf = tetrahedron()
    good = mesh_bytes(4, "t", tp, tf)
    def table(m):
        return m + struct.pack("<QI", 0, 1)
    def write(name, data, expect):
        with open(f"{d}/{name}", "wb") as f:
            f.write(data + f"\nexpect: {expect}\n".encode())
    write("serialized-bad-magic.serialized", b"PLY is not this" + good[4:],
          "not a Mitsuba serialized mesh")
    write("serialized-version-5.serialized", struct.pack("<HH", 0x041C, 5) + good[4:],
          "format version 5 is not supported")
    # A whole zlib stream that holds less than its counts promise (2 of 4 vertices).
    body = struct.pack("<I", SINGLE) + b"t\0" + struct.pack("<QQ", 4, 4)
    body += struct.pack("<6f", 1, 1, 1, 1, -1, -1)
    write("serialized-truncated.serialized",
          struct.pack("<HH", 0x041C, 4) + zlib.compress(body), "the file is truncated")
    corrupt = bytearray(good)
    for i in range(8, 24):
        corrupt[i] ^= 0xA5
    write("serialized-corrupt.serialized", table(bytes(corrupt)), "compressed data is corrupt")
    write("serialized-index-out-of-range.serialized",
          table(mesh_bytes(4, "t", tp, [(0, 1, 2), (0, 1, 4)])), "refers to vertex 4")


def main():
    if sys.argv[1] == "--bad":
        bad_corpus(sys.argv[2])
        return
    out = sys.argv[1]
    version = 3 if "--v3" in sys.argv else 4
    tp, tf = tetrahedron()
    op, of, on, ouv = octahedron()
    meshes = [mesh_bytes(version, "tetrahedron", tp, tf),
              mesh_bytes(version, "octahedron", op, of, on, ouv)]
    data, offsets = b"", []
    for m in meshes:
        offsets.append(len(data))
        data += m
    fmt = "<Q" if version == 4 else "<I"
    for o in offsets:
        data += struct.pack(fmt, o)
    data += struct.pack("<I", len(meshes))
    with open(out, "wb") as f:
        f.write(data)


if __name__ == "__main__":
    main()
