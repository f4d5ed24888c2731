"""Notebook-style tour of the Python module: render the Cornell box, look at it, measure its noise.

After `pip install .` at the repository root (tqdm and matplotlib are used if installed):

    python examples/python_render.py

The images are written to the current directory.
"""

import pathlib

import numpy as np

import mcrt

SCENE = pathlib.Path(__file__).resolve().parent.parent / "scenes" / "cornell-box.toml"

# Load once (the BVH is built here), render as often as needed.
scene = mcrt.load(SCENE)
print(scene)

# Two renders with different seeds: float32 arrays (height, width, 3), linear RGB, the same bits
# `mcrt render --seed S` would write to an EXR.
a = mcrt.render(scene, spp=16, width=128, height=128, seed=1, progress=True)
b = mcrt.render(scene, spp=16, width=128, height=128, seed=2, progress=True)

# Their difference estimates the noise: each has an RMSE of about the RMSE between them / sqrt(2).
m = mcrt.compare(a, b)
print(f"RMSE between two 16-spp renders: {m.rmse:.4f} (PSNR {m.psnr:.1f} dB)")

# AOVs come as a dict of arrays: the denoiser guides and per-pixel statistics.
d = mcrt.render(scene, spp=16, width=128, height=128, seed=1, aovs=["albedo", "normal", "variance"])
assert np.array_equal(d["image"], a)
print(f"mean estimated variance of the pixel means: {d['variance'].mean():.2e}")

mean = (a + b) / 2  # 32 spp: the average of the two
try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    plt = None

if plt is not None:
    srgb = lambda x: np.clip(x, 0, 1) ** (1 / 2.2)
    fig, ax = plt.subplots(1, 3, figsize=(12, 4))
    for axis, (title, img) in zip(ax, [("32 spp", srgb(mean)), ("albedo", d["albedo"]),
                                        ("normal", d["normal"] * 0.5 + 0.5)]):
        axis.imshow(np.clip(img, 0, 1))
        axis.set_title(title)
        axis.axis("off")
    fig.savefig("cornell-python.png", bbox_inches="tight")
    print("wrote cornell-python.png (matplotlib)")
else:
    mcrt.write("cornell-python.png", mean)  # 8-bit sRGB, as `mcrt render -o x.png`
    mcrt.write("cornell-python-albedo.png", d["albedo"])
    mcrt.write("cornell-python.exr", mean, aovs=d)  # linear float, with the AOV layers
    print("wrote cornell-python.png, cornell-python-albedo.png and cornell-python.exr")
