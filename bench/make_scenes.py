#!/usr/bin/env python3
"""Write the benchmark's general scenes as Mitsuba 3 XML that both Mitsuba 3 and mcrt read.

  gallery.xml      a height-field terrain (binary PLY, 816 642 triangles, textured diffuse
                   with a generated PNG) and nine transformed copies of the Stanford bunny
                   (benches/data/bunny.obj) in rough conductors, rough plastics, plastic,
                   glass, rough glass, a smooth conductor and diffuse; two area lights and a
                   constant environment: 849 708 triangles, 11 BSDFs.
  bunny-box.xml    the Cornell box of tests/data/mitsuba/cornell-box.xml with the bunny
                   (3 674 triangles) on its floor.
  materials-box.xml  the same Cornell box in five kinds of BSDF, each with Mitsuba's
                   defaults where not given (so the microfacets are Beckmann): the small box
                   a rough plastic, the large one a rough conductor, a rough dielectric
                   sphere on the small box, the back wall Mitsuba's principled BSDF, the
                   rest diffuse. A small scene whose time is the shading, not the traversal.

Everything is computed from closed-form functions (no random numbers), so the files are the
same bytes on every run. The outputs are large (about 20 MB) and not committed: they go to
bench/out/scenes/ unless a folder is given. Needs Python 3 and numpy only.

usage: python3 bench/make_scenes.py [OUT_DIR] [--terrain N]
"""
import argparse
import math
import os
import re
import struct
import zlib

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUNNY = os.path.join(ROOT, "benches", "data", "bunny.obj")
CORNELL = os.path.join(ROOT, "tests", "data", "mitsuba", "cornell-box.xml")

# The terrain spans [-EXTENT, EXTENT]² in x and z; y is up.
EXTENT = 6.0

# sin and cos of the C library, element by element: NumPy's own vectorised ones differ in the
# last bit between CPUs (SIMD code chosen at run time), and the files must not.
_sin, _cos = np.frompyfunc(math.sin, 1, 1), np.frompyfunc(math.cos, 1, 1)


def sin(a):
    return _sin(a).astype(np.float64)


def cos(a):
    return _cos(a).astype(np.float64)


def height(x, z):
    """The terrain's height: a few sines, smooth at the scale of the bunnies, with fine
    ripples so that its triangles are not coplanar."""
    return (0.35 * sin(0.9 * x + 0.3) * cos(0.7 * z)
            + 0.15 * sin(0.55 * x - 0.45 * z)
            + 0.02 * sin(7.1 * x + 5.3 * z) * cos(4.3 * z - 2.9 * x))


def write_terrain_ply(path, n):
    """An n × n vertex grid as a binary little-endian PLY with positions and texture
    coordinates, two triangles per cell, wound so that the faces' normals point up (+y)."""
    t = np.linspace(-EXTENT, EXTENT, n)
    x, z = np.meshgrid(t, t)  # row index along z, column index along x
    y = height(x, z)
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    verts = np.stack([x, y, z, u, v], axis=-1).reshape(-1, 5).astype("<f4")
    i = np.arange(n - 1)
    a = (i[:, None] * n + i[None, :]).ravel()  # corner (row, col) of each cell
    b, c, d = a + 1, a + n, a + n + 1
    # (a, c, b): with x along columns and z along rows, cross(c - a, b - a) points to +y.
    tris = np.concatenate([np.stack([a, c, b], 1), np.stack([b, c, d], 1)])
    faces = np.zeros(len(tris), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    faces["n"] = 3
    faces["i"] = tris
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment mcrt bench/make_scenes.py terrain\n"
        f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n"
        "property float u\nproperty float v\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(verts.tobytes())
        f.write(faces.tobytes())
    return len(faces)


def write_png(path, rgb):
    """An 8-bit RGB PNG (no interlace, filter 0 on every row), with the standard library's
    zlib: PNG 1.2, ISO/IEC 15948."""
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[r].tobytes() for r in range(h))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


def write_texture(path, size=512):
    """Grass and rock in patches with a faint grid: colour that varies at several scales, so
    that bilinear lookups and the sRGB decode are both exercised."""
    s = np.linspace(0, 2 * np.pi, size, endpoint=False)
    x, y = np.meshgrid(s, s)
    patch = 0.5 + 0.5 * sin(3 * x + sin(2 * y)) * cos(2 * y - sin(3 * x))
    fine = 0.5 + 0.5 * sin(37 * x + 11 * y) * sin(29 * y - 13 * x)
    grass = np.array([0.25, 0.45, 0.15])
    rock = np.array([0.55, 0.5, 0.45])
    col = grass * patch[..., None] + rock * (1 - patch[..., None])
    col *= (0.8 + 0.2 * fine)[..., None]
    grid = (np.abs(sin(8 * x)) < 0.05) | (np.abs(sin(8 * y)) < 0.05)
    col[grid] *= 0.6
    write_png(path, np.clip(np.round(col * 255), 0, 255).astype(np.uint8))


