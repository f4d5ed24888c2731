#!/usr/bin/env python3
"""Writes the glTF test scene and its Mitsuba 3 XML twin (pure json + struct + zlib).

    python3 tests/data/gltf/make_scene.py        # from the repository root

Outputs, in this directory:
  scene.gltf + scene.bin + checker.png   glTF with an external buffer and image
  scene.glb                              the same scene as one binary file (image inside)
  scene_embedded.gltf                    the same with data: URIs
  twin-principled.xml + twin-*.ply       the Mitsuba 3 twin, with Mitsuba's `principled` BSDF
                                         (how mcrt renders glTF materials)
  twin.xml                               the twin with the earlier rough-BSDF mapping

The scene: a node hierarchy (a rig carrying the camera, a group with a scale carrying two
instances of one metal cube, a glass box placed by a `matrix`), a textured rough metal floor
with KHR_texture_transform, a red back wall, an emissive panel (KHR_materials_emissive_strength)
and a point light (KHR_lights_punctual, candela). The twin places the same meshes with the
world matrices computed here from the glTF specification's rules (T*R*S, parent*child,
camera looking down -z), independently of mcrt's loader.
"""
import base64, json, math, os, struct, zlib

HERE = os.path.dirname(os.path.abspath(__file__))
W, H = 96, 64
YFOV = math.radians(40.0)
LUMENS_PER_WATT = 683.0

# ---------------------------------------------------------------- small linear algebra
def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]

def translate(t):
    m = ident(); m[0][3], m[1][3], m[2][3] = t; return m

def ident():
    return [[float(i == j) for j in range(4)] for i in range(4)]

def scale(s):
    m = ident(); m[0][0], m[1][1], m[2][2] = s; return m

def quat_matrix(q):
    x, y, z, w = q
    return [[1 - 2*(y*y + z*z), 2*(x*y - z*w), 2*(x*z + y*w), 0],
            [2*(x*y + z*w), 1 - 2*(x*x + z*z), 2*(y*z - x*w), 0],
            [2*(x*z - y*w), 2*(y*z + x*w), 1 - 2*(x*x + y*y), 0],
            [0, 0, 0, 1]]

def quat_axis_angle(axis, deg):
    a = math.radians(deg) / 2; n = math.sqrt(sum(c*c for c in axis))
    return [axis[0]/n*math.sin(a), axis[1]/n*math.sin(a), axis[2]/n*math.sin(a), math.cos(a)]

def trs(node):
    """glTF 2.0 3.5.2: M = T * R * S (or the column-major `matrix`)."""
    if "matrix" in node:
        c = node["matrix"]
        return [[c[j*4 + i] for j in range(4)] for i in range(4)]
    m = translate(node.get("translation", [0, 0, 0]))
    m = mat_mul(m, quat_matrix(node.get("rotation", [0, 0, 0, 1])))
    return mat_mul(m, scale(node.get("scale", [1, 1, 1])))

def apply(m, p, w=1.0):
    return [sum(m[i][k] * (p[k] if k < 3 else w) for k in range(4)) for i in range(3)]

# ---------------------------------------------------------------- geometry
def quad(size_x, size_z):
    """A quad in the xz plane facing +y, uv (0,0) at (-x, -z)."""
    x, z = size_x / 2, size_z / 2
    pos = [(-x, 0, -z), (x, 0, -z), (x, 0, z), (-x, 0, z)]
    nor = [(0, 1, 0)] * 4
    uv = [(0, 0), (1, 0), (1, 1), (0, 1)]
    idx = [0, 2, 1, 0, 3, 2]  # counter-clockwise seen from +y
    return pos, nor, uv, idx

def cube(h):
    """A cube of half size h, 24 vertices (flat faces), counter-clockwise outside."""
    pos, nor, uv, idx = [], [], [], []
    for axis in range(3):
        for sign in (1, -1):
            n = [0, 0, 0]; n[axis] = sign
            u = [0, 0, 0]; u[(axis + 1) % 3] = 1
            v = [0, 0, 0]; v[(axis + 2) % 3] = 1
            base = len(pos)
            for (a, b) in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                pos.append(tuple(h * (n[i] + a*u[i] + b*v[i]) for i in range(3)))
                nor.append(tuple(n)); uv.append(((a + 1) / 2, (b + 1) / 2))
            tri = [0, 1, 2, 0, 2, 3] if sign > 0 else [0, 2, 1, 0, 3, 2]
            idx += [base + t for t in tri]
    return pos, nor, uv, idx

