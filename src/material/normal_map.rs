//! Normal and bump mapping: Mitsuba 3's `normalmap` and `bumpmap` BSDFs (normalmap.cpp,
//! bumpmap.cpp and normalmap_helpers.h of Mitsuba 3.9).
//!
//! A material with either perturbs the shading normal where a ray hits it
//! ([`perturbed_normal`], called by the scene when it builds the interaction, so every
//! integrator shades with it), and its BSDF then keeps two of Mitsuba's rules that need the
//! unperturbed normal ([`Perturbed`]): no light reaches through the surface, where a
//! direction is on different sides of the two normals; and the microfacet shadowing term of
//! Estevez et al., "A Microfacet-Based Shadowing Function to Solve the Bump Terminator
//! Problem" (Ray Tracing Gems, 2019), which darkens grazing light on strongly tilted normals.

use crate::geometry::Frame;
use crate::texture::{Bitmap, FilterType, Texture};
use glam::{Vec2, Vec3A};

/// A `bumpmap`'s height texture and the `scale` its gradient is multiplied by.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bump {
    pub texture: u32,
    pub scale: f32,
}

/// What the perturbation reads at a hit (Mitsuba's `SurfaceInteraction` fields), all in
/// world space.
#[derive(Clone, Copy, Debug)]
pub struct HitGeometry {
    /// Geometric normal (front side).
    pub ng: Vec3A,
    /// Unperturbed shading normal.
    pub ns: Vec3A,
    /// Partial derivatives of the position in the texture coordinates.
    pub dpdu: Vec3A,
    pub dpdv: Vec3A,
    pub uv: Vec2,
    /// Unit direction towards the viewer (Mitsuba's `si.wi`).
    pub wi: Vec3A,
    /// ±1: the normal map's bitangent is sign · (n × tangent) (glTF's TANGENT.w; +1 for
    /// tangents from dp/du).
    pub bitangent_sign: f32,
}

impl HitGeometry {
    /// The hit with a normal map's tangent frame following the interpolated vertex tangent
    /// `t` (glTF 2.0 §3.7.2.1 TANGENT: xyz the tangent, the sign of w the bitangent's)
    /// instead of dp/du, which stays where `t` has no component orthogonal to the normal.
    /// A bump map still reads dp/du and dp/dv.
    pub fn with_tangent(mut self, t: glam::Vec4) -> HitGeometry {
        let d = Vec3A::from(t.truncate());
        let s = d - self.ns * self.ns.dot(d);
        if s.length_squared() > 0.0 && s.is_finite() {
            self.dpdu = d;
            self.bitangent_sign = if t.w < 0.0 { -1.0 } else { 1.0 };
        }
        self
    }
}

/// Rec. 709 luminance: how Mitsuba reads an RGB texture as one number (`eval_1`).
pub use crate::texture::luminance;

/// The shading frame Mitsuba builds at a hit: the normal `n`, and the tangent `dpdu` made
/// orthogonal to it (an arbitrary one where `dpdu` is parallel to `n` or zero).
pub fn tangent_frame(n: Vec3A, dpdu: Vec3A) -> Frame {
    let s = dpdu - n * n.dot(dpdu);
    let s = if s.length_squared() > 0.0 {
        s.normalize()
    } else {
        Frame::from_normal(n).s
    };
    Frame {
        s,
        t: n.cross(s),
        n,
    }
}

