#!/usr/bin/env python3
"""Side-by-side benchmark of mcrt and Mitsuba 3 on one machine, in one run.

Both renderers read the same Mitsuba 3 XML file for each scene (the script writes a copy with
the film size, sample count and sampler set, and file names made absolute, to bench/out/run/)
and render it with the same resolution, samples per pixel, path length and thread count.

1. Rate: samples per second of the render itself (scene loading and the acceleration
   structure's build are reported apart), both with independent random numbers, each
   renderer's fastest of --rate-runs renders (3) made in turns with the other's, as the
   host's load moves one render's time by 10-20 %. mcrt's time is the one it prints for
   its render; Mitsuba's is that of `mi.render` evaluated to a NumPy
   array, after a warm-up render that is itself evaluated (Dr.Jit is lazy: an unevaluated
   warm-up would run inside the timed render) and after which the timed render must compile no
   kernel (checked in Dr.Jit's kernel history; otherwise it is timed again). Mitsuba's
   `llvm_ad_rgb` and `scalar_rgb` are both measured and the faster one is Mitsuba's figure.
2. Time to equal error, each renderer with its best sampler: RMSE against a reference
   (tests/data/refs for the Cornell box and the TNCG15 room; for the generated scenes a
   Mitsuba render at --ref-spp, cached in bench/out/refs/). Mitsuba renders the base spp with
   `independent`, `multijitter` and `ldsampler` (its fastest variant); the one with the lowest
   RMSE sets the target RMSE and Mitsuba's time. mcrt, with `independent` and with `sobol`,
   renders the base spp too; with each sampler whose time projected to the target (RMSE ∝
   1/√spp) is within a third of the best projection, it searches the fewest spp that reach
   that RMSE (a first guess from the projection, steps of an eighth, then bisection to a
   32nd; at most 32 times the base spp). The ratio takes mcrt's faster sampler, and each
   side's time is the fastest of --error-runs renders (3) at its spp, made in turns with
   the other's (the fixed seeds give the same image, so the same error, every time).

usage: .venv/bin/python bench/side_by_side.py [--quick] [--threads N] [--scenes a,b,...]
                                               [--max-isa avx2] [--rate-runs N]
                                               [--error-runs N]
       .venv/bin/python bench/side_by_side.py --validate SPP   (image means of both, no timing)
--max-isa avx2 times both renderers as an AVX2 host runs them, on an AVX-512 host: mcrt with
MCRT_MAX_ISA=avx2 (no AVX-512 kernel), Mitsuba's Dr.Jit generating code for znver3 (AVX2, eight
lanes, through its `jit_llvm_set_target`) and its Embree with max_isa=avx2 (a small preloaded
library, bench/embree_max_isa.c, compiled with cc, adds it to the device's configuration).

Needs: pip install mitsuba numpy; Debian's libllvm19 for Mitsuba's LLVM variant; cargo (the
script runs `cargo build --release` unless --no-build). The generated scenes are made by
bench/make_scenes.py when missing.
"""
import argparse
import glob
import hashlib
import json
import os
import platform
import re
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "bench", "out")
MCRT = os.path.join(ROOT, "target", "release", "mcrt")
for _llvm in sorted(glob.glob("/usr/lib/*/libLLVM.so.19*"))[:1]:
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", _llvm)

import numpy as np  # noqa: E402

try:
    import mitsuba as mi  # noqa: E402
    import drjit as dr  # noqa: E402
except ImportError:
    sys.exit("the benchmark needs Mitsuba 3: pip install mitsuba numpy (see docs/performance.md)")