# Nine bunnies on a 3 × 3 grid: (x, z, yaw in degrees, scale, BSDF id).
BUNNIES = [
    (-3.2, -3.0, 20, 0.17, "gold"),
    (0.0, -3.2, -35, 0.2, "red-roughplastic"),
    (3.1, -2.9, 60, 0.17, "glass"),
    (-3.0, 0.1, 110, 0.16, "blue-plastic"),
    (0.2, 0.0, 0, 0.21, "silver"),
    (3.2, 0.2, -80, 0.16, "copper"),
    (-2.9, 3.0, 200, 0.15, "rough-glass"),
    (0.1, 3.1, 150, 0.16, "green-roughplastic"),
    (3.0, 3.2, -150, 0.15, "white"),
]

BSDFS = """\
    <bsdf type="diffuse" id="terrain">
        <texture type="bitmap" name="reflectance">
            <string name="filename" value="terrain.png"/>
            <transform name="to_uv"><scale x="6" y="6"/></transform>
        </texture>
    </bsdf>
    <bsdf type="roughconductor" id="gold">
        <string name="material" value="Au"/>
        <string name="distribution" value="ggx"/>
        <float name="alpha" value="0.2"/>
    </bsdf>
    <bsdf type="roughconductor" id="copper">
        <string name="material" value="Cu"/>
        <string name="distribution" value="ggx"/>
        <float name="alpha" value="0.35"/>
    </bsdf>
    <bsdf type="conductor" id="silver">
        <string name="material" value="Ag"/>
    </bsdf>
    <bsdf type="roughplastic" id="red-roughplastic">
        <string name="distribution" value="ggx"/>
        <float name="alpha" value="0.15"/>
        <rgb name="diffuse_reflectance" value="0.6, 0.12, 0.08"/>
    </bsdf>
    <bsdf type="roughplastic" id="green-roughplastic">
        <string name="distribution" value="ggx"/>
        <float name="alpha" value="0.3"/>
        <rgb name="diffuse_reflectance" value="0.15, 0.5, 0.2"/>
    </bsdf>
    <bsdf type="plastic" id="blue-plastic">
        <rgb name="diffuse_reflectance" value="0.1, 0.2, 0.6"/>
    </bsdf>
    <bsdf type="dielectric" id="glass">
        <float name="int_ior" value="1.5"/>
        <float name="ext_ior" value="1.0"/>
    </bsdf>
    <bsdf type="roughdielectric" id="rough-glass">
        <string name="distribution" value="ggx"/>
        <float name="alpha" value="0.1"/>
        <float name="int_ior" value="1.5"/>
        <float name="ext_ior" value="1.0"/>
    </bsdf>
    <bsdf type="diffuse" id="white">
        <rgb name="reflectance" value="0.75, 0.75, 0.72"/>
    </bsdf>
    <bsdf type="diffuse" id="black">
        <rgb name="reflectance" value="0"/>
    </bsdf>
"""

HEAD = """\
<?xml version="1.0" encoding="utf-8"?>
<!-- {comment} Written by bench/make_scenes.py; do not edit. -->
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <default name="res" value="256"/>
    <integrator type="path">
        <integer name="max_depth" value="{depth}"/>
    </integrator>
    <sensor type="perspective">
        <string name="fov_axis" value="x"/>
        <float name="fov" value="{fov}"/>
        <transform name="to_world">
            <lookat origin="{origin}" target="{target}" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
            <rfilter type="box"/>
        </film>
    </sensor>
"""


def bunny_shape(filename, x, y, z, yaw, scale, bsdf):
    return f"""\
    <shape type="obj">
        <string name="filename" value="{filename}"/>
        <transform name="to_world">
            <scale value="{scale}"/>
            <rotate y="1" angle="{yaw}"/>
            <translate x="{x}" y="{y:.6f}" z="{z}"/>
        </transform>
        <ref id="{bsdf}"/>
    </shape>
"""


def gallery_xml(bunny_rel, tris):
    parts = [HEAD.format(comment=f"The benchmark's gallery: {tris} triangles.", depth=8,
                         fov=48, origin="0, 4.5, 9", target="0, 0.3, 0.5"), BSDFS]
    parts.append("""\
    <shape type="ply">
        <string name="filename" value="terrain.ply"/>
        <ref id="terrain"/>
    </shape>
""")
    for x, z, yaw, scale, bsdf in BUNNIES:
        # On the ground's mean height under the bunny (about 10 units wide unscaled), sunk by
        # 5 % of its height (9.65 units unscaled) so that its open base hides.
        r = np.linspace(-5 * scale, 5 * scale, 9)
        y = float(height(x + r[:, None], z + r[None, :]).mean()) - 0.05 * 9.65 * scale
        parts.append(bunny_shape(bunny_rel, x, y, z, yaw, scale, bsdf))
    parts.append("""\
    <shape type="rectangle">
        <transform name="to_world">
            <scale x="1.5" y="0.8"/>
            <rotate x="1" angle="90"/>
            <rotate z="1" angle="-25"/>
            <translate x="-4" y="6" z="2"/>
        </transform>
        <ref id="black"/>
        <emitter type="area"><rgb name="radiance" value="14, 11, 8"/></emitter>
    </shape>
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="0.7"/>
            <rotate x="1" angle="70"/>
            <translate x="4.5" y="4" z="-1"/>
        </transform>
        <ref id="black"/>
        <emitter type="area"><rgb name="radiance" value="8, 12, 20"/></emitter>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="0.25, 0.3, 0.4"/></emitter>
</scene>
""")
    return "".join(parts)


