#!/usr/bin/env python3
"""Writes tests/data/toml/: the TOML equivalents of the Mitsuba feature scenes in
tests/data/mitsuba/features (lights, materials, textures), with every to_world transform
applied by hand (M = translate · rotate · scale, as Mitsuba composes them), and the moved
copies of quad.obj and pyramid.ply that textures.toml loads.

Run from the repository root: python3 tools/toml_feature_scenes.py
"""
import math
import struct

OUT = "tests/data/toml"


def fmt(x):
    x = round(x, 6) + 0.0
    return repr(int(x)) if x == int(x) else repr(x)


def v3(p):
    return "[" + ", ".join(fmt(c) for c in p) + "]"


def rot(axis, deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    if axis == "x":
        return lambda p: (p[0], c * p[1] - s * p[2], s * p[1] + c * p[2])
    if axis == "y":
        return lambda p: (c * p[0] + s * p[2], p[1], -s * p[0] + c * p[2])
    raise ValueError(axis)


def compose(scale, r, t):
    def f(p):
        q = r((p[0] * scale[0], p[1] * scale[1], p[2] * scale[2]))
        return (q[0] + t[0], q[1] + t[1], q[2] + t[2])

    return f


def quad(m):
    """Mitsuba's rectangle [−1, 1]² (z = 0, facing +z) moved by m, as a TOML quad."""
    return "vertices = [" + ", ".join(
        v3(m(p)) for p in [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
    ) + "]"


def cube(m):
    """The importer's cube (src/scene/xml/objects.rs): 6 faces × 4 vertices, same order."""
    v, idx = [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = [0.0] * 3
            n[axis] = sign
            u = [0.0] * 3
            u[(axis + 1) % 3] = 1.0
            w = (n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0])
            base = len(v)
            for a, b in [(-1, -1), (1, -1), (1, 1), (-1, 1)]:
                v.append(tuple(n[i] + u[i] * a + w[i] * b for i in range(3)))
            idx += [[base, base + 1, base + 2], [base, base + 2, base + 3]]
    pos = ",\n    ".join(v3(m(p)) for p in v)
    ind = ", ".join("[%d, %d, %d]" % tuple(t) for t in idx)
    return f"positions = [\n    {pos},\n]\nindices = [{ind}]"


IDENT = lambda p: p

lights = f"""# TOML twin of tests/data/mitsuba/features/lights.xml (written by
# tools/toml_feature_scenes.py): point, directional and constant lights on diffuse shapes
# (quad, cube mesh, sphere, two-sided disk facing down), compared with the same Mitsuba
# reference (tests/data/refs/lights.exr) in tests/toml_features.rs.

[render]
width = 96
height = 64
spp = 64
integrator = "path"
max_depth = -1
rr_depth = 5
hide_emitters = false

[[camera]]
name = "main"
type = "perspective"
origin = [0, 3, 6]
target = [0, 0.3, 0]
up = [0, 1, 0]
fov = 45
fov_axis = "x"

# Mitsuba's diffuse BSDF is one-sided; `twosided` wraps the disk's.
[material.grey]
type = "lambert"
albedo = 0.7
two_sided = false

[material.red]
type = "lambert"
albedo = [0.8, 0.2, 0.15]
two_sided = false

[material.green]
type = "lambert"
albedo = [0.2, 0.7, 0.25]
two_sided = false

[material.blue]
type = "lambert"
albedo = [0.3, 0.3, 0.9]
two_sided = true

# rectangle: scale 4, rotate x −90.
[[shape]]
type = "quad"
material = "grey"
{quad(compose((4, 4, 4), rot("x", -90), (0, 0, 0)))}

# cube: scale (0.5, 0.7, 0.5), rotate y 30, translate (−1.2, 0.7, −0.5).
[[shape]]
type = "mesh"
material = "red"
{cube(compose((0.5, 0.7, 0.5), rot("y", 30), (-1.2, 0.7, -0.5)))}

[[shape]]
type = "sphere"
material = "green"
center = [1.1, 0.6, 0.3]
radius = 0.6

# disk: scale 0.5, rotate x −90 (facing +y), translate (0, 1.6, −1.5), flip_normals.
[[shape]]
type = "disk"
material = "blue"
center = [0, 1.6, -1.5]
normal = [0, -1, 0]
radius = 0.5

[[light]]
type = "point"
position = [1.5, 2.5, 1.5]
intensity = [6, 5, 4]

[[light]]
type = "directional"
direction = [-1, -1.5, -0.5]
irradiance = [1.2, 1.2, 1.5]

[[light]]
type = "constant"
radiance = [0.15, 0.2, 0.3]
"""

sphere_x = [-3, -2, -1, 0, 1, 2, 3]
materials = f"""# TOML twin of tests/data/mitsuba/features/materials.xml (written by
# tools/toml_feature_scenes.py): a row of spheres, one per BSDF, on a diffuse floor, lit by
# a rectangular area light and a constant environment; compared with the same Mitsuba
# reference (tests/data/refs/materials.exr) in tests/toml_features.rs. Mitsuba's default
# exterior index is air's, 1.000277 (mcrt's TOML default is 1).

[render]
width = 128
height = 64
spp = 64
integrator = "path"
max_depth = 12

[[camera]]
name = "main"
type = "perspective"
origin = [0, 2.2, 6.5]
target = [0, 0.4, 0]
up = [0, 1, 0]
fov = 50
fov_axis = "x"

[material.floor]
type = "lambert"
albedo = [0.5, 0.5, 0.45]
two_sided = false

[material.gold]
type = "conductor"
material = "Au"
two_sided = false

[material.copper]
type = "roughconductor"
material = "Cu"
alpha = 0.25
two_sided = false

[material.rough-glass]
type = "roughdielectric"
alpha = 0.15
ior = 1.5046
ext_ior = 1.000277

[material.thin-glass]
type = "thindielectric"
ior = 1.5
ext_ior = 1.000277

[material.red-plastic]
type = "plastic"
albedo = [0.7, 0.1, 0.1]
ior = 1.49
ext_ior = 1.000277
two_sided = false

[material.blue-rough-plastic]
type = "roughplastic"
alpha = 0.2
albedo = [0.1, 0.2, 0.7]
nonlinear = true
ext_ior = 1.000277
two_sided = false

[material.custom-metal]
type = "conductor"
eta = [0.2, 0.9, 1.1]
k = [3.9, 2.4, 2.2]
two_sided = false

# rectangle: scale 8, rotate x −90.
[[shape]]
type = "quad"
material = "floor"
{quad(compose((8, 8, 8), rot("x", -90), (0, 0, 0)))}

# The light: rectangle scaled (1.5, 0.75), rotate x 90 (facing −y), translate (0, 4, 1).
[[shape]]
type = "quad"
{quad(compose((1.5, 0.75, 1), rot("x", 90), (0, 4, 1)))}
emission = [12, 11, 10]

[[light]]
type = "constant"
radiance = [0.25, 0.3, 0.4]
""" + "".join(
    f"""
[[shape]]
type = "sphere"
material = "{m}"
center = [{x}, 0.5, 0]
radius = 0.5
"""
    for x, m in zip(
        sphere_x,
        ["gold", "copper", "rough-glass", "thin-glass", "red-plastic", "blue-rough-plastic",
         "custom-metal"],
    )
)

floor = compose((5, 5, 5), rot("x", -90), (0, 0, 0))
textures = f"""# TOML twin of tests/data/mitsuba/features/textures.xml (written by
# tools/toml_feature_scenes.py): a checkerboard (uv_scale) on a floor given with `uvs`, an
# sRGB PNG (nearest) on an OBJ quad, a linear EXR (mirror wrap, uv_scale) on a sphere, a
# textured plastic on a smooth-shaded PLY pyramid and a textured rough metal; compared with the
# same Mitsuba reference (tests/data/refs/textures.exr) in tests/toml_features.rs.
# quad.obj and pyramid.ply here are the features' files with their to_world applied.

[render]
width = 128
height = 96
spp = 64
integrator = "path"
max_depth = 6

[[camera]]
name = "main"
type = "perspective"
origin = [0, 2.5, 6]
target = [0, 0.6, 0]
up = [0, 1, 0]
fov = 45
fov_axis = "x"

[texture.checks]
type = "checkerboard"
color0 = [0.8, 0.8, 0.75]
color1 = [0.15, 0.2, 0.3]
uv_scale = [6, 6]

[texture.png-nearest]
type = "bitmap"
file = "../mitsuba/features/tex.png"
filter = "nearest"

[texture.png]
type = "bitmap"
file = "../mitsuba/features/tex.png"

[texture.exr]
type = "bitmap"
file = "../mitsuba/features/tex.exr"
wrap = "mirror"
uv_scale = [2, 1.5]

[material.floor]
type = "lambert"
albedo = "checks"
two_sided = false

[material.picture]
type = "lambert"
albedo = "png-nearest"
two_sided = false

[material.ball]
type = "lambert"
albedo = "exr"
two_sided = false

[material.plastic]
type = "plastic"
albedo = "png"
ext_ior = 1.000277
two_sided = false

[material.checked-metal]
type = "roughconductor"
alpha = 0.3
reflectance = "checks"
two_sided = false

# rectangle: scale 5, rotate x −90, with the rectangle's texture coordinates.
[[shape]]
type = "mesh"
material = "floor"
positions = [{", ".join(v3(floor(p)) for p in [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)])}]
indices = [[0, 1, 2], [0, 2, 3]]
uvs = [[0, 0], [1, 0], [1, 1], [0, 1]]

[[shape]]
type = "mesh"
material = "picture"
file = "quad.obj"

[[shape]]
type = "sphere"
material = "ball"
center = [1.4, 0.8, -0.6]
radius = 0.8

[[shape]]
type = "mesh"
material = "plastic"
file = "pyramid.ply"
smooth = true

[[shape]]
type = "sphere"
material = "checked-metal"
center = [0.6, 0.35, 1.3]
radius = 0.35

# The light: rectangle rotated x 90 (facing −y), translated to y = 4.5.
[[shape]]
type = "quad"
{quad(compose((1, 1, 1), rot("x", 90), (0, 4.5, 0)))}
emission = [8, 8, 7]

[[light]]
type = "constant"
radiance = 0.4
"""

for name, text in [("lights", lights), ("materials", materials), ("textures", textures)]:
    with open(f"{OUT}/{name}.toml", "w") as f:
        f.write(text)

# quad.obj: scale (1.6, 1.2, 1), translate (−1.2, 1.3, −1.5).
m = compose((1.6, 1.2, 1), IDENT, (-1.2, 1.3, -1.5))
with open(f"{OUT}/quad.obj", "w") as f:
    f.write("# tests/data/mitsuba/features/quad.obj moved as textures.xml moves it\n")
    for p in [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]:
        f.write("v " + " ".join(fmt(c) for c in m(p)) + "\n")
    f.write("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1 4/4/1\n")

# pyramid.ply (binary) as ASCII: scale 0.6, translate (−0.6, 0.02, 1).
d = open("tests/data/mitsuba/features/pyramid.ply", "rb").read()
body = d[d.index(b"end_header\n") + len(b"end_header\n"):]
verts = [struct.unpack_from("<5f", body, 20 * k) for k in range(5)]
off, faces = 100, []
for _ in range(6):
    n = body[off]
    faces.append(struct.unpack_from("<%dI" % n, body, off + 1))
    off += 1 + 4 * n
m = compose((0.6, 0.6, 0.6), IDENT, (-0.6, 0.02, 1))
with open(f"{OUT}/pyramid.ply", "w") as f:
    f.write("ply\nformat ascii 1.0\ncomment tests/data/mitsuba/features/pyramid.ply moved as "
            "textures.xml moves it\nelement vertex 5\nproperty float x\nproperty float y\n"
            "property float z\nproperty float u\nproperty float v\nelement face 6\n"
            "property list uchar uint vertex_indices\nend_header\n")
    for v in verts:
        f.write(" ".join(fmt(c) for c in m(v[:3])) + " " + " ".join(fmt(c) for c in v[3:]) + "\n")
    for t in faces:
        f.write(f"{len(t)} " + " ".join(map(str, t)) + "\n")
