"""Reference values of Mitsuba 3's BSDFs for tests/bsdf_mitsuba.rs.

Evaluates eval() and pdf() of Mitsuba's conductor, roughconductor, roughdielectric,
thindielectric, plastic and roughplastic plugins (scalar_rgb variant; GGX, then the
Beckmann cases, named bk_*, with Mitsuba's default distribution) at fixed
direction pairs in the local frame and writes tests/data/bsdf_mitsuba.txt. Each line:

    case wo.x wo.y wo.z wi.x wi.y wi.z mode f_cos.r f_cos.g f_cos.b pdf

with mcrt's naming (wo towards the viewer = Mitsuba's si.wi; wi = Mitsuba's wo); f_cos is
Mitsuba's eval, i.e. f·|cos θi|; mode is R (radiance) or I (importance). For the delta BSDFs
(conductor, thindielectric, plastic's coating) the line holds the sample weight of the
delta lobe instead (wi = the sampled direction, pdf = the lobe's selection probability).

The principled and principledthin cases (pr_*, pt_*; llvm_* from the llvm_ad_rgb variant),
from their own random stream after everything else, are evaluated from both sides and in both transport modes; their sample
lines (named smp_pr_*, smp_pt_*) hold what `sample` returns for given random numbers:

    case wo.x wo.y wo.z wi.x wi.y wi.z S weight.r weight.g weight.b pdf u1 u2.x u2.y

(weight and pdf 0 where Mitsuba rejects the sample).

Usage: python3 tools/mitsuba_bsdf_ref.py > tests/data/bsdf_mitsuba.txt
"""
import math
import random

import mitsuba as mi

mi.set_variant("scalar_rgb")

CASES = {
    "rc_au_01": {"type": "roughconductor", "distribution": "ggx", "alpha": 0.1, "material": "Au"},
    "rc_cu_04": {"type": "roughconductor", "distribution": "ggx", "alpha": 0.4, "material": "Cu"},
    "rc_none_aniso": {"type": "roughconductor", "distribution": "ggx", "alpha_u": 0.05,
                      "alpha_v": 0.3},
    "rc_al_aniso": {"type": "roughconductor", "distribution": "ggx", "alpha_u": 0.3,
                    "alpha_v": 0.1, "material": "Al"},
    "rd_15_02": {"type": "roughdielectric", "distribution": "ggx", "alpha": 0.2,
                 "int_ior": 1.5, "ext_ior": 1.0},
    "rd_133_aniso": {"type": "roughdielectric", "distribution": "ggx", "alpha_u": 0.1,
                     "alpha_v": 0.4, "int_ior": 1.33, "ext_ior": 1.0},
    "pl_lin": {"type": "plastic", "int_ior": 1.5, "ext_ior": 1.0,
               "diffuse_reflectance": {"type": "rgb", "value": [0.5, 0.2, 0.1]}},
    "pl_nonlin": {"type": "plastic", "int_ior": 1.9, "ext_ior": 1.0, "nonlinear": True,
                  "diffuse_reflectance": {"type": "rgb", "value": [0.8, 0.6, 0.1]}},
    "rp_01": {"type": "roughplastic", "distribution": "ggx", "alpha": 0.1, "int_ior": 1.5,
              "ext_ior": 1.0,
              "diffuse_reflectance": {"type": "rgb", "value": [0.5, 0.2, 0.1]}},
    "rp_04_nonlin": {"type": "roughplastic", "distribution": "ggx", "alpha": 0.4,
                     "int_ior": 1.6, "ext_ior": 1.0, "nonlinear": True,
                     "diffuse_reflectance": {"type": "rgb", "value": [0.8, 0.6, 0.1]}},
}
DELTA = {
    "c_au": {"type": "conductor", "material": "Au"},
    "c_none": {"type": "conductor"},
    "c_cu": {"type": "conductor", "material": "Cu"},
    "td_15": {"type": "thindielectric", "int_ior": 1.5, "ext_ior": 1.0},
    "pl_lin": CASES["pl_lin"],
    "pl_nonlin": CASES["pl_nonlin"],
}
# Beckmann: no "distribution", Mitsuba's default. Evaluated after the cases above, from the
# same random stream, so that adding them left the earlier lines unchanged.
BECKMANN = {
    "bk_rc_au_01": {"type": "roughconductor", "alpha": 0.1, "material": "Au"},
    "bk_rc_cu_04": {"type": "roughconductor", "alpha": 0.4, "material": "Cu"},
    "bk_rc_none_aniso": {"type": "roughconductor", "alpha_u": 0.05, "alpha_v": 0.3},
    "bk_rc_al_aniso": {"type": "roughconductor", "alpha_u": 0.3, "alpha_v": 0.1,
                       "material": "Al"},
    "bk_rd_15_02": {"type": "roughdielectric", "alpha": 0.2, "int_ior": 1.5, "ext_ior": 1.0},
    "bk_rd_133_aniso": {"type": "roughdielectric", "alpha_u": 0.1, "alpha_v": 0.4,
                        "int_ior": 1.33, "ext_ior": 1.0},
    "bk_rp_01": {"type": "roughplastic", "alpha": 0.1, "int_ior": 1.5, "ext_ior": 1.0,
                 "diffuse_reflectance": {"type": "rgb", "value": [0.5, 0.2, 0.1]}},
    "bk_rp_04_nonlin": {"type": "roughplastic", "alpha": 0.4, "int_ior": 1.6, "ext_ior": 1.0,
                        "nonlinear": True,
                        "diffuse_reflectance": {"type": "rgb", "value": [0.8, 0.6, 0.1]}},
}

