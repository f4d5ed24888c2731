//! Emitters and light sampling.
//!
//! Area lights are emissive triangles (quads are two) and spheres: one-sided, with constant RGB
//! radiance leaving the front (the side the geometric normal points to). Next-event estimation
//! picks one light in proportion to its power, then a point uniformly on its area, and converts
//! the area density to solid angle: p_ω = p_A · d² / |cos θ_light| (Veach 1997, eq. 8.10).
//!
//! An area light's radiance may be a texture (Mitsuba's `area` emitter with a textured
//! `radiance`): evaluated at the texture coordinates of the point, sampled or hit, with the
//! light's point still chosen uniformly over its area (as Mitsuba's `area` does) and its
//! power, for choosing among lights, taken from the texture's mean.

pub mod distribution;
pub mod envmap;
pub mod spot;

use crate::geometry::{ray::gamma, Sphere, Triangle};
use crate::simd::{Float, Vector3};
use crate::texture::Texture;
use crate::Color;
use distribution::Distribution1D;
use glam::{Vec2, Vec3A};

#[derive(Clone, Copy, Debug)]
pub enum LightShape {
    Triangle(Triangle),
    /// Two triangles of one mesh that together form a parallelogram `p0 + u·e1 + v·e2`
    /// (a quad light, as most scenes have): sampled as one light, uniformly in (u, v),
    /// without the square root of triangle sampling and with no choice between the halves.
    Parallelogram {
        p0: Vec3A,
        e1: Vec3A,
        e2: Vec3A,
    },
    Sphere(Sphere),
}

#[derive(Clone, Copy, Debug)]
pub struct AreaLight {
    pub shape: LightShape,
    /// The radiance; with a texture, the texture's mean.
    pub radiance: Color,
    pub area: f32,
    /// The texture giving the radiance (an index into [`Lights::textures`]), or
    /// [`NO_TEXTURE`]; and for a triangle its vertices' texture coordinates.
    pub texture: u32,
    pub uvs: [Vec2; 3],
    /// Planar shapes: the unit normal of the emitting side, and a bound on the floating-point
    /// error of any sampled point, both computed once here rather than per shadow ray.
    normal: Vec3A,
    err: Vec3A,
}

impl AreaLight {
    pub fn new(shape: LightShape, radiance: Color) -> Self {
        let (area, normal, err) = match &shape {
            // p = p0·w + p1·u + p2·v with w + u + v = 1: pbrt-v4's γ(7) bound (§6.8.4) taken
            // at its largest, weights of one.
            LightShape::Triangle(t) => (
                t.area(),
                t.normal_unnormalized().normalize(),
                (t.p0.abs() + t.p1.abs() + t.p2.abs()) * gamma(7),
            ),
            // p = p0 + u·e1 + v·e2, the edges themselves rounded differences of vertices.
            LightShape::Parallelogram { p0, e1, e2 } => {
                let n = e1.cross(*e2);
                (
                    n.length(),
                    n.normalize(),
                    (p0.abs() * 3.0 + e1.abs() * 2.0 + e2.abs() * 2.0) * gamma(7),
                )
            }
            LightShape::Sphere(s) => (s.area(), Vec3A::Z, Vec3A::ZERO),
        };
        AreaLight {
            shape,
            radiance,
            area,
            texture: NO_TEXTURE,
            uvs: [Vec2::ZERO, Vec2::X, Vec2::Y],
            normal,
            err,
        }
    }

    /// This sphere light emitting towards its centre (Mitsuba's `flip_normals`): its sampled
    /// points get inward normals. (Spheres keep +z in `normal` as the sign of theirs.)
    pub fn inward(mut self) -> Self {
        debug_assert!(matches!(self.shape, LightShape::Sphere(_)));
        self.normal = -self.normal;
        self
    }

    /// This light with its radiance given by texture `texture` (whose mean `radiance`
    /// already is); `uvs` are a triangle's vertex texture coordinates.
    pub fn with_texture(mut self, texture: u32, uvs: [Vec2; 3]) -> Self {
        self.texture = texture;
        self.uvs = uvs;
        self
    }

