#!/usr/bin/env python3
"""Time Mitsuba 3's ray queries (Embree, through `llvm_ad_rgb`) on the rays that
`cargo bench --bench intersect_many -- SCENE.xml --dump DIR` traced, to compare the two
renderers' traversal on the same rays, one thread each.

usage: .venv/bin/python bench/embree_rays.py SCENE.xml DIR [--rounds N] [--threads N] [--shuffle]
       [--repeat N]

For each of DIR/STEM-{camera,bounces,first,shadow}.f32 (seven little-endian f32 a ray: origin,
direction, end distance) it prints ns a ray for `ray_intersect_preliminary` (Embree's closest
hit alone), `ray_intersect` (with the surface interaction) and `ray_test` (occlusion), the
minimum over the rounds, each evaluated (Dr.Jit is lazy) after an untimed warm-up that compiles
its kernel; and how many rays hit, to check that both renderers saw the same scene.

--single N --set NAME: instead, N of NAME's rays, evenly spaced through the file, one at a
time through `scalar_rgb` (Embree's `rtcIntersect1`, as a single ray), untimed, for
callgrind, which counts Embree's instructions a ray:
    valgrind --tool=callgrind --branch-sim=yes python bench/embree_rays.py SCENE.xml DIR
        --single 20000 --set first
and read the inclusive count of `BVHNIntersector1<...>::intersect` (valgrind has no AVX-512,
so Embree runs its AVX2 kernels, as mcrt does under `MCRT_MAX_ISA=avx2`).
"""
import argparse
import glob
import os
import sys
import time

for _llvm in sorted(glob.glob("/usr/lib/*/libLLVM.so.19*"))[:1]:
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", _llvm)

import numpy as np  # noqa: E402
import mitsuba as mi  # noqa: E402
import drjit as dr  # noqa: E402


def timed(f, rounds):
    """Minimum seconds of `f()` evaluated, over `rounds` runs after one warm-up."""
    dr.eval(f())
    dr.sync_thread()
    best = float("inf")
    for _ in range(rounds):
        t = time.perf_counter()
        out = f()
        dr.eval(out)
        dr.sync_thread()
        best = min(best, time.perf_counter() - t)
    return best, out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("dir")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=1,
                    help="trace each sixteen consecutive rays N times over (warm caches)")
    ap.add_argument("--shuffle", action="store_true",
                    help="trace the rays in a random order (fixed seed), not as written")
    ap.add_argument("--single", type=int, metavar="N",
                    help="trace N rays of --set one at a time through scalar_rgb, untimed")
    ap.add_argument("--set", default="first", choices=["camera", "bounces", "first"],
                    help="the set --single traces (default first)")
    a = ap.parse_args()
    if a.single is not None:
        if a.single < 1:
            ap.error("--single must be at least 1")
        return single(a)
    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(a.threads)
    scene = mi.load_file(os.path.abspath(a.scene))
    stem = os.path.splitext(os.path.basename(a.scene))[0]
    for name in ("camera", "bounces", "first", "shadow"):
        raw = np.fromfile(os.path.join(a.dir, f"{stem}-{name}.f32"), dtype="<f4").reshape(-1, 7)
        if a.repeat > 1:
            m = len(raw) // 16 * 16
            raw = np.repeat(raw[:m].reshape(-1, 1, 16, 7), a.repeat, axis=1).reshape(-1, 7)
        if a.shuffle:
            raw = raw[np.random.default_rng(1).permutation(len(raw))]
        n = len(raw)
        o = mi.Point3f(*(mi.Float(np.ascontiguousarray(raw[:, i])) for i in range(3)))
        d = mi.Vector3f(*(mi.Float(np.ascontiguousarray(raw[:, 3 + i])) for i in range(3)))
        ray = mi.Ray3f(o, d, mi.Float(np.ascontiguousarray(raw[:, 6])), 0.0, [])
        dr.eval(ray)
        if name == "shadow":
            t, hit = timed(lambda: scene.ray_test(ray), a.rounds)
            print(f"{name}: {n} rays ({int(dr.count(hit)[0])} blocked), ray_test {t * 1e9 / n:.1f} ns/ray")
            continue
        tp, pi = timed(lambda: scene.ray_intersect_preliminary(ray).t, a.rounds)
        ts, _ = timed(lambda: scene.ray_intersect(ray, mi.RayFlags.All, False).p, a.rounds)
        hits = int(dr.count(dr.isfinite(pi))[0])
        print(f"{name}: {n} rays ({hits} hit), ray_intersect_preliminary {tp * 1e9 / n:.1f} "
              f"ns/ray, ray_intersect {ts * 1e9 / n:.1f} ns/ray")


def single(a):
    """N rays of a set, evenly spaced, each through `rtcIntersect1` (see the module's
    documentation); prints how many hit."""
    mi.set_variant("scalar_rgb")
    scene = mi.load_file(os.path.abspath(a.scene))
    stem = os.path.splitext(os.path.basename(a.scene))[0]
    path = os.path.join(a.dir, f"{stem}-{a.set}.f32")
    if not os.path.isfile(path):
        print(f"{path}: no such file (write it with intersect_many's --dump {a.dir})",
              file=sys.stderr)
        sys.exit(2)
    raw = np.fromfile(path, dtype="<f4").reshape(-1, 7)
    raw = raw[::max(1, len(raw) // a.single)][:a.single]
    rays = [mi.Ray3f(mi.Point3f(*map(float, x[:3])), mi.Vector3f(*map(float, x[3:6])),
                     float(x[6])) for x in raw]
    hits = sum(bool(scene.ray_intersect_preliminary(r).is_valid()) for r in rays)
    print(f"{a.set}: {len(rays)} rays one at a time ({hits} hit)")


if __name__ == "__main__":
    main()
