#!/usr/bin/env python3
"""Side-by-side benchmark of mcrt and Mitsuba 3 on one machine, in one run.

For the Cornell box and the TNCG15 room it renders, with the same resolution, samples per
pixel, path length and thread count:
  * mcrt (target/release/mcrt, built first with `cargo build --release`),
  * Mitsuba 3 `llvm_ad_rgb` and `scalar_rgb`, when the `mitsuba` Python package is installed
    (each timed on a second, warm render, so that JIT compilation is not counted),
and prints samples/s for each and the ratios. Then it measures time to equal error: the
RMSE against the reference in tests/data/refs that Mitsuba `llvm_ad_rgb` reaches at 256 spp,
and the wall time mcrt needs to reach it (mcrt renders with its Sobol sampler; its spp is
found by doubling, then bisection, and the reported time is the measured one of that render).

usage: python3 bench/side_by_side.py [--quick] [--threads N]
"""
import argparse, glob, json, os, subprocess, sys, tempfile, time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
for _llvm in glob.glob("/usr/lib/*/libLLVM.so.19*")[:1]:
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", _llvm)
try:
    import mitsuba as mi
    import numpy as np
except ImportError:
    mi = None
    import numpy as np

MCRT = os.path.join(ROOT, "target/release/mcrt")

SCENES = {
    # name: (mcrt scene, mitsuba scene, reference (256²), resolution of the rate test, depth)
    "cornell": ("scenes/cornell-box.toml", "tests/data/mitsuba/cornell-box.xml",
                "tests/data/refs/cornell-box.exr", 512, 8),
    "tncg15": ("scenes/tncg15.toml", "tests/data/mitsuba/hexroom/hexroom.xml",
               "tests/data/refs/hexroom-eye1.exr", 256, -1),
}


def read_exr(path):
    if mi is not None:
        return np.array(mi.Bitmap(path), dtype=np.float64)[:, :, :3]
    raise SystemExit("reading EXR needs the mitsuba package")


def rmse(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)))


def mcrt_render(scene, res, spp, depth, threads, sampler="independent", out=None):
    out = out or tempfile.mktemp(suffix=".exr")
    cmd = [MCRT, "render", os.path.join(ROOT, scene), "-o", out, "--width", str(res),
           "--height", str(res), "--spp", str(spp), "--max-depth", str(depth),
           "--threads", str(threads), "--sampler", sampler, "--camera"]
    cmd.append("eye1" if "tncg15" in scene else "main")
    t = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    return time.perf_counter() - t, out


def mitsuba_render(variant, scene, res, spp, depth, threads):
    mi.set_variant(variant)
    mi.set_log_level(mi.LogLevel.Warn)
    path = os.path.join(ROOT, scene)
    text = open(path).read()
    # Both files render 256×256 (hexroom.xml through its `res` default); change the film.
    text = text.replace('name="width" value="256"', f'name="width" value="{res}"')
    text = text.replace('name="height" value="256"', f'name="height" value="{res}"')
    text = text.replace('name="res" value="256"', f'name="res" value="{res}"')
    s = mi.load_string(text.replace('filename" value="', 'filename" value="' + os.path.dirname(path) + "/"))
    integ = mi.load_dict({"type": "path", "max_depth": depth})
    assert list(s.sensors()[0].film().size()) == [res, res]
    mi.render(s, integrator=integ, spp=spp, seed=99)  # warm-up: JIT compilation
    t = time.perf_counter()
    img = np.array(mi.render(s, integrator=integ, spp=spp, seed=0), dtype=np.float64)[:, :, :3]
    return time.perf_counter() - t, img


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="fewer samples (a smoke test)")
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    a = ap.parse_args()
    spp_rate = 16 if a.quick else 64
    base_spp = 64 if a.quick else 256
    if mi is not None:
        mi.set_variant("scalar_rgb")
        import drjit as dr
        dr.set_thread_count(a.threads)
    print(f"machine: {os.cpu_count()} cores, threads {a.threads}; mitsuba "
          f"{mi.__version__ if mi else 'not installed'}")
    results = {}
    for name, (msc, xsc, ref, res, depth) in SCENES.items():
        pixels = res * res
        r = {}
        t, _ = mcrt_render(msc, res, spp_rate, depth, a.threads)
        r["mcrt samples/s"] = pixels * spp_rate / t
        if mi is not None:
            for v in ("llvm_ad_rgb", "scalar_rgb"):
                spp_v = spp_rate if v == "llvm_ad_rgb" else max(4, spp_rate // 8)
                t, _ = mitsuba_render(v, xsc, res, spp_v, depth, a.threads)
                r[f"mitsuba {v} samples/s"] = pixels * spp_v / t
            r["ratio vs llvm_ad_rgb"] = r["mcrt samples/s"] / r["mitsuba llvm_ad_rgb samples/s"]
            r["ratio vs scalar_rgb"] = r["mcrt samples/s"] / r["mitsuba scalar_rgb samples/s"]
            # Time to equal error.
            reference = read_exr(os.path.join(ROOT, ref))
            res = 256  # the references' resolution
            pixels = res * res
            t_mi, img = mitsuba_render("llvm_ad_rgb", xsc, res, base_spp, depth, a.threads)
            target = rmse(img, reference)
            r["mitsuba llvm: spp, s, RMSE"] = (base_spp, t_mi, target)
            lo, hi, found = 0, 8, None
            while True:
                t, out = mcrt_render(msc, res, hi, depth, a.threads, "sobol")
                e = rmse(read_exr(out), reference)
                if e <= target:
                    found = (hi, t, e)
                    break
                lo, hi = hi, hi * 2
                if hi > 64 * base_spp:
                    break
            while found and hi - lo > max(1, hi // 16):
                mid = (lo + hi) // 2
                t, out = mcrt_render(msc, res, mid, depth, a.threads, "sobol")
                e = rmse(read_exr(out), reference)
                if e <= target:
                    hi, found = mid, (mid, t, e)
                else:
                    lo = mid
            r["mcrt sobol: spp, s, RMSE"] = found
            if found:
                r["time to equal error vs llvm_ad_rgb"] = found[1] / t_mi
        results[name] = r
        print(f"\n{name} (rate at {SCENES[name][3]}², error at 256², max depth {depth}):")
        for k, v in r.items():
            print(f"  {k}: {v if not isinstance(v, float) else round(v, 4)}")
    with open(os.path.join(tempfile.gettempdir(), "mcrt-side-by-side.json"), "w") as f:
        json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
