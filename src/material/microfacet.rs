//! The GGX (Trowbridge–Reitz) microfacet distribution, anisotropic, with Smith's separable
//! shadowing–masking and visible-normal sampling; the conventions are those of Mitsuba 3's
//! `MicrofacetDistribution` (include/mitsuba/render/microfacet.h), which the rough BSDFs
//! must match.
//!
//! - D(m) = 1 / (π αu αv (m_x²/αu² + m_y²/αv² + m_z²)²) (Trowbridge and Reitz 1975; Walter
//!   et al., "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007, eq. 33;
//!   the anisotropic form is Heitz, "Understanding the Masking-Shadowing Function in
//!   Microfacet-Based BRDFs", JCGT 3(2), 2014, eq. 85).
//! - Λ(v) = (−1 + √(1 + (αu² v_x² + αv² v_y²)/v_z²))/2 and G1(v, m) = 1/(1 + Λ(v)) =
//!   2/(1 + √(1 + tan²θ α²)) (Heitz 2014, eqs. 86 and 43), zero when v sees the back of the
//!   microfacet (χ⁺(v·m / v·n)).
//! - G(wo, wi, m) = G1(wo, m)·G1(wi, m): the separable form, as in Mitsuba (Walter et al.
//!   2007, eq. 23), not the height-correlated one.
//! - Visible normals D_wo(m) = G1(wo, m)·|wo·m|·D(m)/cos θo are sampled with Heitz, "Sampling
//!   the GGX Distribution of Visible Normals", JCGT 7(4), 2018, using the concentric disk
//!   map for the disk sample (the paper allows any area-preserving map; it is the one
//!   Mitsuba's `sample_visible_11` uses, so that quadratures over the warped square, like
//!   the rough plastic's transmittance table, see the same nodes).

use super::sampling::square_to_disk_concentric;
use glam::{Vec2, Vec3A};
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    /// Roughness along the tangent (x) and bitangent (y) of the shading frame.
    pub alpha_u: f32,
    pub alpha_v: f32,
}

impl Ggx {
    /// Roughness below 1e-4 is clamped to 1e-4, as in Mitsuba (`configure()`).
    pub fn new(alpha_u: f32, alpha_v: f32) -> Self {
        Ggx {
            alpha_u: alpha_u.max(1e-4),
            alpha_v: alpha_v.max(1e-4),
        }
    }

    /// The normal distribution D(m) (zero for m below the surface; like Mitsuba, values with
    /// D·cos θm ≤ 1e-20 are flushed to zero).
    #[inline]
    pub fn d(&self, m: Vec3A) -> f32 {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let t = (m.x / au) * (m.x / au) + (m.y / av) * (m.y / av) + m.z * m.z;
        let d = 1.0 / (PI * au * av * t * t);
        if d * m.z > 1e-20 {
            d
        } else {
            0.0
        }
    }

    /// Smith's Λ(v) for GGX.
    #[inline]
    pub fn lambda(&self, v: Vec3A) -> f32 {
        let xy = (self.alpha_u * v.x).powi(2) + (self.alpha_v * v.y).powi(2);
        if xy == 0.0 {
            return 0.0;
        }
        0.5 * (-1.0 + (1.0 + xy / (v.z * v.z)).sqrt())
    }

    /// Smith's masking G1(v, m) = 1/(1 + Λ(v)), zero when v and the macro-normal disagree
    /// about the side of m (Mitsuba's `smith_g1`).
    #[inline]
    pub fn g1(&self, v: Vec3A, m: Vec3A) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        let xy = (self.alpha_u * v.x).powi(2) + (self.alpha_v * v.y).powi(2);
        if xy == 0.0 {
            return 1.0;
        }
        2.0 / (1.0 + (1.0 + xy / (v.z * v.z)).sqrt())
    }

    /// The separable shadowing–masking G1(wo, m)·G1(wi, m).
    #[inline]
    pub fn g(&self, wo: Vec3A, wi: Vec3A, m: Vec3A) -> f32 {
        self.g1(wo, m) * self.g1(wi, m)
    }

    /// Samples a microfacet normal from the distribution of normals visible from `wo`
    /// (`wo.z > 0`; Heitz 2018, listing 1).
    #[inline]
    pub fn sample_visible(&self, wo: Vec3A, u: Vec2) -> Vec3A {
        // Stretch wo to the configuration with α = 1 (the hemisphere).
        let vh = Vec3A::new(self.alpha_u * wo.x, self.alpha_v * wo.y, wo.z).normalize();
        // An orthonormal basis around vh (T1 is perpendicular to the plane of incidence).
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 {
            Vec3A::new(-vh.y, vh.x, 0.0) / len2.sqrt()
        } else {
            Vec3A::X
        };
        let t2 = vh.cross(t1);
        // A point on the disk, squeezed onto the part of the projected hemisphere visible
        // from vh.
        let p = square_to_disk_concentric(u);
        let s = 0.5 * (1.0 + vh.z);
        let p1 = p.x;
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p.y;
        // Reproject onto the hemisphere, then unstretch.
        let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        Vec3A::new(self.alpha_u * nh.x, self.alpha_v * nh.y, nh.z.max(0.0)).normalize()
    }

    /// Density of `sample_visible` over microfacet normals: D_wo(m) = G1(wo, m)·|wo·m|·D(m)
    /// / cos θo (Heitz 2018, eq. 1).
    #[inline]
    pub fn pdf_visible(&self, wo: Vec3A, m: Vec3A) -> f32 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        self.d(m) * self.g1(wo, m) * wo.dot(m).abs() / wo.z
    }
}

/// Reflects `wo` about the microfacet normal `m`.
#[inline]
pub fn reflect_about(wo: Vec3A, m: Vec3A) -> Vec3A {
    2.0 * wo.dot(m) * m - wo
}