def rgb(r, g, b):
    return {"type": "rgb", "value": [r, g, b]}


# Principled BSDFs: every parameter, alone and together. No sheen with spec_trans = 1: there
# Mitsuba's scalar variants (used here) drop the sheen and its vectorised ones keep it (see
# src/material/principled.rs).
PRINCIPLED = {
    "pr_default": {"type": "principled"},
    "pr_metal": {"type": "principled", "base_color": rgb(0.9, 0.6, 0.3), "metallic": 0.8,
                 "roughness": 0.3, "spec_tint": 0.5},
    "pr_aniso": {"type": "principled", "base_color": rgb(0.2, 0.5, 0.8), "anisotropic": 0.7,
                 "roughness": 0.45, "metallic": 0.3},
    "pr_glass": {"type": "principled", "base_color": rgb(0.9, 0.95, 0.7), "spec_trans": 0.8,
                 "roughness": 0.3, "eta": 1.45},
    "pr_coat": {"type": "principled", "base_color": rgb(0.6, 0.1, 0.1), "clearcoat": 0.9,
                "clearcoat_gloss": 0.6, "roughness": 0.6, "sheen": 0.7, "sheen_tint": 0.4,
                "flatness": 0.5, "specular": 0.3},
    "pr_all": {"type": "principled", "base_color": rgb(0.7, 0.5, 0.3), "metallic": 0.3,
               "specular": 0.6, "roughness": 0.2, "spec_tint": 0.4, "anisotropic": 0.5,
               "sheen": 0.3, "sheen_tint": 0.2, "clearcoat": 0.6, "clearcoat_gloss": 0.3,
               "spec_trans": 0.4, "flatness": 0.3},
    "pr_eta_below_1": {"type": "principled", "base_color": rgb(0.4, 0.8, 0.6), "eta": 0.8,
                       "spec_trans": 0.5, "roughness": 0.35, "spec_tint": 0.7, "metallic": 0.2,
                       "clearcoat": 0.5},
    "pr_rates": {"type": "principled", "base_color": rgb(0.5, 0.5, 0.9), "spec_trans": 0.3,
                 "clearcoat": 0.4, "main_specular_sampling_rate": 0.5,
                 "clearcoat_sampling_rate": 2.0, "diffuse_reflectance_sampling_rate": 1.5},
}
PRINCIPLED_THIN = {
    "pt_default": {"type": "principledthin"},
    "pt_all": {"type": "principledthin", "base_color": rgb(0.3, 0.7, 0.2), "spec_trans": 0.5,
               "diff_trans": 0.6, "eta": 1.3, "roughness": 0.4, "anisotropic": 0.3,
               "spec_tint": 0.5, "sheen": 0.4, "sheen_tint": 0.6, "flatness": 0.4},
    "pt_leaf": {"type": "principledthin", "base_color": rgb(0.2, 0.6, 0.1), "diff_trans": 1.5,
                "roughness": 0.6},
    "pt_glass": {"type": "principledthin", "base_color": rgb(0.9, 0.9, 1.0), "spec_trans": 0.9,
                 "eta": 1.6, "roughness": 0.2, "specular_reflectance_sampling_rate": 0.7,
                 "diffuse_transmittance_sampling_rate": 2.0, "diff_trans": 0.4},
}