/// The shading normal of a normal-mapped (`normal_map`: an RGB texture) or bump-mapped
/// surface at `h`.
pub fn perturbed_normal(
    normal_map: Option<u32>,
    bump: Option<Bump>,
    h: &HitGeometry,
    textures: &[Texture],
) -> Vec3A {
    let n = if let Some(t) = normal_map {
        // normalmap.cpp, frame(): the texture's colour c is the normal 2c − 1 in the
        // shading frame (dp/du made orthogonal to ns, ns × that, ns).
        // A vertex tangent's sign w flips the bitangent (glTF: B = (N × T)·w).
        let c = textures[t as usize].eval(h.uv);
        let local = Vec3A::from(c * 2.0 - 1.0);
        let mut f = tangent_frame(h.ns, h.dpdu);
        f.t *= h.bitangent_sign;
        f.to_world(local)
    } else if let Some(b) = bump {
        // bumpmap.cpp, frame(): the surface displaced along ns by scale·height has the
        // partials below (the height's own variation replaces their normal component).
        let g = b.scale * float_gradient(&textures[b.texture as usize], h.uv);
        let dpdu = h.dpdu + h.ns * (g.x - h.ns.dot(h.dpdu));
        let dpdv = h.dpdv + h.ns * (g.y - h.ns.dot(h.dpdv));
        let n = dpdu.cross(dpdv);
        // Flipped to the geometric normal's side.
        if h.ng.dot(n) < 0.0 {
            -n
        } else {
            n
        }
    } else {
        return h.ns;
    };
    let n = n.normalize_or_zero();
    if n == Vec3A::ZERO || !n.is_finite() {
        return h.ns; // a zero map value or a degenerate parametrization
    }
    // `flip_invalid_normals` (Mitsuba's default; Schüssler et al. 2017): a normal the
    // viewer sees from the other side than the unperturbed one is mirrored about it, which
    // is (−x, −y, z) in the shading frame.
    if h.wi.dot(h.ns) * h.wi.dot(n) <= 0.0 {
        (2.0 * n.dot(h.ns) * h.ns - n).normalize()
    } else {
        n
    }
}

/// The gradient in (u, v) of a texture read as one number (Mitsuba's `eval_1_grad`): that of
/// the bilinear interpolation for a bitmap, mapped back through its `to_uv`; zero for
/// nearest-neighbour lookups and for textures constant by parts.
pub fn float_gradient(tex: &Texture, uv: Vec2) -> Vec2 {
    let Texture::Bitmap(b) = tex else {
        return Vec2::ZERO;
    };
    if b.filter != FilterType::Bilinear {
        return Vec2::ZERO;
    }
    let bm: &Bitmap = &b.bitmap;
    let res = Vec2::new(bm.width as f32, bm.height as f32);
    let p = b.to_uv.apply(uv) * res - 0.5;
    let p0 = p.floor();
    let w1 = p - p0;
    let w0 = 1.0 - w1;
    let (xi, yi) = (p0.x as i64, p0.y as i64);
    let (w, h) = (bm.width as i64, bm.height as i64);
    let x = [b.wrap.wrap(xi, w), b.wrap.wrap(xi.saturating_add(1), w)];
    let y = [b.wrap.wrap(yi, h), b.wrap.wrap(yi.saturating_add(1), h)];
    let f = |i: usize, j: usize| luminance(bm.pixel(y[j] * bm.width as usize + x[i]));
    let (f00, f10, f01, f11) = (f(0, 0), f(1, 0), f(0, 1), f(1, 1));
    // Partials in pixel units, then through the transpose of to_uv's linear part
    // (bitmap.cpp, eval_1_grad).
    let dx = w0.y * (f10 - f00) + w1.y * (f11 - f01);
    let dy = w0.x * (f01 - f00) + w1.x * (f11 - f10);
    let m = b.to_uv.0.matrix2;
    res * Vec2::new(
        m.x_axis.x * dx + m.x_axis.y * dy,
        m.y_axis.x * dx + m.y_axis.y * dy,
    )
}

/// The unperturbed shading normal as a perturbed BSDF sees it at one hit: what its
/// evaluation and sampling need besides the local directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Perturbed {
    /// The unperturbed shading normal in the local frame of the perturbed one
    /// (`Frame::from_normal`, the integrators' frame); unaligned, to keep `Material` small.
    base: glam::Vec3,
    /// The shadowing term's α² = min(tan²θ/8, 1), θ the angle between the two normals.
    alpha2: f32,
}

impl Perturbed {
    /// For the perturbed shading normal `n` and the unperturbed `base` (unit vectors).
    pub fn new(n: Vec3A, base: Vec3A) -> Perturbed {
        let c = n.dot(base);
        Perturbed {
            base: Frame::from_normal(n).to_local(base).into(),
            alpha2: (0.125 * tan2(c)).min(1.0),
        }
    }