    /// The texture coordinates of the point `sample_point(u)` (normal `n`): a triangle's
    /// interpolated vertex uvs, a sphere's (φ/2π, θ/π) (as at a hit on it).
    fn uv_of_sample(&self, u: Vec2, n: Vec3A) -> Vec2 {
        match &self.shape {
            LightShape::Triangle(_) => {
                let (bu, bv) = Triangle::sample_uniform(u);
                self.uvs[0] * (1.0 - bu - bv) + self.uvs[1] * bu + self.uvs[2] * bv
            }
            // (Lights with textures are not merged into parallelograms.)
            LightShape::Parallelogram { .. } => u,
            LightShape::Sphere(_) => crate::geometry::sphere::uv_of_normal(n),
        }
    }

    /// The parallelogram light made of triangles `a` and `b` (one mesh, same emission), if
    /// they share an edge as the diagonal of a parallelogram and face the same way; within
    /// a relative 1e-6, far below what the image can show.
    pub fn parallelogram(a: &Triangle, b: &Triangle, radiance: Color) -> Option<AreaLight> {
        let (va, vb) = (a.vertices(), b.vertices());
        // The vertex of `a` not in `b`, and of `b` not in `a`; exactly one each.
        let only = |v: &[Vec3A; 3], w: &[Vec3A; 3]| {
            let mut it = v.iter().filter(|p| !w.contains(p));
            match (it.next(), it.next()) {
                (Some(p), None) => Some(*p),
                _ => None,
            }
        };
        let (x, y) = (only(&va, &vb)?, only(&vb, &va)?);
        let mut shared = va.iter().filter(|p| vb.contains(p));
        let (s0, s1) = (*shared.next()?, *shared.next()?);
        // The diagonals of a parallelogram bisect each other: x + y = s0 + s1.
        let scale = (x.abs() + y.abs() + s0.abs() + s1.abs()).max_element();
        if ((x + y) - (s0 + s1)).abs().max_element() > 1e-6 * scale {
            return None;
        }
        let (na, nb) = (a.normal_unnormalized(), b.normal_unnormalized());
        if na.dot(nb) <= 0.0 {
            return None;
        }
        // Orient the edges so that e1 × e2 is the triangles' (emitting) normal.
        let (e1, e2) = if (s0 - x).cross(s1 - x).dot(na) > 0.0 {
            (s0 - x, s1 - x)
        } else {
            (s1 - x, s0 - x)
        };
        Some(AreaLight::new(
            LightShape::Parallelogram { p0: x, e1, e2 },
            radiance,
        ))
    }

    /// Emitted power of a one-sided Lambertian emitter, Φ = π·A·L, averaged over RGB.
    pub fn power(&self) -> f32 {
        std::f32::consts::PI * self.area * (self.radiance.x + self.radiance.y + self.radiance.z)
            / 3.0
    }

    /// A uniform point on the surface: (point, unit normal, error bound).
    #[inline]
    pub fn sample_point(&self, u: Vec2) -> (Vec3A, Vec3A, Vec3A) {
        match &self.shape {
            LightShape::Triangle(t) => (
                planar_point(t.p0, t.p1, t.p2, true, u.x, u.y),
                self.normal,
                self.err,
            ),
            LightShape::Parallelogram { p0, e1, e2 } => (
                planar_point(*p0, *e1, *e2, false, u.x, u.y),
                self.normal,
                self.err,
            ),
            LightShape::Sphere(s) => {
                let n = crate::material::sampling::square_to_uniform_sphere(u);
                let p = s.center + n * s.radius;
                let err = (s.center.abs() + (n * s.radius).abs()) * gamma(5);
                // `normal.z` is −1 for a sphere that emits inwards ([`AreaLight::inward`]).
                (p, n * self.normal.z, err)
            }
        }
    }
}