def checker_png(n=8, cells=4):
    rows = b""
    for y in range(n):
        rows += b"\x00"
        for x in range(n):
            on = ((x * cells // n) + (y * cells // n)) % 2 == 0
            rows += bytes((230, 200, 60) if on else (40, 90, 200))
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", n, n, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))

# ---------------------------------------------------------------- the scene
MESHES = {  # name: (geometry, material, with normals, with uvs, indexed)
    "floor": (quad(6, 6), 0, True, True, True),
    "wall": (quad(6, 3), 1, False, False, True),
    "cube": (cube(0.5), 2, True, False, True),
    "glass": (cube(0.4), 3, True, False, False),
    "panel": (quad(2.0, 1.2), 4, False, False, True),
}
TT = {"offset": [0.1, 0.2], "rotation": 0.3, "scale": [2.0, 3.0]}
MATERIALS = [
    {"name": "floor", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": TT}},
                                               "metallicFactor": 1.0, "roughnessFactor": 0.6}},
    {"name": "wall", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.15, 0.1, 1.0], "metallicFactor": 0.0,
                                              "roughnessFactor": 0.4}},
    {"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [0.95, 0.7, 0.3, 1.0], "metallicFactor": 1.0,
                                              "roughnessFactor": 0.35}},
    {"name": "glass", "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.45},
     "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.5}}},
    {"name": "light", "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0.0,
                                               "roughnessFactor": 1.0},
     "emissiveFactor": [1.0, 0.9, 0.8], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 10.0}}},
]
POINT_CD = 5464.0  # 8 W/sr
NODES = [
    {"name": "Rig", "translation": [0, 1.2, 0], "rotation": quat_axis_angle([0, 1, 0], 20), "children": [1]},
    {"name": "CamArm", "translation": [0, 0, 5.0], "rotation": quat_axis_angle([1, 0, 0], -12), "children": [2]},
    {"name": "MainCam", "camera": 0},
    {"name": "Floor", "mesh": 0},
    {"name": "Wall", "mesh": 1, "translation": [0, 1.5, -2.0], "rotation": quat_axis_angle([1, 0, 0], 90)},
    {"name": "Group", "translation": [-0.4, 0, 0.2], "scale": [0.8, 0.8, 0.8], "children": [6, 7]},
    {"name": "CubeA", "mesh": 2, "translation": [-0.6, 0.5, 0], "rotation": quat_axis_angle([0, 1, 0], 30)},
    {"name": "CubeB", "mesh": 2, "translation": [0.9, 0.5, -0.8], "rotation": quat_axis_angle([1, 1, 0], 40)},
    {"name": "Glass", "mesh": 3},
    {"name": "Panel", "mesh": 4, "translation": [0.3, 2.6, 0.4], "rotation": quat_axis_angle([1, 0, 0], 180)},
    {"name": "Lamp", "translation": [1.5, 2.0, 1.5], "extensions": {"KHR_lights_punctual": {"light": 0}}},
]
# The glass box by a column-major matrix: rotation 25 deg about z, then a translation.
_g = mat_mul(translate([1.1, 0.6, 0.6]), quat_matrix(quat_axis_angle([0, 0, 1], 25)))
NODES[8]["matrix"] = [_g[i][j] for j in range(4) for i in range(4)]
ROOTS = [0, 3, 4, 5, 8, 9, 10]


def build_buffer(with_image):
    """The binary buffer, the bufferViews and accessors, and the mesh JSON."""
    data = bytearray(); views = []; accessors = []; meshes = []
    def add_view(b, target=None):
        while len(data) % 4: data.append(0)
        v = {"buffer": 0, "byteOffset": len(data), "byteLength": len(b)}
        if target: v["target"] = target
        data.extend(b); views.append(v); return len(views) - 1
    def add_acc(vals, typ, n):
        flat = [c for v in vals for c in v] if n > 1 else list(vals)
        view = add_view(struct.pack("<%d%s" % (len(flat), "f" if typ == 5126 else "H"), *flat),
                        34962 if typ == 5126 else 34963)
        a = {"bufferView": view, "componentType": typ, "count": len(vals),
             "type": {1: "SCALAR", 2: "VEC2", 3: "VEC3"}[n]}
        if n == 3 and typ == 5126:
            a["min"] = [min(v[i] for v in vals) for i in range(3)]
            a["max"] = [max(v[i] for v in vals) for i in range(3)]
        accessors.append(a); return len(accessors) - 1
    for name, ((pos, nor, uv, idx), mat, with_n, with_uv, indexed) in MESHES.items():
        if not indexed:
            pos = [pos[i] for i in idx]; nor = [nor[i] for i in idx]; uv = [uv[i] for i in idx]
        attrs = {"POSITION": add_acc(pos, 5126, 3)}
        if with_n: attrs["NORMAL"] = add_acc(nor, 5126, 3)
        if with_uv: attrs["TEXCOORD_0"] = add_acc(uv, 5126, 2)
        prim = {"attributes": attrs, "material": mat}
        if indexed: prim["indices"] = add_acc(idx, 5123, 1)
        meshes.append({"name": name, "primitives": [prim]})
    image = {"uri": "checker.png"}
    if with_image:
        image = {"bufferView": add_view(checker_png()), "mimeType": "image/png"}
    while len(data) % 4: data.append(0)
    return bytes(data), views, accessors, meshes, image