GENERATED = os.path.join(OUT, "scenes")
# name: (XML scene, reference EXR at ERR_RES² or None to render one, resolution of the rate test)
SCENES = {
    "cornell": ("tests/data/mitsuba/cornell-box.xml", "tests/data/refs/cornell-box.exr", 512),
    "tncg15": ("tests/data/mitsuba/hexroom/hexroom.xml", "tests/data/refs/hexroom-eye1.exr", 256),
    "bunny-box": (os.path.join(GENERATED, "bunny-box.xml"), None, 256),
    "gallery": (os.path.join(GENERATED, "gallery.xml"), None, 256),
    "materials-box": (os.path.join(GENERATED, "materials-box.xml"), None, 256),
}
TITLES = {
    "cornell": "Cornell box",
    "tncg15": "TNCG15 room",
    "bunny-box": "Cornell box with the bunny",
    "gallery": "gallery (850 k triangles)",
    "materials-box": "Cornell box in five BSDFs",
}
ERR_RES = 256  # the references' resolution
MITSUBA_SAMPLERS = ("independent", "multijitter", "ldsampler")
MCRT_SAMPLERS = ("independent", "sobol")
SEED_RATE, SEED_ERR, SEED_REF = 0, 1, 1_000_000


def scene_xml(name, src, res, spp, sampler):
    """Writes bench/out/run/NAME.xml: SRC with the film at RES², SPP samples of SAMPLER and
    file names made absolute, so that the copy loads from anywhere in both renderers."""
    tree = ET.parse(src)
    base = os.path.dirname(os.path.abspath(src))
    for el in tree.getroot().iter():
        key = "filename" if el.tag == "include" else "value"
        if el.tag == "include" or (el.tag == "string" and el.get("name") == "filename"):
            v = el.get(key)
            if v and "$" not in v and not os.path.isabs(v):
                el.set(key, os.path.normpath(os.path.join(base, v)))
    if tree.getroot().find("integrator") is None:  # mcrt's default; Mitsuba needs one named
        ET.SubElement(tree.getroot(), "integrator", type="path")
    sensors = tree.getroot().findall("sensor")
    if len(sensors) != 1:
        sys.exit(f"{src}: the benchmark needs exactly one sensor at the top level")
    # Mitsuba's defaults where the file has no film or sampler: hdrfilm and independent.
    film = sensors[0].find("film")
    if film is None:
        film = ET.SubElement(sensors[0], "film", type="hdrfilm")
    smp = sensors[0].find("sampler")
    if smp is None:
        smp = ET.SubElement(sensors[0], "sampler")
    smp.set("type", sampler)
    for parent, prop, value in ((film, "width", res), (film, "height", res),
                                (smp, "sample_count", spp)):
        el = parent.find(f"integer[@name='{prop}']")
        if el is None:
            el = ET.SubElement(parent, "integer", name=prop)
        el.set("value", str(value))
    os.makedirs(os.path.join(OUT, "run"), exist_ok=True)
    out = os.path.join(OUT, "run", f"{name}.xml")
    tree.write(out, encoding="utf-8", xml_declaration=True)
    return out


def read_exr(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[:, :, :3]


def rmse(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)))


def mcrt_render(xml, sampler, seed, threads):
    """Renders with mcrt; returns (render seconds, load seconds, image)."""
    out = xml[:-4] + ".mcrt.exr"
    cmd = [MCRT, "render", xml, "-o", out, "--threads", str(threads), "--sampler", sampler,
           "--seed", str(seed)]
    env = {k: v for k, v in os.environ.items() if k != "LD_PRELOAD"}
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr}")
    m = re.search(r"(\d+)x(\d+) at (\d+) spp .*loaded in ([0-9.]+) s\) in ([0-9.]+) s", p.stderr)
    if not m:
        sys.exit(f"mcrt printed no timing line:\n{p.stderr}")
    img = read_exr(out)
    sensor = ET.parse(xml).getroot().find("sensor")
    asked = [sensor.find(f"film/integer[@name='{k}']").get("value") for k in ("width", "height")]
    asked.append(sensor.find("sampler/integer[@name='sample_count']").get("value"))
    if list(m.group(1, 2, 3)) != asked or (int(m.group(2)), int(m.group(1))) != img.shape[:2]:
        sys.exit(f"mcrt rendered {m.group(0)}, not what {xml} asks")
    # mcrt prints hundredths of a second: the renders timed here take a second or more.
    return max(float(m.group(5)), 0.005), float(m.group(4)), img


def jit_compiles():
    """Kernels compiled (not found in Dr.Jit's caches) since the last call, and the
    milliseconds that took."""
    ks = [k for k in dr.kernel_history()
          if k.get("type") == dr.KernelType.JIT and not k.get("cache_hit", 1)]
    return len(ks), sum(k.get("codegen_time", 0) + k.get("backend_time", 0) for k in ks)