/// A point of a planar light, over any lanes: `a·(1 − u' − v') + b·u' + c·v'` with the
/// uniform barycentric (u', v') of (u, v) for a triangle (`a, b, c` its vertices; the
/// square-root parameterisation, Shirley and Chiu 1997), `a + b·u + c·v` for a parallelogram
/// (`a` a corner, `b`, `c` its edges).
#[inline(always)]
pub fn planar_point<V: Vector3>(a: V, b: V, c: V, triangle: bool, u: V::F, v: V::F) -> V {
    if triangle {
        let one = V::F::splat(1.0);
        let su = u.sqrt();
        let (bu, bv) = (one - su, v * su);
        a.scale(one - bu - bv) + b.scale(bu) + c.scale(bv)
    } else {
        a + b.scale(u) + c.scale(v)
    }
}

/// From `p` towards the light point `pl` (unit normal `n`, on a light of area `area` chosen
/// with probability `pmf`), over any lanes: the offset `pl − p`, its squared length, the unit
/// direction, the cosine at the light and the solid-angle density of the sample (which counts
/// only where the distance and the cosine are positive).
#[inline(always)]
pub fn towards<V: Vector3>(p: V, pl: V, n: V, pmf: V::F, area: V::F) -> (V, V::F, V, V::F, V::F) {
    let d = pl - p;
    let dist2 = d.dot(d);
    let wi = d.div(dist2.sqrt());
    let cos_l = -n.dot(wi);
    (d, dist2, wi, cos_l, pmf * dist2 / (cos_l * area))
}

/// [`Lights::pdf`] over any lanes: the solid-angle density at `p` of sampling `pl` (normal
/// `n`) on a light of area `area` chosen with probability `pmf`; 0 from behind.
#[inline(always)]
pub fn area_pdf<V: Vector3>(p: V, pl: V, n: V, pmf: V::F, area: V::F) -> V::F {
    let zero = V::F::zero();
    let d = pl - p;
    let dist2 = d.dot(d);
    let cos_l = (-n.dot(d)).max_num(zero) / dist2.sqrt();
    V::F::select(cos_l.le(zero), zero, pmf * dist2 / (cos_l * area))
}

/// `AreaLight::texture` of a light with constant radiance.
pub const NO_TEXTURE: u32 = u32::MAX;

/// A light that is not a surface: a point, a direction, or the environment.
#[derive(Clone, Debug)]
pub enum OtherLight {
    /// Intensity I (W/sr) from a point.
    Point { p: Vec3A, intensity: Color },
    /// Irradiance E along `dir` (the direction the light travels).
    Directional { dir: Vec3A, irradiance: Color },
    /// Constant radiance from every direction.
    Constant { radiance: Color },
    /// Mitsuba's `spot`: a point light within a cone.
    Spot(Box<spot::SpotLight>),
    /// Mitsuba's `envmap`: radiance from a latitude-longitude image.
    Envmap(std::sync::Arc<envmap::EnvMap>),
}

/// The weights with which next-event estimation chooses a light (pbrt-v4's
/// `BVHLightSampler::Sample`): each light at infinity (constant, image environment,
/// directional) is chosen with probability 1/(n + 1), n the number of them, and the lights
/// of the scene share the rest by power. A light at infinity's power is that crossing a disk
/// of the scene's radius ([`OtherLight::power`]), which grows with the scene's size whatever
/// reaches its surfaces: on the gallery of `bench/make_scenes.py` (two area lights and a
/// constant environment) it gave the environment 79 % of the light samples, and this rule
/// lowered the image's variance by 12 % at equal samples (two seeds, 128², 128 spp). Without
/// lights at infinity, or without others, the weights are the powers.
fn selection_weights(powers: &[f32], at_infinity: &[bool]) -> Vec<f32> {
    let n_inf = at_infinity.iter().filter(|&&b| b).count();
    let finite: f32 = (powers.iter().zip(at_infinity))
        .filter(|&(_, &inf)| !inf)
        .map(|(p, _)| p)
        .sum();
    if n_inf == 0 || finite <= 0.0 {
        return powers.to_vec();
    }
    (powers.iter().zip(at_infinity))
        .map(|(&p, &inf)| if inf { 1.0 } else { p / finite })
        .collect()
}

