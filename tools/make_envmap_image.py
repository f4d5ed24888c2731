#!/usr/bin/env python3
"""Writes the environment map of the envmap feature scene (tests/data/mitsuba/features/):
sky.hdr (Radiance RGBE, written by Mitsuba's Bitmap) and sky.exr (the same values as float
OpenEXR, read back from the .hdr so that both files hold the same radiance), 64x32 pixels
in Mitsuba's latitude-longitude layout (row 0 = straight up, column 0 = looking along -z).

usage: /work/venv-mi/bin/python tools/make_envmap_image.py [OUT_DIR]
"""
import os, sys, glob, math
for _llvm in glob.glob("/usr/lib/*/libLLVM.so.19*")[:1]:
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", _llvm)
import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
out = sys.argv[1] if len(sys.argv) > 1 else "tests/data/mitsuba/features"
W, H = 64, 32
img = np.zeros((H, W, 3), dtype=np.float32)
for y in range(H):
    theta = math.pi * y / (H - 1)          # 0 = up
    for x in range(W):
        phi = 2 * math.pi * (x + 0.5) / W  # 0 = -z, pi/2 = +x
        if theta < math.pi / 2:
            # Sky: brighter and bluer towards the zenith, warmer towards +x.
            t = math.cos(theta)
            warm = 0.5 + 0.5 * math.sin(phi)
            img[y, x] = [0.3 + 0.5 * warm * (1 - t), 0.5 + 0.3 * t, 0.9 + 0.6 * t]
        else:
            # Ground: dark and brown, a green quarter (towards -x).
            green = 1.0 if 1.25 * math.pi < phi < 1.75 * math.pi else 0.0
            img[y, x] = [0.15 - 0.1 * green, 0.1 + 0.15 * green, 0.05]
# A small sun, towards +x and up about 45 degrees.
for (y, x, v) in [(8, 16, 250.0), (8, 17, 120.0), (7, 16, 80.0)]:
    img[y, x] = [v, 0.9 * v, 0.7 * v]
hdr = os.path.join(out, "sky.hdr")
mi.Bitmap(img).write(hdr)
back = np.array(mi.Bitmap(hdr), dtype=np.float32)
mi.Bitmap(back).write(os.path.join(out, "sky.exr"))
print(f"wrote {hdr} and sky.exr; max abs difference from the design {np.abs(back - img).max():.3g}")