def mitsuba_renderer(variant, xml, seed):
    """Loads a scene into Mitsuba and warms it up; returns (load seconds, render), where
    `render()` renders it timed, warm, and returns (seconds, image). A four-sample warm-up
    compiles the kernels and is evaluated first. (`mi.render(spp=...)` sets the sampler's
    count for good, so every call passes it.)"""
    mi.set_variant(variant)
    mi.set_log_level(mi.LogLevel.Warn)
    t = time.perf_counter()
    scene = mi.load_file(xml)
    load = time.perf_counter() - t
    spp = scene.sensors()[0].sampler().sample_count()

    def render(spp_, seed_):
        img = np.array(mi.render(scene, spp=spp_, seed=seed_), dtype=np.float64)
        dr.sync_thread()
        return img

    render(4, seed + 7919)  # warm-up, evaluated (4: square and a power of two, as ldsampler wants)

    def timed():
        # Mitsuba's kernels depend on the sample count: for `independent` only on whether it
        # is a power of two (a 4-spp warm-up serves 64 and 256), for `multijitter` and
        # `ldsampler` on the count itself. Where the warm-up missed a kernel, the full
        # render was the warm-up.
        mi.set_variant(variant)
        for attempt in range(3):
            jit_compiles()
            t = time.perf_counter()
            img = render(spp, seed)
            secs = time.perf_counter() - t
            n, ms = jit_compiles()
            if not variant.startswith("llvm") or n == 0:
                break
            print(f"  ({variant} compiled {n} kernel(s) in {ms:.0f} ms during the timed render, "
                  f"{secs:.2f} s; " + ("timing it again)" if attempt < 2 else "kept)"), flush=True)
        return secs, img[:, :, :3]

    return load, timed


def mitsuba_render(variant, xml, seed):
    """Loads and renders with Mitsuba (see `mitsuba_renderer`); returns (render seconds, load
    seconds, image)."""
    load, timed = mitsuba_renderer(variant, xml, seed)
    secs, img = timed()
    return secs, load, img


def reference(name, src, ref_spp, variant):
    """The cached Mitsuba reference of a generated scene at ERR_RES², or renders it (in passes
    of 256 spp, so that the LLVM variant's wavefront stays small)."""
    step = min(256, ref_spp)
    xml = scene_xml(name + "-ref", src, ERR_RES, step, "independent")
    # The cache key: the scene and every file it names (meshes, textures, includes).
    h = hashlib.sha1(open(xml, "rb").read())
    for el in ET.parse(xml).getroot().iter():
        f = el.get("filename") if el.tag == "include" else (
            el.get("value") if el.tag == "string" and el.get("name") == "filename" else None)
        if f and os.path.isfile(f):
            h.update(open(f, "rb").read())
    path = os.path.join(OUT, "refs", f"{name}-{ERR_RES}-{ref_spp}-{h.hexdigest()[:10]}.exr")
    if os.path.exists(path):
        return read_exr(path)
    print(f"  rendering the reference ({ref_spp} spp with {variant}; cached in {path})", flush=True)
    mi.set_variant(variant)
    scene = mi.load_file(xml)
    acc, done = 0.0, 0
    while done < ref_spp:
        n = min(step, ref_spp - done)
        acc = acc + n * np.array(mi.render(scene, spp=n, seed=SEED_REF + done), dtype=np.float64)
        done += n
    os.makedirs(os.path.dirname(path), exist_ok=True)
    mi.Bitmap((acc / done).astype(np.float32)).write(path)
    return read_exr(path)[:, :, :3]