impl OtherLight {
    /// Whether the light is at infinity: directions, not points, are what it is sampled by.
    pub fn at_infinity(&self) -> bool {
        matches!(
            self,
            OtherLight::Directional { .. } | OtherLight::Constant { .. } | OtherLight::Envmap(_)
        )
    }

    /// Power, for choosing among lights; `radius` bounds the scene (pbrt-v4's convention
    /// for lights at infinity: the power that crosses a disk of that radius).
    pub fn power(&self, radius: f32) -> f32 {
        let mean = |c: Color| (c.x + c.y + c.z) / 3.0;
        let disk = std::f32::consts::PI * radius * radius;
        match self {
            OtherLight::Point { intensity, .. } => 4.0 * std::f32::consts::PI * mean(*intensity),
            OtherLight::Directional { irradiance, .. } => disk * mean(*irradiance),
            OtherLight::Constant { radiance } => {
                4.0 * std::f32::consts::PI * disk * mean(*radiance)
            }
            OtherLight::Spot(s) => s.power(),
            OtherLight::Envmap(e) => 4.0 * std::f32::consts::PI * disk * mean(e.mean()),
        }
    }

    /// Radiance arriving from direction `d` (unit) and the solid-angle density of sampling
    /// it, for the lights at infinity that a ray can reach (constant and image environments).
    #[inline]
    fn environment(&self, d: Vec3A) -> Option<(Color, f32)> {
        match self {
            OtherLight::Constant { radiance } => {
                Some((*radiance, 1.0 / (4.0 * std::f32::consts::PI)))
            }
            OtherLight::Envmap(e) => Some((e.eval(d), e.pdf(d))),
            _ => None,
        }
    }
}

/// A sampled point on a light, seen from a shading point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    pub p: Vec3A,
    pub n: Vec3A,
    pub p_err: Vec3A,
    /// Unit direction from the shading point to the light point.
    pub wi: Vec3A,
    pub le: Color,
    /// Solid-angle density, including the probability of choosing this light; for a delta
    /// light (point, directional) only that probability.
    pub pdf: f32,
    /// A point or directional light: no BSDF sample can find it, so no MIS.
    pub delta: bool,
    /// The light is at infinity along `wi` (shadow rays are unbounded).
    pub infinite: bool,
}

/// The scene's only light, when it is a triangle or a parallelogram, with what next-event
/// estimation's batched path (`integrator::nee`) needs, computed once.
#[derive(Clone, Copy, Debug)]
pub struct PlanarLight {
    /// A point on the light is `a·w0 + b·w1 + c·w2`, with weights (1, u, v) for a
    /// parallelogram (`a, b, c` = p0, e1, e2) or barycentric ones for a triangle (its
    /// vertices): the expressions of `AreaLight::sample_point`.
    pub a: Vec3A,
    pub b: Vec3A,
    pub c: Vec3A,
    pub triangle: bool,
    /// The emitting side's unit normal.
    pub normal: Vec3A,
    /// `offset_ray_origin`'s push off the light for any sampled point: the normal times
    /// twice the error bound's projection on it.
    pub offset: Vec3A,
    pub area: f32,
    pub radiance: Color,
}

impl PlanarLight {
    fn new(l: &AreaLight) -> Option<PlanarLight> {
        let (a, b, c, triangle) = match l.shape {
            LightShape::Triangle(t) => (t.p0, t.p1, t.p2, true),
            LightShape::Parallelogram { p0, e1, e2 } => (p0, e1, e2, false),
            LightShape::Sphere(_) => return None,
        };
        Some(PlanarLight {
            a,
            b,
            c,
            triangle,
            normal: l.normal,
            offset: crate::geometry::ray::offset_push(l.normal, l.err),
            area: l.area,
            radiance: l.radiance,
        })
    }
}