def gltf_json(buffer, views, accessors, meshes, image):
    return {
        "asset": {"version": "2.0", "generator": "mcrt tests/data/gltf/make_scene.py"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_ior",
                           "KHR_materials_transmission", "KHR_texture_transform"],
        "scene": 0,
        "scenes": [{"nodes": ROOTS}],
        "nodes": NODES,
        "cameras": [{"name": "Lens", "type": "perspective",
                     "perspective": {"yfov": YFOV, "aspectRatio": W / H, "znear": 0.05}}],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "Bulb", "type": "point", "color": [1.0, 0.95, 0.9], "intensity": POINT_CD}]}},
        "meshes": meshes, "materials": MATERIALS,
        "textures": [{"source": 0}], "images": [image],
        "buffers": [buffer], "bufferViews": views, "accessors": accessors,
    }


def write_gltf_files():
    data, views, acc, meshes, image = build_buffer(False)
    with open(os.path.join(HERE, "scene.bin"), "wb") as f: f.write(data)
    with open(os.path.join(HERE, "checker.png"), "wb") as f: f.write(checker_png())
    j = gltf_json({"uri": "scene.bin", "byteLength": len(data)}, views, acc, meshes, image)
    with open(os.path.join(HERE, "scene.gltf"), "w") as f: json.dump(j, f, indent=1)
    emb = gltf_json({"uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode(),
                     "byteLength": len(data)}, views, acc, meshes,
                    {"uri": "data:image/png;base64," + base64.b64encode(checker_png()).decode()})
    with open(os.path.join(HERE, "scene_embedded.gltf"), "w") as f: json.dump(emb, f)
    data, views, acc, meshes, image = build_buffer(True)
    j = json.dumps(gltf_json({"byteLength": len(data)}, views, acc, meshes, image)).encode()
    j += b" " * ((4 - len(j) % 4) % 4)
    glb = (struct.pack("<I", len(j)) + b"JSON" + j + struct.pack("<I", len(data)) + b"BIN\x00" + data)
    with open(os.path.join(HERE, "scene.glb"), "wb") as f:
        f.write(b"glTF" + struct.pack("<II", 2, 12 + len(glb)) + glb)


# ---------------------------------------------------------------- the Mitsuba twin
def world_matrices():
    out = {}
    def walk(i, parent):
        m = mat_mul(parent, trs(NODES[i])); out[i] = m
        for c in NODES[i].get("children", []): walk(c, m)
    for r in ROOTS: walk(r, ident())
    return out


