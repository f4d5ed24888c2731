#!/usr/bin/env python3
"""Writes the glTF cases of tests/bad-inputs/ (run from anywhere): each a one-triangle scene
wrong in one way, with the fragment of the expected message in its asset.generator (read by
tests/bad_inputs.rs after `expect:`)."""
import base64, copy, json, os, struct

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "bad-inputs")
DATA = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<3H", 0, 1, 2) + b"\0\0"


def base():
    return {
        "asset": {"generator": "", "version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 0, 3]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"emissiveFactor": [1, 1, 1]}],
        "buffers": [{"uri": "data:application/octet-stream;base64," + base64.b64encode(DATA).decode(),
                     "byteLength": len(DATA)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
    }


def text(doc, expect):
    doc["asset"]["generator"] = "expect: " + expect
    # The generator on its own line, first: the test reads the first 400 bytes.
    head = '{\n"asset": {"version": "2.0",\n"generator": %s\n},\n' % json.dumps(doc["asset"]["generator"])
    rest = {k: v for k, v in doc.items() if k != "asset"}
    return head + json.dumps(rest, indent=1)[1:]


def write(name, content):
    mode = "wb" if isinstance(content, bytes) else "w"
    with open(os.path.join(OUT, name), mode) as f:
        f.write(content)


def glb(doc, expect):
    j = text(doc, expect).encode()
    j += b" " * ((4 - len(j) % 4) % 4)
    body = struct.pack("<I", len(j)) + b"JSON" + j
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


cases = {}
d = base(); cases["gltf-missing-buffer.gltf"] = (d, "buffers[0]: cannot read")
d["buffers"][0]["uri"] = "no-such-file.bin"
d = base(); d["accessors"][0]["count"] = 4
cases["gltf-accessor-out-of-bounds.gltf"] = (d, "reads past the end of bufferViews[0]")
d = base(); d["accessors"][1]["count"] = 3
cases["gltf-index-out-of-range.gltf"] = (d, "is out of range (the primitive has 2 vertices)")
d["accessors"][0]["count"] = 2
d = base(); d["meshes"][0]["primitives"][0]["attributes"]["TANGENT"] = 0
cases["gltf-tangent-wrong-type.gltf"] = (d, "(TANGENT) has type Vec3; 4 components were expected")
d = base(); d["meshes"][0]["primitives"][0]["attributes"]["TANGENT"] = 2
d["accessors"].append({"bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC4"})
cases["gltf-tangent-count.gltf"] = (d, "TANGENT has 2 elements but POSITION has 3")
d = base(); d["extensionsRequired"] = ["KHR_draco_mesh_compression"]; d["extensionsUsed"] = ["KHR_draco_mesh_compression"]
cases["gltf-unsupported-extension.gltf"] = (d, "requires the extension 'KHR_draco_mesh_compression'")
d = base(); d["scenes"][0]["nodes"] = [0]
cases["gltf-no-camera.gltf"] = (d, "the scene has no camera")
d = base(); d["materials"] = [{}]
cases["gltf-no-light.gltf"] = (d, "the scene has no light")
d = base(); d["nodes"][0]["children"] = [2]; d["nodes"].append({"children": [0]})
cases["gltf-node-cycle.gltf"] = (d, "is reached twice")
d = base(); d["nodes"][0]["mesh"] = 5
cases["gltf-bad-reference.gltf"] = (d, "nodes[0].mesh refers to an object that does not exist")
d = base(); d["materials"][0]["extensions"] = {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0}}
cases["gltf-clearcoat-strict.gltf"] = (d, "--lenient renders the scene anyway")
d = base(); d["materials"][0]["pbrMetallicRoughness"] = {"roughnessFactor": 2.0}
cases["gltf-roughness-above-one.gltf"] = (d, "roughnessFactor 2 is out of range")
d = base(); d["cameras"][0]["perspective"]["yfov"] = 0.0
cases["gltf-zero-yfov.gltf"] = (d, "yfov 0 is not an angle")

for name, (doc, expect) in cases.items():
    write(name, text(doc, expect))

# A missing comma: the next key, on line 7 column 2, is where the parser stops.
write("gltf-bad-json.gltf", text(base(), "gltf-bad-json.gltf:7:2: invalid glTF JSON: expected `,` or `}`").replace(
    '\n "scene": 0,', '\n "scene": 0', 1))
full = glb(base(), "truncated GLB file")
write("gltf-truncated.glb", full[: len(full) - 40])
d = base(); d["buffers"] = [{"byteLength": 44}]
write("gltf-glb-without-bin-chunk.glb", glb(d, "the file has none"))
# Found by the fuzz target: the gltf crate's validation indexed the accessors by POSITION.
d = base(); d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 7
write("gltf-position-accessor-missing.gltf",
      text(d, "attributes.POSITION refers to accessors[7], which does not exist"))
# Found by the fuzz target: the gltf crate's Image::source unwrapped a missing uri.
d = base(); d["materials"][0]["pbrMetallicRoughness"] = {"baseColorTexture": {"index": 0}}
d["textures"] = [{"source": 0}]; d["images"] = [{"name": "nothing"}]
write("gltf-image-without-data.gltf", text(d, "images[0] has neither a uri nor a bufferView"))
# Found by the fuzz target: a GLB length below the header's 12 bytes underflowed in the crate.
short = bytearray(glb(base(), "too few for the header and a JSON chunk"))
short[8:12] = struct.pack("<I", 8)
write("gltf-glb-length-too-small.glb", bytes(short))