#[derive(Clone, Debug, Default)]
pub struct Lights {
    /// Area lights, indexed by the `light` of the primitives that emit.
    pub lights: Vec<AreaLight>,
    /// Point, directional and environment lights.
    pub others: Vec<OtherLight>,
    /// Over area lights, then the others ([`selection_weights`]).
    distribution: Distribution1D,
    /// Indices in `others` of the environment lights (constant or image), which rays that
    /// leave the scene see.
    envs: Vec<usize>,
    /// The only light, if there is one and it is planar.
    planar: Option<PlanarLight>,
    /// The textures of area lights' radiance (`AreaLight::texture`).
    pub textures: Vec<Texture>,
}

impl Lights {
    pub fn new(lights: Vec<AreaLight>) -> Self {
        Self::with_others(lights, Vec::new(), 1.0)
    }

    /// `radius`: the scene's bounding-sphere radius, which sets the power of lights at
    /// infinity relative to the others.
    pub fn with_others(lights: Vec<AreaLight>, others: Vec<OtherLight>, radius: f32) -> Self {
        let powers: Vec<f32> = lights
            .iter()
            .map(|l| l.power())
            .chain(others.iter().map(|o| o.power(radius)))
            .collect();
        let envs = (0..others.len())
            .filter(|&i| others[i].environment(Vec3A::Y).is_some())
            .collect();
        let at_infinity: Vec<bool> = (lights.iter().map(|_| false))
            .chain(others.iter().map(OtherLight::at_infinity))
            .collect();
        let distribution = Distribution1D::new(&selection_weights(&powers, &at_infinity));
        let planar = match (&lights[..], others.len(), distribution.len()) {
            ([l], 0, 1) if l.texture == NO_TEXTURE => PlanarLight::new(l),
            _ => None,
        };
        Lights {
            distribution,
            lights,
            others,
            envs,
            planar,
            textures: Vec::new(),
        }
    }

    /// These lights with `textures` for the radiance of those that have one.
    pub fn with_textures(mut self, textures: Vec<Texture>) -> Self {
        self.textures = textures;
        self
    }

    /// The radiance of area light `light` at texture coordinates `uv`.
    #[inline(always)]
    fn radiance_at(&self, light: &AreaLight, uv: impl FnOnce() -> Vec2) -> Color {
        if light.texture == NO_TEXTURE {
            light.radiance
        } else {
            self.textures[light.texture as usize].eval(uv())
        }
    }

    /// The radiance of area light `id` at its point `sample_point(u)`, of normal `n`.
    #[inline]
    pub fn radiance_of_sample(&self, id: usize, u: Vec2, n: Vec3A) -> Color {
        let light = &self.lights[id];
        self.radiance_at(light, || light.uv_of_sample(u, n))
    }

    /// The scene's only light, if it is a triangle or a parallelogram (chosen with
    /// probability one).
    #[inline]
    pub fn single_planar(&self) -> Option<&PlanarLight> {
        self.planar.as_ref()
    }

    pub fn is_empty(&self) -> bool {
        self.lights.is_empty() && self.others.is_empty()
    }

    /// The probability with which `sample` chooses light `id` (as `pdf` weighs it).
    #[inline]
    pub(crate) fn pmf(&self, id: usize) -> f32 {
        self.distribution.pmf(id)
    }

    /// Radiance leaving light `id` at a point with normal `n` and texture coordinates `uv`
    /// in direction `w` (unit).
    #[inline]
    pub fn le(&self, id: u32, n: Vec3A, uv: Vec2, w: Vec3A) -> Color {
        if n.dot(w) > 0.0 {
            self.radiance_at(&self.lights[id as usize], || uv)
        } else {
            Color::ZERO
        }
    }

