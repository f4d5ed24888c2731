#!/usr/bin/env python3
"""Writes the textures of tests/data/mitsuba/features/maps-mask.xml (8-bit PNGs, read raw):
maps-normal.png, a tangent-space normal map of bumps; maps-height.png, a height field of
stripes; maps-leaf.png, a leaf-shaped opacity (1 inside, 0 outside, a half-opaque band).
usage: make_maps_textures.py OUTDIR   (needs numpy and Mitsuba 3 for the PNG writer)"""
import sys, numpy as np, mitsuba as mi
mi.set_variant("scalar_rgb")
out = sys.argv[1]
def png(name, a):
    mi.Bitmap(np.ascontiguousarray(np.clip(np.rint(a * 255), 0, 255).astype(np.uint8))).write(f"{out}/{name}")
# Normal map: n = normalize(-dh/dx, -dh/dy, 1) of h = 0.35 sin(2πx·3) sin(2πy·2), 48×48.
w = 48
y, x = (np.mgrid[0:w, 0:w] + 0.5) / w
hx = 0.35 * 2 * np.pi * 3 * np.cos(2 * np.pi * 3 * x) * np.sin(2 * np.pi * 2 * y)
hy = 0.35 * 2 * np.pi * 2 * np.sin(2 * np.pi * 3 * x) * np.cos(2 * np.pi * 2 * y)
n = np.stack([-hx, -hy, np.ones_like(hx)], -1)
n /= np.linalg.norm(n, axis=-1, keepdims=True)
png("maps-normal.png", 0.5 * n + 0.5)
# Height: stripes in u and v, 64×32 (gray).
y, x = (np.mgrid[0:32, 0:64] + 0.5) / np.array([32, 64])[:, None, None]
h = 0.5 + 0.25 * np.sin(2 * np.pi * 6 * x) + 0.25 * np.sin(2 * np.pi * 4 * y)
png("maps-height.png", h[..., None])
# Leaf opacity, 32×32 (gray): an ellipse around the diagonal, a half-opaque rim, a vein cut out.
y, x = (np.mgrid[0:32, 0:32] + 0.5) / 32 * 2 - 1
a, b = (x + y) / np.sqrt(2), (y - x) / np.sqrt(2)
r = (a / 0.95) ** 2 + (b / 0.5) ** 2
alpha = np.where(r < 0.6, 1.0, np.where(r < 1.0, 0.5, 0.0))
alpha[np.abs(b) < 0.04] = 0.0
png("maps-leaf.png", alpha[..., None])