def bunny_box_xml(bunny_rel):
    """The Cornell box file with the bunny inserted before </scene>, in its white BSDF."""
    bunny = bunny_shape(bunny_rel, -0.42, -1.0, 0.5, 25, 0.045, "white")
    return cornell_with(open(CORNELL).read(), [
        ("<!-- Mitsuba 3's own Cornell box",
         "<!-- With the Stanford bunny on the floor; Mitsuba 3's own Cornell box"),
        (r"</scene>\s*$", bunny + "</scene>\n")])


def cornell_with(text, edits):
    """The Cornell box file `text` with the regular-expression `edits` applied (each must
    match) and the gallery's parameters: $spp and $res."""
    edits = edits + [
        (r'(<scene version="[^"]*">)', r'\1\n    <default name="spp" value="64"/>\n'
         r'    <default name="res" value="256"/>'),
        (r'name="(width|height)" value="\d+"', r'name="\1" value="$res"'),
        (r'name="sample_count" value="\d+"', r'name="sample_count" value="$spp"')]
    for pattern, repl in edits:
        text, n = re.subn(pattern, repl, text)
        assert n >= 1, f"cornell-box.xml: no match for {pattern}"
    return text


def materials_box_xml():
    """The Cornell box with its boxes, a sphere and its back wall in other BSDFs."""
    bsdfs = """    <bsdf type="roughplastic" id="plastic">
        <rgb name="diffuse_reflectance" value="0.2, 0.35, 0.6"/>
    </bsdf>
    <bsdf type="roughconductor" id="metal">
        <string name="material" value="Au"/>
        <float name="alpha" value="0.2"/>
    </bsdf>
    <bsdf type="principled" id="principled">
        <rgb name="base_color" value="0.7, 0.65, 0.55"/>
        <float name="roughness" value="0.4"/>
        <float name="metallic" value="0.3"/>
    </bsdf>
"""
    sphere = """    <shape type="sphere">
        <point name="center" x="0.335" y="-0.15" z="0.38"/>
        <float name="radius" value="0.25"/>
        <bsdf type="roughdielectric">
            <float name="alpha" value="0.15"/>
        </bsdf>
    </shape>
"""
    return cornell_with(open(CORNELL).read(), [
        ("<!-- Mitsuba 3's own Cornell box",
         "<!-- In rough plastic, rough conductor, rough dielectric and principled BSDFs; "
         "Mitsuba 3's own Cornell box"),
        (r'(\n    <shape type="rectangle" id="light">)', "\n" + bsdfs.rstrip("\n") + r"\1"),
        (r'(?s)(<shape type="rectangle" id="back">(?:(?!</shape>).)*?)<ref id="white"/>',
         r'\1<ref id="principled"/>'),
        (r'(?s)(<shape type="cube" id="small-box">(?:(?!</shape>).)*?)<ref id="white"/>',
         r'\1<ref id="plastic"/>'),
        (r'(?s)(<shape type="cube" id="large-box">(?:(?!</shape>).)*?)<ref id="white"/>',
         r'\1<ref id="metal"/>'),
        (r"</scene>\s*$", sphere + "</scene>\n")])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", nargs="?", default=os.path.join(ROOT, "bench", "out", "scenes"))
    ap.add_argument("--terrain", type=int, default=640, help="terrain vertices per side")
    a = ap.parse_args()
    if not 2 <= a.terrain <= 4096:  # 4096² vertices: 33.5 M triangles, 0.8 GB of PLY
        ap.error("--terrain must be between 2 and 4096")
    os.makedirs(a.out, exist_ok=True)
    bunny_rel = os.path.relpath(BUNNY, a.out)
    tris = write_terrain_ply(os.path.join(a.out, "terrain.ply"), a.terrain)
    write_texture(os.path.join(a.out, "terrain.png"))
    tris += len(BUNNIES) * sum(1 for line in open(BUNNY) if line.startswith("f "))
    with open(os.path.join(a.out, "gallery.xml"), "w") as f:
        f.write(gallery_xml(bunny_rel, tris))
    with open(os.path.join(a.out, "bunny-box.xml"), "w") as f:
        f.write(bunny_box_xml(bunny_rel))
    with open(os.path.join(a.out, "materials-box.xml"), "w") as f:
        f.write(materials_box_xml())
    print(f"wrote {a.out}/gallery.xml ({tris} triangles), bunny-box.xml and materials-box.xml")


if __name__ == "__main__":
    main()