    /// Radiance arriving along a ray that leaves the scene in direction `d` (unit), and the
    /// solid-angle density with which light sampling would have chosen that direction (over
    /// all environment lights, each weighted by its probability of being chosen); None
    /// without an environment light.
    #[inline]
    pub fn environment(&self, d: Vec3A) -> Option<(Color, f32)> {
        let (&first, rest) = self.envs.split_first()?;
        let one = |i: usize| {
            let (le, pdf) = self.others[i].environment(d).unwrap_or_default();
            (le, pdf * self.distribution.pmf(self.lights.len() + i))
        };
        let mut sum = one(first);
        for &i in rest {
            let (le, pdf) = one(i);
            sum = (sum.0 + le, sum.1 + pdf);
        }
        Some(sum)
    }

    /// Samples a light and a point on it as seen from `p`.
    #[inline(always)]
    pub fn sample(&self, p: Vec3A, u_select: f32, u: Vec2) -> Option<LightSample> {
        let (id, pmf) = self.distribution.sample_discrete(u_select)?;
        let Some(light) = self.lights.get(id) else {
            return self.sample_other(id - self.lights.len(), pmf, p, u);
        };
        let (pl, n, p_err) = light.sample_point(u);
        let (_, dist2, wi, cos_l, pdf) = towards(p, pl, n, pmf, light.area);
        // (cos_l ≤ 0: the back of a one-sided emitter.)
        if dist2 == 0.0 || cos_l <= 0.0 {
            return None;
        }
        Some(LightSample {
            p: pl,
            n,
            p_err,
            wi,
            le: self.radiance_at(light, || light.uv_of_sample(u, n)),
            pdf,
            delta: false,
            infinite: false,
        })
    }

    #[cold]
    fn sample_other(&self, i: usize, pmf: f32, p: Vec3A, u: Vec2) -> Option<LightSample> {
        Some(match &self.others[i] {
            &OtherLight::Point { p: pl, intensity } => {
                let d = pl - p;
                let dist2 = d.length_squared();
                if dist2 == 0.0 {
                    return None;
                }
                let wi = d / dist2.sqrt();
                LightSample {
                    p: pl,
                    n: -wi,
                    p_err: Vec3A::ZERO,
                    wi,
                    le: intensity / dist2,
                    pdf: pmf,
                    delta: true,
                    infinite: false,
                }
            }
            &OtherLight::Directional { dir, irradiance } => LightSample {
                p: p - dir,
                n: dir,
                p_err: Vec3A::ZERO,
                wi: -dir,
                le: irradiance,
                pdf: pmf,
                delta: true,
                infinite: true,
            },
            OtherLight::Spot(s) => {
                let d = s.position - p;
                let dist2 = d.length_squared();
                if dist2 == 0.0 {
                    return None;
                }
                let wi = d / dist2.sqrt();
                let le = s.intensity_towards(-wi);
                if le == Color::ZERO {
                    return None;
                }
                LightSample {
                    p: s.position,
                    n: -wi,
                    p_err: Vec3A::ZERO,
                    wi,
                    le: le / dist2,
                    pdf: pmf,
                    delta: true,
                    infinite: false,
                }
            }
            OtherLight::Envmap(e) => {
                let (wi, le, pdf) = e.sample(u)?;
                LightSample {
                    p: p + wi,
                    n: -wi,
                    p_err: Vec3A::ZERO,
                    wi,
                    le,
                    pdf: pmf * pdf,
                    delta: false,
                    infinite: true,
                }
            }
            &OtherLight::Constant { radiance } => {
                let wi = crate::material::sampling::square_to_uniform_sphere(u);
                LightSample {
                    p: p + wi,
                    n: -wi,
                    p_err: Vec3A::ZERO,
                    wi,
                    le: radiance,
                    pdf: pmf / (4.0 * std::f32::consts::PI),
                    delta: false,
                    infinite: true,
                }
            }
        })
    }

    /// The solid-angle density with which `sample` would have produced the point `pl`
    /// (normal `n`) on light `id` from `p`. Used for multiple importance sampling.
    #[inline]
    pub fn pdf(&self, id: u32, p: Vec3A, pl: Vec3A, n: Vec3A) -> f32 {
        let light = &self.lights[id as usize];
        area_pdf(p, pl, n, self.distribution.pmf(id as usize), light.area)
    }

