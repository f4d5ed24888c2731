#!/usr/bin/env python3
"""Values of Mitsuba 3's normalmap and bumpmap BSDFs (around a diffuse one of reflectance 0.5)
at fixed hits and direction pairs, for the unit tests of src/material/normal_map.rs: prints
one line per case, `kind viewer light value` (value = f·cos θ, Mitsuba's eval, red channel).
The hit: shading frame = world axes, dp/du = (2, 0, 0), dp/dv = (0, 2, 0), uv = (0.3, 0.6).
usage: /work/venv-mi/bin/python tools/mitsuba_maps_ref.py"""
import numpy as np, mitsuba as mi
mi.set_variant("scalar_rgb")
diffuse = {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.5}}
nmap = mi.load_dict({"type": "normalmap", "nested": diffuse, "normalmap": {
    "type": "bitmap", "raw": True, "bitmap": mi.Bitmap(np.array([[[0.8, 0.4, 0.9]]], dtype=np.float32))}})
height = np.array([[0.1, 0.5, 0.3], [0.9, 0.2, 0.6]], dtype=np.float32)[..., None]
bump = mi.load_dict({"type": "bumpmap", "scale": 0.3, "nested": diffuse,
                     "tex": {"type": "bitmap", "raw": True, "bitmap": mi.Bitmap(height)}})
si = mi.SurfaceInteraction3f()
si.p = [0, 0, 0]; si.n = [0, 0, 1]; si.sh_frame = mi.Frame3f([0, 0, 1])
si.dp_du = [2, 0, 0]; si.dp_dv = [0, 2, 0]; si.uv = [0.3, 0.6]
ctx = mi.BSDFContext()
def unit(v):
    v = np.array(v, dtype=np.float64); return v / np.linalg.norm(v)
viewers = [unit(v) for v in ([0.1, 0.2, 1], [-0.7, 0.3, 0.4], [0.6, -0.5, 0.2])]
lights = [unit(v) for v in ([0, 0, 1], [0.5, 0.5, 0.7], [-0.8, 0.1, 0.15], [0.9, 0.3, -0.08], [0.2, -0.9, 0.1])]
for kind, b in (("normal", nmap), ("bump", bump)):
    for v in viewers:
        si.wi = mi.Vector3f(*v)
        for l in lights:
            f = b.eval(ctx, si, mi.Vector3f(*l))
            print(kind, *("%.9g" % x for x in v), *("%.9g" % x for x in l), "%.9g" % f[0])