def mcrt_equal_error(name, src, sampler, target, base, threads):
    """The fewest spp (to within a 32nd; at most 32 times the base spp) at which mcrt's RMSE
    reaches TARGET: a first guess from its error at the base spp (RMSE ∝ 1/√spp), steps of an
    eighth up or down, then bisection. BASE is the base render's (spp, seconds, RMSE), taken
    as the first guess where the guess lies within a sixteenth of it. Returns (spp, seconds,
    RMSE) of the render that reached it, or None."""
    def at(spp):
        secs, _, img = mcrt_render(scene_xml(f"{name}-mcrt-{sampler}", src, ERR_RES, spp, sampler),
                                   sampler, SEED_ERR, threads)
        return spp, secs, rmse(img, REF[name])

    cap = 32 * base[0]
    spp = min(max(4, int(round(base[0] * (base[2] / target) ** 2))), cap)
    if abs(spp - base[0]) <= base[0] / 16:
        spp = base[0]
    found, failed, tried = None, None, base if spp == base[0] else at(spp)
    going_up = tried[2] > target
    for _ in range(24):
        if tried[2] <= target:
            found = tried
            if going_up:
                break
        else:
            failed = tried[0]
            if not going_up:
                break
        nxt = min(max(1, int(round(spp * (9 / 8 if going_up else 7 / 8)))), cap)
        if nxt == spp:
            break
        spp = nxt
        tried = at(spp)
    # Bisect between the last spp that failed and the first that reached, to a 32nd.
    while found and failed and found[0] - failed > max(1, found[0] // 32):
        tried = at((found[0] + failed) // 2)
        if tried[2] <= target:
            found = tried
        else:
            failed = tried[0]
    return found


def equal_error_times(name, src, mc, mi_, n, threads):
    """The two times of the equal-error column, each the fastest of N renders made in turns
    (as the rate test's; the images, and so the errors, are the same every time: fixed
    seeds). MC is mcrt's (sampler, spp, seconds) that reached the target, MI_ Mitsuba's
    (variant, sampler, spp, seconds) that set it. Returns (mcrt s, Mitsuba s, every time)."""
    mc_s, mc_spp, mc_t = mc
    variant, mi_s, mi_spp, mi_t = mi_
    times = {"mcrt": [mc_t], "mitsuba": [mi_t]}
    if n > 1:
        mc_xml = scene_xml(f"{name}-mcrt-{mc_s}", src, ERR_RES, mc_spp, mc_s)
        mi_xml = scene_xml(f"{name}-mi-{mi_s}", src, ERR_RES, mi_spp, mi_s)
        _, timed = mitsuba_renderer(variant, mi_xml, SEED_ERR)
        for _ in range(n - 1):
            times["mcrt"].append(mcrt_render(mc_xml, mc_s, SEED_ERR, threads)[0])
            times["mitsuba"].append(timed()[0])
    print(f"  equal error, fastest of {n} (slowest/fastest): mcrt {mc_s} {mc_spp} spp "
          f"{min(times['mcrt']):.2f} s ({max(times['mcrt']) / min(times['mcrt']):.2f}), "
          f"Mitsuba {mi_s} {mi_spp} spp {min(times['mitsuba']):.2f} s "
          f"({max(times['mitsuba']) / min(times['mitsuba']):.2f})", flush=True)
    return min(times["mcrt"]), min(times["mitsuba"]), times


REF = {}


def validate(names, res, spp, threads):
    """Both renderers on each scene at RES², SPP: the relative difference of the images'
    means, and how many standard errors it is (from the pixels' differences, which are
    independent across pixels with independent samplers and distinct seeds)."""
    print(f"| scene | Mitsuba mean | mcrt mean | mcrt / Mitsuba − 1 | standard errors |\n"
          f"|---|---|---|---|---|")
    for name in names:
        src = os.path.join(ROOT, SCENES[name][0])
        xml = scene_xml(name + "-validate", src, res, spp, "independent")
        _, _, a = mcrt_render(xml, "independent", SEED_RATE, threads)
        _, _, b = mitsuba_render("llvm_ad_rgb", xml, SEED_ERR)
        d = (a - b).mean(axis=2).ravel()
        se = d.std(ddof=1) / np.sqrt(d.size)
        print(f"| {TITLES[name]}, {res}², {spp} spp | {b.mean():.5f} | {a.mean():.5f} | "
              f"{a.mean() / b.mean() - 1:+.4f} | {d.mean() / se:+.2f} |", flush=True)


def cap_isa(isa):
    """Both renderers limited to ISA (only "avx2"): mcrt by MCRT_MAX_ISA; Mitsuba's Embree by
    the preloaded bench/embree_max_isa.c (the script runs itself again with it preloaded), its
    Dr.Jit by a target without AVX-512. Returns a line saying what each runs."""
    shim = os.path.join(OUT, "embree_max_isa.so")
    if os.environ.get("LD_PRELOAD") != shim:
        os.makedirs(OUT, exist_ok=True)
        subprocess.run(["cc", "-shared", "-fPIC", "-O2", "-o", shim,
                        os.path.join(ROOT, "bench", "embree_max_isa.c"), "-ldl"], check=True)
        os.environ.update(LD_PRELOAD=shim, EMBREE_MAX_ISA=isa)
        os.execv(sys.executable, [sys.executable] + sys.argv)
    os.environ["MCRT_MAX_ISA"] = isa
    import ctypes
    core = ctypes.CDLL(os.path.join(os.path.dirname(dr.__file__), "libdrjit-core.so"))
    # jit.h's C++ names: jit_llvm_set_target, jit_llvm_target_cpu, jit_llvm_vector_width.
    set_target = core._Z19jit_llvm_set_targetPKcS0_j
    set_target.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint32]
    cpu = core._Z19jit_llvm_target_cpuv
    cpu.restype = ctypes.c_char_p
    width = core._Z21jit_llvm_vector_widthv
    width.restype = ctypes.c_uint32
    mi.set_variant("llvm_ad_rgb")
    dr.eval(dr.llvm.Float(1.0) + 1)  # the LLVM backend started, so that the target sticks
    set_target(b"znver3", None, 8)
    return (f"ISA capped at {isa}: mcrt MCRT_MAX_ISA={isa}; Mitsuba's Dr.Jit targets "
            f"{cpu().decode()} with {width()} lanes, its Embree max_isa={isa}")


def cpu_line():
    model, flags = platform.processor() or "unknown CPU", set()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
            elif line.startswith("flags"):
                flags = set(line.split(":", 1)[1].split())
    except OSError:
        pass
    shown = [f for f in ("sse4_2", "avx", "avx2", "fma", "bmi2", "avx512f", "avx512dq",
                         "avx512bw", "avx512vl", "avx512vbmi") if f in flags]
    return f"{model}, {os.cpu_count()} logical CPUs; flags: {' '.join(shown) or 'none of interest'}"


def main():
    ap = argparse.ArgumentParser(description="mcrt against Mitsuba 3, side by side")
    ap.add_argument("--quick", action="store_true", help="fewer samples (a smoke test)")
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--scenes", default=",".join(SCENES), help="comma-separated subset of "
                    + ", ".join(SCENES))
    ap.add_argument("--ref-spp", type=int, help="spp of the generated scenes' references "
                    "(default 4096; 1024 with --quick)")
    ap.add_argument("--no-build", action="store_true", help="do not run cargo build --release")
    ap.add_argument("--rate-runs", type=int, default=3, help="renders of the rate test a "
                    "renderer, taking turns; each renderer's fastest counts (default 3)")
    ap.add_argument("--error-runs", type=int, default=3, help="renders of each renderer at "
                    "its equal-error sample count, taking turns; each one's fastest counts "
                    "(default 3)")
    ap.add_argument("--validate", type=int, metavar="SPP", help="instead of timing, compare "
                    "the two renderers' image means at --validate-res² with SPP samples")
    ap.add_argument("--validate-res", type=int, default=64)
    ap.add_argument("--json", help="where the figures go (default bench/out/side-by-side.json, "
                    "or side-by-side-avx2.json with --max-isa avx2)")
    ap.add_argument("--max-isa", choices=["avx2"], help="time both renderers as an AVX2 host "
                    "runs them (see the module's documentation)")
    a = ap.parse_args()
    if a.rate_runs < 1 or a.error_runs < 1:
        ap.error("--rate-runs and --error-runs must be at least 1")
    a.json = a.json or os.path.join(
        OUT, f"side-by-side{'-' + a.max_isa if a.max_isa else ''}.json")
    names = [n for n in a.scenes.split(",") if n]
    for n in names:
        if n not in SCENES:
            ap.error(f"unknown scene {n!r}; known: {', '.join(SCENES)}")
    if a.threads < 1:
        ap.error("--threads must be at least 1")
    for opt, v, hi in (("--ref-spp", a.ref_spp, 65536), ("--validate", a.validate, 65536),
                       ("--validate-res", a.validate_res, 4096)):
        if v is not None and not 1 <= v <= hi:
            ap.error(f"{opt} must be between 1 and {hi}")
    spp_rate, base_spp = (16, 64) if a.quick else (64, 256)
    ref_spp = a.ref_spp or (1024 if a.quick else 4096)
    if not a.no_build:
        subprocess.run(["cargo", "build", "--release", "--quiet"], cwd=ROOT, check=True)
    if any(SCENES[n][1] is None for n in names):  # deterministic, so rewriting is harmless
        subprocess.run([sys.executable, os.path.join(ROOT, "bench", "make_scenes.py")],
                       check=True, stdout=subprocess.DEVNULL)
    capped = cap_isa(a.max_isa) if a.max_isa else None
    mi.set_variant("scalar_rgb")
    dr.set_thread_count(a.threads)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    if a.validate:
        return validate(names, a.validate_res, a.validate, a.threads)
    commit = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=ROOT,
                            capture_output=True, text=True).stdout.strip()
    t_start = time.time()
    print(f"machine: {cpu_line()}; {platform.system()} {platform.release()}")
    if capped:
        print(capped)
    print(f"threads {a.threads}; mcrt {commit}; Mitsuba {mi.__version__}; "
          f"{'--quick: ' if a.quick else ''}rate at {spp_rate} spp, error at {ERR_RES}² with "
          f"{base_spp} spp; {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}", flush=True)
    results = {}
    for name in names:
        src, ref, res = SCENES[name]
        src = os.path.join(ROOT, src)
        r = results[name] = {"rate_res": res, "max_isa": a.max_isa or "native"}
        print(f"\n{name}:", flush=True)
        px = res * res
        # The renderers take turns, `--rate-runs` times, and each keeps its fastest render:
        # the host's load moves a single render's time by 10-20 %.
        xml = scene_xml(name + "-rate", src, res, spp_rate, "independent")
        spps = {"mcrt": spp_rate, "llvm_ad_rgb": spp_rate, "scalar_rgb": max(4, spp_rate // 4)}
        timers, loads, times = {}, {}, {k: [] for k in spps}
        for v in ("llvm_ad_rgb", "scalar_rgb"):
            vxml = scene_xml(f"{name}-rate-{v}", src, res, spps[v], "independent")
            loads[v], timers[v] = mitsuba_renderer(v, vxml, SEED_RATE)
        for _ in range(a.rate_runs):
            secs, loads["mcrt"], _ = mcrt_render(xml, "independent", SEED_RATE, a.threads)
            times["mcrt"].append(secs)
            for v, timed in timers.items():
                times[v].append(timed()[0])
        for k, spp in spps.items():
            best = min(times[k])
            r[k] = {"samples/s": px * spp / best, "render s": best, "runs s": times[k],
                    "load s": loads[k], "spp": spp}
        best_v = max(("llvm_ad_rgb", "scalar_rgb"), key=lambda v: r[v]["samples/s"])
        r["mitsuba variant"] = best_v
        r["rate ratio"] = r["mcrt"]["samples/s"] / r[best_v]["samples/s"]
        spread = {k: max(t) / min(t) for k, t in times.items()}
        print(f"  samples/s (best of {a.rate_runs}, slowest/fastest): mcrt "
              f"{r['mcrt']['samples/s'] / 1e6:.3f} M ({spread['mcrt']:.2f}; loaded in "
              f"{r['mcrt']['load s']:.2f} s), llvm_ad_rgb {r['llvm_ad_rgb']['samples/s'] / 1e6:.3f} M "
              f"({spread['llvm_ad_rgb']:.2f}), scalar_rgb {r['scalar_rgb']['samples/s'] / 1e6:.3f} M "
              f"({spread['scalar_rgb']:.2f}; loaded in {r['scalar_rgb']['load s']:.2f} s)",
              flush=True)
        timers.clear()

        REF[name] = (read_exr(os.path.join(ROOT, ref)) if ref
                     else reference(name, src, ref_spp, best_v))
        err = r["error"] = {"mitsuba": {}, "mcrt": {}}
        for s in MITSUBA_SAMPLERS:
            xml = scene_xml(f"{name}-mi-{s}", src, ERR_RES, base_spp, s)
            secs, _, img = mitsuba_render(best_v, xml, SEED_ERR)
            err["mitsuba"][s] = {"spp": base_spp, "s": secs, "rmse": rmse(img, REF[name])}
        mi_s = min(MITSUBA_SAMPLERS, key=lambda s: err["mitsuba"][s]["rmse"])
        target, t_mi = err["mitsuba"][mi_s]["rmse"], err["mitsuba"][mi_s]["s"]
        print("  Mitsuba at %d spp: %s; best %s" % (base_spp, ", ".join(
            f"{s} RMSE {e['rmse']:.5f} in {e['s']:.2f} s" for s, e in err["mitsuba"].items()),
            mi_s), flush=True)
        for s in MCRT_SAMPLERS:
            xml = scene_xml(f"{name}-mcrt-{s}", src, ERR_RES, base_spp, s)
            secs, _, img = mcrt_render(xml, s, SEED_ERR, a.threads)
            e0 = rmse(img, REF[name])
            # The time this sampler would need at the target, if RMSE ∝ 1/√spp.
            err["mcrt"][s] = {"base rmse": e0, "base s": secs,
                              "projected s": secs * (e0 / target) ** 2, "equal error": None}
        # Search with each sampler that could be the faster: a sampler projected to need a
        # third more time than the best is not searched (its projection is printed).
        fastest = min(e["projected s"] for e in err["mcrt"].values())
        for s, e in err["mcrt"].items():
            found = None
            if e["projected s"] <= 1.33 * fastest:
                found = mcrt_equal_error(name, src, s, target,
                                         (base_spp, e["base s"], e["base rmse"]), a.threads)
            if found:
                e["equal error"] = {"spp": found[0], "s": found[1], "rmse": found[2]}
            print(f"  mcrt {s}: RMSE {e['base rmse']:.5f} at {base_spp} spp in "
                  f"{e['base s']:.2f} s; " + (
                      f"RMSE {found[2]:.5f} at {found[0]} spp in {found[1]:.2f} s" if found else
                      f"projected {e['projected s']:.2f} s at the target, not searched"
                      if e["projected s"] > 1.33 * fastest else
                      "did not reach the target RMSE"), flush=True)
        reached = [s for s in MCRT_SAMPLERS if err["mcrt"][s]["equal error"]]
        if reached:
            mc_s = min(reached, key=lambda s: err["mcrt"][s]["equal error"]["s"])
            eq = err["mcrt"][mc_s]["equal error"]
            t_mc, t_mi, runs = equal_error_times(
                name, src, (mc_s, eq["spp"], eq["s"]), (best_v, mi_s, base_spp, t_mi),
                a.error_runs, a.threads)
            err["equal error runs s"] = runs
            r["time ratio"] = t_mc / t_mi
            r["samplers"] = (mc_s, mi_s)
    with open(a.json, "w") as f:
        json.dump(results, f, indent=1)

    print(f"\n| scene | Mitsuba samples/s | mcrt samples/s | mcrt / Mitsuba | time to equal "
          f"RMSE, mcrt / Mitsuba (samplers) |\n|---|---|---|---|---|")
    for name, r in results.items():
        v = r["mitsuba variant"]
        tr = (f"**{r['time ratio']:.2f}×** ({r['samplers'][0]} / {r['samplers'][1]})"
              if "time ratio" in r else "not reached")
        print(f"| {TITLES[name]}, {r['rate_res']}², {spp_rate} spp | "
              f"{r[v]['samples/s'] / 1e6:.2f} M (`{v}`) | {r['mcrt']['samples/s'] / 1e6:.2f} M | "
              f"**{r['rate ratio']:.2f}×** | {tr} |")
    print(f"\n(whole run {time.time() - t_start:.0f} s; figures in {a.json})")


if __name__ == "__main__":
    main()