    /// The factor a perturbed BSDF's value (or sampling weight) takes for light arriving
    /// along the local direction `wi`: zero where `wi` lies on different sides of the two
    /// normals (no light through the surface), else the shadowing term
    /// 2 / (1 + √(1 + α² tan²θᵢ)), θᵢ measured from the unperturbed normal.
    #[inline]
    pub fn factor(&self, wi: Vec3A) -> f32 {
        let c = wi.dot(Vec3A::from(self.base));
        if c * wi.z <= 0.0 {
            return 0.0;
        }
        2.0 / (1.0 + (1.0 + self.alpha2 * tan2(c)).sqrt())
    }
}

/// tan²θ from cos θ.
#[inline]
fn tan2(c: f32) -> f32 {
    let c2 = c * c;
    ((1.0 - c2) / c2).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::{BitmapTexture, UvTransform, WrapMode};
    use crate::Color;
    use std::sync::Arc;

    fn bitmap(w: u32, h: u32, px: Vec<Color>) -> Texture {
        Texture::Bitmap(BitmapTexture::new(Arc::new(
            Bitmap::from_pixels(w, h, px).unwrap(),
        )))
    }

    fn hit(ns: Vec3A, wi: Vec3A) -> HitGeometry {
        HitGeometry {
            ng: Vec3A::Z,
            ns,
            dpdu: Vec3A::new(2.0, 0.0, 0.0),
            dpdv: Vec3A::new(0.0, 2.0, 0.0),
            uv: Vec2::new(0.3, 0.7),
            wi,
            bitangent_sign: 1.0,
        }
    }

    /// A vertex tangent equal to dp/du (sign +1) gives the frame built from dp/du.
    #[test]
    fn tangent_equal_to_dpdu_keeps_the_normal() {
        let tex = [bitmap(1, 1, vec![Color::new(0.7, 0.35, 0.9)])];
        let ns = Vec3A::new(0.3, -0.2, 0.9).normalize();
        let wi = Vec3A::new(0.1, 0.4, 0.8).normalize();
        let mut h = hit(ns, wi);
        h.dpdu = Vec3A::new(2.0, 0.3, 0.1);
        let today = perturbed_normal(Some(0), None, &h, &tex);
        assert!((today - ns).length() > 0.1, "the texel tilts: {today}");
        let t = glam::Vec3::from(h.dpdu).extend(1.0);
        let n = perturbed_normal(Some(0), None, &h.with_tangent(t), &tex);
        assert!((n - today).length() < 1e-6, "{n} vs {today}");
        // A tangent along the normal has no direction in the surface: dp/du stays.
        let n = perturbed_normal(Some(0), None, &h.with_tangent(ns.extend(1.0)), &tex);
        assert!((n - today).length() < 1e-6, "{n} vs {today}");
    }

    /// A tangent turned 90° about n turns the tilt with it; w = −1 mirrors the bitangent.
    #[test]
    fn rotated_tangent_turns_the_tilt() {
        let (s, c) = 30f32.to_radians().sin_cos();
        // Tilted 30° towards +x of the tangent frame...
        let along_t = [bitmap(
            1,
            1,
            vec![Color::new((1.0 + s) / 2.0, 0.5, (1.0 + c) / 2.0)],
        )];
        // ...and towards +y (the bitangent).
        let along_b = [bitmap(
            1,
            1,
            vec![Color::new(0.5, (1.0 + s) / 2.0, (1.0 + c) / 2.0)],
        )];
        let h = hit(Vec3A::Z, Vec3A::Z); // dp/du = (2, 0, 0)
        let n = perturbed_normal(Some(0), None, &h, &along_t);
        assert!((n - Vec3A::new(s, 0.0, c)).length() < 1e-5, "{n}");
        // T = +y: B = z × y = −x.
        let ty = h.with_tangent(glam::Vec4::new(0.0, 3.0, 0.0, 1.0));
        let n = perturbed_normal(Some(0), None, &ty, &along_t);
        assert!((n - Vec3A::new(0.0, s, c)).length() < 1e-5, "{n}");
        let n = perturbed_normal(Some(0), None, &ty, &along_b);
        assert!((n - Vec3A::new(-s, 0.0, c)).length() < 1e-5, "{n}");
        // w = −1: B = −(z × y) = +x.
        let ty = h.with_tangent(glam::Vec4::new(0.0, 3.0, 0.0, -1.0));
        let n = perturbed_normal(Some(0), None, &ty, &along_b);
        assert!((n - Vec3A::new(s, 0.0, c)).length() < 1e-5, "{n}");
    }

    #[test]
    fn flat_normal_map_keeps_the_shading_normal() {
        let tex = [bitmap(2, 2, vec![Color::new(0.5, 0.5, 1.0); 4])];
        let ns = Vec3A::new(0.3, -0.2, 0.9).normalize();
        let wi = Vec3A::new(0.1, 0.4, 0.8).normalize();
        let n = perturbed_normal(Some(0), None, &hit(ns, wi), &tex);
        assert!((n - ns).length() < 1e-6, "{n} vs {ns}");
    }

    #[test]
    fn normal_map_tilts_along_dpdu() {
        // (1 + sin, 1, 1 + cos)/2 encodes a normal tilted 30° towards +s = dp/du.
        let (s, c) = 30f32.to_radians().sin_cos();
        let tex = [bitmap(
            1,
            1,
            vec![Color::new((1.0 + s) / 2.0, 0.5, (1.0 + c) / 2.0)],
        )];
        let h = hit(Vec3A::Z, Vec3A::new(0.0, 0.0, 1.0));
        let n = perturbed_normal(Some(0), None, &h, &tex);
        assert!((n - Vec3A::new(s, 0.0, c)).length() < 1e-5, "{n}");
        // Seen from where the tilted normal faces away, it is mirrored about ns.
        let h = hit(Vec3A::Z, Vec3A::new(-0.9, 0.0, 0.1).normalize());
        let n = perturbed_normal(Some(0), None, &h, &tex);
        assert!((n - Vec3A::new(-s, 0.0, c)).length() < 1e-5, "{n}");
    }

    #[test]
    fn constant_height_keeps_the_shading_normal() {
        let tex = [
            bitmap(3, 2, vec![Color::splat(0.7); 6]),
            Texture::Constant(Color::splat(0.4)),
        ];
        for t in 0..2 {
            let b = Bump {
                texture: t,
                scale: 5.0,
            };
            let wi = Vec3A::new(0.2, 0.1, 0.9).normalize();
            let n = perturbed_normal(None, Some(b), &hit(Vec3A::Z, wi), &tex);
            assert!((n - Vec3A::Z).length() < 1e-6, "{n}");
        }
    }

    #[test]
    fn bilinear_gradient_matches_finite_differences() {
        let px = (0..12)
            .map(|i| Color::new(0.1 * i as f32, 0.05 * (i * i % 7) as f32, 0.3))
            .collect();
        let Texture::Bitmap(mut b) = bitmap(4, 3, px) else {
            unreachable!()
        };
        b.wrap = WrapMode::Repeat;
        b.to_uv = UvTransform::scale(Vec2::new(2.0, 0.5));
        let tex = Texture::Bitmap(b);
        let uv = Vec2::new(0.37, 0.61);
        let g = float_gradient(&tex, uv);
        let h = 1e-3;
        let f = |d: Vec2| luminance(tex.eval(uv + d));
        let fd = Vec2::new(
            (f(Vec2::new(h, 0.0)) - f(Vec2::new(-h, 0.0))) / (2.0 * h),
            (f(Vec2::new(0.0, h)) - f(Vec2::new(0.0, -h))) / (2.0 * h),
        );
        assert!(
            (g - fd).length() < 1e-2 * fd.length().max(1.0),
            "{g} vs {fd}"
        );
        assert!(g.length() > 0.1, "a gradient that cannot be zero: {g}");
    }

    #[test]
    fn bump_slope_tilts_against_the_gradient() {
        // Height rising along u with slope k per unit u on a plane with dp/du = (2, 0, 0):
        // the displaced surface's normal is (−k/2, 0, 1), normalized.
        let px = vec![Color::splat(0.0), Color::splat(0.25)];
        let tex = [bitmap(2, 1, px)];
        let b = Bump {
            texture: 0,
            scale: 1.0,
        };
        let mut h = hit(Vec3A::Z, Vec3A::Z);
        h.uv = Vec2::new(0.5, 0.5);
        let k = float_gradient(&tex[0], h.uv).x;
        assert!((k - 0.5).abs() < 1e-6, "{k}");
        let n = perturbed_normal(None, Some(b), &h, &tex);
        let want = Vec3A::new(-k / 2.0, 0.0, 1.0).normalize();
        assert!((n - want).length() < 1e-5, "{n} vs {want}");
    }

    /// The BSDF values of a normal-mapped and a bump-mapped diffuse surface, as Mitsuba 3
    /// computes them (tests/data/maps_mitsuba.txt): the perturbed normal, its flip towards
    /// the viewer, the light-leak test and the shadowing term together.
    #[test]
    fn values_agree_with_mitsuba() {
        use crate::material::{Bsdf, Lambert, Material};
        let height = [0.1, 0.5, 0.3, 0.9, 0.2, 0.6].map(Color::splat).to_vec();
        let tex = [
            bitmap(1, 1, vec![Color::new(0.8, 0.4, 0.9)]),
            bitmap(3, 2, height),
        ];
        let data = include_str!("../../tests/data/maps_mitsuba.txt");
        let mut n_cases = 0;
        for line in data.lines().filter(|l| !l.starts_with('#')) {
            let w: Vec<&str> = line.split_whitespace().collect();
            let x: Vec<f32> = w[1..].iter().map(|v| v.parse().unwrap()).collect();
            let (viewer, light) = (Vec3A::new(x[0], x[1], x[2]), Vec3A::new(x[3], x[4], x[5]));
            let (normal_map, bump) = match w[0] {
                "normal" => (Some(0), None),
                _ => (
                    None,
                    Some(Bump {
                        texture: 1,
                        scale: 0.3,
                    }),
                ),
            };
            let mut h = hit(Vec3A::Z, viewer);
            h.uv = Vec2::new(0.3, 0.6);
            let n = perturbed_normal(normal_map, bump, &h, &tex);
            let albedo = Color::splat(0.5);
            let mut m = Material::new(Bsdf::Lambert(Lambert { albedo }), false);
            m.perturbed = Some(Perturbed::new(n, Vec3A::Z));
            let f = Frame::from_normal(n);
            let wi = f.to_local(light);
            let got = m.eval(f.to_local(viewer), wi).x * wi.z.abs();
            assert!(
                (got - x[6]).abs() < 1e-5 + 1e-4 * x[6],
                "{line}: mcrt {got}"
            );
            n_cases += 1;
        }
        assert_eq!(n_cases, 30);
    }

    #[test]
    fn guard_blocks_light_between_the_normals_and_shadows_grazing_light() {
        let n = Vec3A::new(0.5, 0.0, 1.0).normalize();
        let p = Perturbed::new(n, Vec3A::Z);
        let frame = Frame::from_normal(n);
        // Above the perturbed normal's horizon, below the unperturbed one's: blocked.
        let below = Vec3A::new(0.9, 0.2, -0.1).normalize();
        assert!(frame.to_local(below).z > 0.0);
        assert_eq!(p.factor(frame.to_local(below)), 0.0);
        // Straight along the unperturbed normal: no shadowing (tan θ = 0).
        assert!((p.factor(frame.to_local(Vec3A::Z)) - 1.0).abs() < 1e-6);
        // Grazing: darker, never above 1.
        let graze = Vec3A::new(0.9, 0.0, 0.1).normalize();
        let g = p.factor(frame.to_local(graze));
        assert!(g > 0.0 && g < 0.95, "{g}");
        // Unperturbed: the factor is 1 wherever light arrives from above.
        let q = Perturbed::new(Vec3A::Z, Vec3A::Z);
        assert!((q.factor(graze) - 1.0).abs() < 1e-6);
    }
}