    pub fn total_power(&self) -> f32 {
        self.lights.iter().map(|l| l.power()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lights at infinity get 1/(n + 1) each, the others the rest by power; with only one
    /// kind, the powers decide.
    #[test]
    fn light_selection_gives_lights_at_infinity_equal_shares() {
        let quad = |e: f32| {
            AreaLight::new(
                LightShape::Parallelogram {
                    p0: Vec3A::ZERO,
                    e1: Vec3A::X,
                    e2: Vec3A::Z,
                },
                Color::splat(e),
            )
        };
        let sky = || OtherLight::Constant {
            radiance: Color::splat(0.3),
        };
        let lights = Lights::with_others(vec![quad(3.0), quad(1.0)], vec![sky()], 50.0);
        let pmf: Vec<f32> = (0..3).map(|i| lights.pmf(i)).collect();
        let want = [0.375, 0.125, 0.5];
        for (p, w) in pmf.iter().zip(want) {
            assert!((p - w).abs() < 1e-6, "{pmf:?}");
        }
        let two_skies = Lights::with_others(vec![quad(3.0)], vec![sky(), sky()], 50.0);
        for i in 0..3 {
            assert!((two_skies.pmf(i) - 1.0 / 3.0).abs() < 1e-6);
        }
        let areas = Lights::with_others(vec![quad(3.0), quad(1.0)], Vec::new(), 50.0);
        assert!((areas.pmf(0) - 0.75).abs() < 1e-6);
    }

    fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
        Triangle::new(a.into(), b.into(), c.into())
    }

    /// A square split along its diagonal is one parallelogram light: its area, its normal
    /// (the triangles' own), and sampled points inside the square.
    #[test]
    fn quad_is_one_parallelogram_light() {
        let (a, b) = (
            tri([0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [2.0, 3.0, 1.0]),
            tri([0.0, 0.0, 1.0], [2.0, 3.0, 1.0], [0.0, 3.0, 1.0]),
        );
        let l = AreaLight::parallelogram(&a, &b, Color::ONE).expect("a parallelogram");
        assert!((l.area - 6.0).abs() < 1e-6, "area {}", l.area);
        for (i, j) in [
            (0.0, 0.0),
            (0.999, 0.0),
            (0.5, 0.5),
            (0.0, 0.999),
            (0.999, 0.999),
        ] {
            let (p, n, _) = l.sample_point(Vec2::new(i, j));
            assert_eq!(n, Vec3A::Z);
            assert!((0.0..=2.0).contains(&p.x) && (0.0..=3.0).contains(&p.y) && p.z == 1.0);
        }
        // The corners of the unit square map to the square's four corners.
        let corners: Vec<Vec3A> = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
            .iter()
            .map(|&(i, j)| l.sample_point(Vec2::new(i, j)).0)
            .collect();
        for c in [[0.0, 0.0], [2.0, 0.0], [2.0, 3.0], [0.0, 3.0]] {
            assert!(corners.iter().any(|p| p.x == c[0] && p.y == c[1]), "{c:?}");
        }
    }

    /// Pairs that are not a parallelogram, or face opposite ways, stay two triangle lights.
    #[test]
    fn other_pairs_are_not_parallelograms() {
        let a = tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]);
        // A kite: shares the diagonal, but the far vertex is not the fourth corner.
        let kite = tri([0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [-0.2, 1.3, 0.0]);
        assert!(AreaLight::parallelogram(&a, &kite, Color::ONE).is_none());
        // The square's other half, wound the other way (facing down).
        let flipped = tri([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]);
        assert!(AreaLight::parallelogram(&a, &flipped, Color::ONE).is_none());
        // Sharing only one vertex.
        let apart = tri([1.0, 1.0, 0.0], [2.0, 1.0, 0.0], [2.0, 2.0, 0.0]);
        assert!(AreaLight::parallelogram(&a, &apart, Color::ONE).is_none());
    }
}