def write_ply(name, pos, nor, uv, idx, with_n, with_uv):
    lines = ["ply", "format ascii 1.0", "element vertex %d" % len(pos),
             "property float x", "property float y", "property float z"]
    if with_n: lines += ["property float nx", "property float ny", "property float nz"]
    if with_uv: lines += ["property float u", "property float v"]
    lines += ["element face %d" % (len(idx) // 3), "property list uchar int vertex_indices", "end_header"]
    for i, p in enumerate(pos):
        row = list(p) + (list(nor[i]) if with_n else []) + (list(uv[i]) if with_uv else [])
        lines.append(" ".join("%.9g" % c for c in row))
    for t in range(0, len(idx), 3):
        lines.append("3 %d %d %d" % tuple(idx[t:t+3]))
    with open(os.path.join(HERE, "twin-%s.ply" % name), "w") as f: f.write("\n".join(lines) + "\n")


def tex_matrix():
    """KHR_texture_transform: T * R * S with R = GLSL mat3(cos, sin, 0, -sin, cos, 0, 0, 0, 1),
    as the 4x4 matrix Mitsuba's `to_uv` takes (it keeps the upper-left 2x2 block and the x, y
    of column 3: a 3x3 matrix would lose the offset)."""
    c, s = math.cos(TT["rotation"]), math.sin(TT["rotation"])
    sx, sy = TT["scale"]; ox, oy = TT["offset"]
    return [[c*sx, -s*sy, 0, ox], [s*sx, c*sy, 0, oy], [0, 0, 1, 0], [0, 0, 0, 1]]


# twin.xml is the rough-BSDF mapping mcrt used before it had `principled` (docs/gltf.md):
# a plastic's base colour times this, so that its diffuse albedo at normal incidence is
# glTF's (1 - F0) * baseColor; here for ior 1.5 and roughness 0.4, the wall's, integrated
# from Mitsuba 3's roughplastic.
PLASTIC_SCALE = {(1.5, 0.4): 1.19731}


def bsdf_xml(m, principled):
    pbr = m["pbrMetallicRoughness"]; r = pbr.get("roughnessFactor", 1.0); a = r * r
    metal = pbr.get("metallicFactor", 1.0); base = pbr.get("baseColorFactor", [1, 1, 1, 1])[:3]
    ext = m.get("extensions", {})
    trans = ext.get("KHR_materials_transmission", {}).get("transmissionFactor", 0.0)
    ior = ext.get("KHR_materials_ior", {}).get("ior", 1.5)
    rgb = lambda n, c: '<rgb name="%s" value="%.9g %.9g %.9g"/>' % (n, *c)
    if "baseColorTexture" in pbr:
        mt = tex_matrix()
        colour = lambda n: ('<texture type="bitmap" name="%s"><string name="filename" value="checker.png"/>'
                            '<transform name="to_uv"><matrix value="%s"/></transform></texture>'
                            % (n, " ".join("%.9g" % v for row in mt for v in row)))
    else:
        colour = lambda n: rgb(n, base)
    if principled:
        return ('<bsdf type="principled">%s<float name="metallic" value="%g"/><float name="roughness" value="%g"/>'
                '<float name="spec_trans" value="%g"/><float name="eta" value="%g"/></bsdf>'
                % (colour("base_color"), metal, r, trans, ior))
    if metal >= 0.5:
        return ('<bsdf type="roughconductor"><string name="material" value="none"/><string name="distribution" '
                'value="ggx"/><float name="alpha" value="%.9g"/>%s</bsdf>' % (a, colour("specular_reflectance")))
    if trans >= 0.5:
        return ('<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" '
                'value="%.9g"/><float name="int_ior" value="%g"/><float name="ext_ior" value="1"/></bsdf>' % (a, ior))
    k = PLASTIC_SCALE[(ior, r)] if any(base) else 1.0
    return ('<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="%.9g"/>'
            '<float name="int_ior" value="%g"/><float name="ext_ior" value="1"/>%s</bsdf>'
            % (a, ior, rgb("diffuse_reflectance", [c * k for c in base])))


def write_twin(principled):
    worlds = world_matrices()
    out = ['<scene version="3.0.0">', '<integrator type="path"/>']
    cam = worlds[2]
    o = apply(cam, [0, 0, 0]); t = apply(cam, [0, 0, -1]); up = apply(cam, [0, 1, 0], 0.0)
    out.append('<sensor type="perspective"><string name="fov_axis" value="y"/><float name="fov" value="%.9g"/>'
               '<transform name="to_world"><lookat origin="%.9g %.9g %.9g" target="%.9g %.9g %.9g" up="%.9g %.9g %.9g"/>'
               '</transform><film type="hdrfilm"><integer name="width" value="%d"/><integer name="height" value="%d"/>'
               '<rfilter type="box"/></film></sensor>' % (math.degrees(YFOV), *o, *t, *up, W, H))
    names = list(MESHES)
    for i, n in enumerate(NODES):
        if "mesh" not in n: continue
        name = names[n["mesh"]]
        (pos, nor, uv, idx), mat, with_n, with_uv, _ = MESHES[name]
        m = worlds[i]
        shape = ['<shape type="ply"><string name="filename" value="twin-%s.ply"/>' % name]
        if not with_n: shape.append('<boolean name="face_normals" value="true"/>')
        shape.append('<transform name="to_world"><matrix value="%s"/></transform>'
                     % " ".join("%.9g" % v for row in m for v in row))
        shape.append(bsdf_xml(MATERIALS[mat], principled))
        em = MATERIALS[mat].get("emissiveFactor")
        if em:
            k = MATERIALS[mat]["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"]
            shape.append('<emitter type="area"><rgb name="radiance" value="%.9g %.9g %.9g"/></emitter>'
                         % tuple(c * k for c in em))
        shape.append('</shape>')
        out.append("".join(shape))
    lamp = apply(worlds[10], [0, 0, 0])
    c = [x * POINT_CD / LUMENS_PER_WATT for x in (1.0, 0.95, 0.9)]
    out.append('<emitter type="point"><point name="position" x="%.9g" y="%.9g" z="%.9g"/>'
               '<rgb name="intensity" value="%.9g %.9g %.9g"/></emitter>' % (*lamp, *c))
    out.append('</scene>')
    fname = "twin-principled.xml" if principled else "twin.xml"
    with open(os.path.join(HERE, fname), "w") as f: f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    write_gltf_files()
    for name, ((pos, nor, uv, idx), _, with_n, with_uv, _) in MESHES.items():
        write_ply(name, pos, nor, uv, idx, with_n, with_uv)
    write_twin(False)
    write_twin(True)