LLVM = {
    "pr_sheen_glass": {"type": "principled", "base_color": rgb(0.8, 0.4, 0.2), "spec_trans": 1.0,
                       "sheen": 0.8, "sheen_tint": 0.5, "roughness": 0.5},
}


def rand_dir(rng, upper):
    z = rng.uniform(0.02, 1.0)
    phi = rng.uniform(0, 2 * math.pi)
    r = math.sqrt(1 - z * z)
    return [r * math.cos(phi), r * math.sin(phi), z if upper else -z]


def non_delta(rng, cases, prefix=""):
    for name, d in cases.items():
        bsdf = mi.load_dict(d)
        two_sided = d["type"] in ("roughdielectric", "principled", "principledthin")
        n = 0
        while n < 40:
            wo = rand_dir(rng, True if not two_sided else rng.random() < 0.5)
            wi = rand_dir(rng, True if not two_sided else rng.random() < 0.5)
            # Nearly specular configurations make huge values that f32 noise dominates.
            for mode, tag in ((mi.TransportMode.Radiance, "R"), (mi.TransportMode.Importance, "I")):
                if tag == "I" and not two_sided:
                    continue
                ctx = mi.BSDFContext(mode)
                si = mi.SurfaceInteraction3f()
                si.wi = mi.Vector3f(wo)
                si.sh_frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0),
                                         mi.Vector3f(0, 0, 1))
                f = bsdf.eval(ctx, si, mi.Vector3f(wi))
                p = bsdf.pdf(ctx, si, mi.Vector3f(wi))
                vals = [*wo, *wi]
                print(prefix + name, " ".join(f"{v:.9g}" for v in vals), tag,
                      " ".join(f"{float(v[0] if hasattr(v, '__len__') else v):.9g}"
                               for v in (f[0], f[1], f[2], p)))
            n += 1


def main():
    rng = random.Random(7)
    non_delta(rng, CASES)
    for name, d in DELTA.items():
        bsdf = mi.load_dict(d)
        for _ in range(20):
            wo = rand_dir(rng, True)
            ctx = mi.BSDFContext()
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(wo)
            si.sh_frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0),
                                     mi.Vector3f(0, 0, 1))
            # u1 = 0: the reflection lobe when there is a choice.
            bs, w = bsdf.sample(ctx, si, 0.0, mi.Point2f(0.5, 0.5))
            vals = [*wo, bs.wo[0], bs.wo[1], bs.wo[2]]
            print("delta_" + name, " ".join(f"{v:.9g}" for v in vals), "R",
                  " ".join(f"{float(v):.9g}" for v in (w[0], w[1], w[2], bs.pdf)))
    non_delta(rng, BECKMANN)
    rng = random.Random(25)
    non_delta(rng, PRINCIPLED)
    non_delta(rng, PRINCIPLED_THIN)
    samples(rng, {**PRINCIPLED, **PRINCIPLED_THIN})
    # Sheen with spec_trans = 1, where the variants differ: the vectorised one's (which
    # renders the references) lines are named llvm_*.
    mi.set_variant("llvm_ad_rgb")
    non_delta(rng, LLVM, prefix="llvm_")


def samples(rng, cases):
    """What `sample` returns for random numbers that f32 holds exactly."""
    frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
    for name, d in cases.items():
        bsdf = mi.load_dict(d)
        for k in range(60):
            wo = rand_dir(rng, rng.random() < 0.6)
            u = [rng.randrange(1 << 20) / (1 << 20) for _ in range(3)]
            mode, tag = mi.TransportMode.Radiance, "R"
            ctx = mi.BSDFContext(mode)
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(wo)
            si.sh_frame = frame
            bs, w = bsdf.sample(ctx, si, u[0], mi.Point2f(u[1], u[2]))
            vals = [*wo, bs.wo[0], bs.wo[1], bs.wo[2]]
            print("smp_" + name, " ".join(f"{v:.9g}" for v in vals), "S",
                  " ".join(f"{float(v):.9g}" for v in (w[0], w[1], w[2], bs.pdf)),
                  " ".join(f"{v:.9g}" for v in u))


if __name__ == "__main__":
    main()
