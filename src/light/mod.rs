//! Emitters and light sampling.
//!
//! Area lights are emissive triangles (quads are two) and spheres: one-sided, with constant RGB
//! radiance leaving the front (the side the geometric normal points to). Next-event estimation
//! picks one light in proportion to its power, then a point uniformly on its area, and converts
//! the area density to solid angle: p_ω = p_A · d² / |cos θ_light| (Veach 1997, eq. 8.10).

pub mod distribution;

use crate::geometry::{ray::gamma, Sphere, Triangle};
use crate::Color;
use distribution::Distribution1D;
use glam::{Vec2, Vec3A};

#[derive(Clone, Copy, Debug)]
pub enum LightShape {
    Triangle(Triangle),
    Sphere(Sphere),
}

#[derive(Clone, Copy, Debug)]
pub struct AreaLight {
    pub shape: LightShape,
    pub radiance: Color,
    pub area: f32,
}

impl AreaLight {
    pub fn new(shape: LightShape, radiance: Color) -> Self {
        let area = match &shape {
            LightShape::Triangle(t) => t.area(),
            LightShape::Sphere(s) => s.area(),
        };
        AreaLight {
            shape,
            radiance,
            area,
        }
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
            LightShape::Triangle(t) => {
                let (bu, bv) = Triangle::sample_uniform(u);
                let (p, err) = t.point(bu, bv);
                (p, t.normal_unnormalized().normalize(), err)
            }
            LightShape::Sphere(s) => {
                let n = crate::material::sampling::square_to_uniform_sphere(u);
                let p = s.center + n * s.radius;
                let err = (s.center.abs() + (n * s.radius).abs()) * gamma(5);
                (p, n, err)
            }
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
    /// Solid-angle density, including the probability of choosing this light.
    pub pdf: f32,
}

#[derive(Clone, Debug, Default)]
pub struct Lights {
    pub lights: Vec<AreaLight>,
    distribution: Distribution1D,
}

impl Lights {
    pub fn new(lights: Vec<AreaLight>) -> Self {
        let powers: Vec<f32> = lights.iter().map(|l| l.power()).collect();
        Lights {
            distribution: Distribution1D::new(&powers),
            lights,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    /// Radiance leaving light `id` at a point with normal `n` in direction `w` (unit).
    #[inline]
    pub fn le(&self, id: u32, n: Vec3A, w: Vec3A) -> Color {
        if n.dot(w) > 0.0 {
            self.lights[id as usize].radiance
        } else {
            Color::ZERO
        }
    }

    /// Samples a light and a point on it as seen from `p`.
    #[inline]
    pub fn sample(&self, p: Vec3A, u_select: f32, u: Vec2) -> Option<LightSample> {
        let (id, pmf) = self.distribution.sample_discrete(u_select)?;
        let light = &self.lights[id];
        let (pl, n, p_err) = light.sample_point(u);
        let d = pl - p;
        let dist2 = d.length_squared();
        if dist2 == 0.0 {
            return None;
        }
        let wi = d / dist2.sqrt();
        let cos_l = -n.dot(wi);
        if cos_l <= 0.0 {
            return None; // the back of a one-sided emitter
        }
        let pdf = pmf * dist2 / (cos_l * light.area);
        Some(LightSample {
            p: pl,
            n,
            p_err,
            wi,
            le: light.radiance,
            pdf,
        })
    }

    /// The solid-angle density with which `sample` would have produced the point `pl`
    /// (normal `n`) on light `id` from `p`. Used for multiple importance sampling.
    #[inline]
    pub fn pdf(&self, id: u32, p: Vec3A, pl: Vec3A, n: Vec3A) -> f32 {
        let d = pl - p;
        let dist2 = d.length_squared();
        let cos_l = (-n.dot(d)).max(0.0) / dist2.sqrt();
        if cos_l <= 0.0 {
            return 0.0;
        }
        let light = &self.lights[id as usize];
        self.distribution.pmf(id as usize) * dist2 / (cos_l * light.area)
    }

    pub fn total_power(&self) -> f32 {
        self.lights.iter().map(|l| l.power()).sum()
    }
}
