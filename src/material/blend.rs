//! Blends of two BSDFs, as Mitsuba 3's `blendbsdf`: f = (1 − w)·f₀ + w·f₁ and likewise the
//! pdf, with the weight w a constant or a float texture clipped to [0, 1].
//!
//! The scene stores a blend as [`Blend`]: the weight and its two parts by material index, so
//! that [`Bsdf`] stays small and `Copy`. At a hit, [`Material::at`] resolves it, recursively,
//! into a flat mixture of the leaf materials with their products of weights (each leaf's
//! textures evaluated at the hit), held by the hit's material ([`Material::mix`]); a weight
//! of 0 or 1 gives the one part itself. A nested blend is the mixture of its leaves, as
//! Mitsuba's recursion evaluates it. Nesting is bounded by [`MAX_BLEND_DEPTH`] (checked when
//! the scene is read), so a mixture has at most 2^depth leaves.
//!
//! Sampling (blendbsdf.cpp, `sample`): a leaf is chosen with probability its weight (the
//! first random number reused, rescaled to the chosen interval), sampled, and for a
//! non-delta sample the mixture's value and pdf are evaluated at the sampled direction, so
//! that `weight = f·|cos θ|/pdf` of the whole blend. A delta sample (from a smooth leaf)
//! keeps the leaf's own weight: the leaf's share w cancels between the choice and the value.
//! (Mitsuba mixes a delta sample's weight with the other leaves' densities there, a bias for
//! blends of smooth and rough BSDFs that mcrt does not follow.)

use super::{Bsdf, BsdfSample, Material, TransportMode};
use crate::texture::Texture;
use crate::Color;
use glam::{Vec2, Vec3A};

/// Most blends one inside another (a blend of plain BSDFs has depth 1).
pub const MAX_BLEND_DEPTH: u32 = 4;

/// A blend as stored in the scene: its weight (or the mean of its texture, replaced per hit
/// by the texture's value) and its two parts, indices into the scene's materials.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blend {
    /// Weight of `second`; `first` has 1 − weight. In [0, 1] (a texture's value is clipped).
    pub weight: f32,
    pub first: u32,
    pub second: u32,
}

/// One leaf of a resolved blend and its share.
#[derive(Clone, Debug)]
pub struct Part {
    pub material: Material,
    pub weight: f32,
}

/// The material at a hit for `blend` (its weight already evaluated there): a mixture of its
/// leaves, or a single leaf where the weights leave one.
pub(super) fn resolve(
    blend: Blend,
    two_sided: bool,
    materials: &[Material],
    textures: &[Texture],
    uv: Vec2,
) -> Material {
    let mut parts = Vec::with_capacity(4);
    flatten(
        blend,
        1.0,
        two_sided,
        materials,
        textures,
        uv,
        MAX_BLEND_DEPTH,
        &mut parts,
    );
    if parts.len() == 1 {
        return parts.pop().expect("one part").material;
    }
    Material {
        mix: Some(parts.into_boxed_slice()),
        ..Material::new(Bsdf::Blend(blend), two_sided)
    }
}

/// Pushes the leaves of `blend` with their weights times `share`; `depth` more levels of
/// blends may follow.
#[allow(clippy::too_many_arguments)]
fn flatten(
    blend: Blend,
    share: f32,
    two_sided: bool,
    materials: &[Material],
    textures: &[Texture],
    uv: Vec2,
    depth: u32,
    parts: &mut Vec<Part>,
) {
    let w = blend.weight.clamp(0.0, 1.0);
    for (index, weight) in [(blend.first, 1.0 - w), (blend.second, w)] {
        // (A NaN weight, which no texture gives, fails this test too: no part.)
        if !(weight > 0.0) {
            continue;
        }
        let m = &materials[index as usize];
        let bsdf = m.bsdf_at(textures, uv);
        // A part of a two-sided blend is two-sided: `twosided` wraps the whole blend.
        let sided = m.two_sided || two_sided;
        match bsdf {
            // Deeper than the bound (the readers refuse such scenes): the part is black.
            Bsdf::Blend(inner) => {
                if depth > 1 {
                    let share = share * weight;
                    flatten(
                        inner,
                        share,
                        sided,
                        materials,
                        textures,
                        uv,
                        depth - 1,
                        parts,
                    );
                }
            }
            _ => parts.push(Part {
                material: Material {
                    bsdf,
                    two_sided: sided,
                    slots: Box::default(),
                    mix: None,
                    ..*m
                },
                weight: share * weight,
            }),
        }
    }
}

/// The mixture's f(wo, wi) in `mode` and its pdf.
#[inline]
pub(super) fn eval_pdf(parts: &[Part], wo: Vec3A, wi: Vec3A, mode: TransportMode) -> (Color, f32) {
    let mut f = Color::ZERO;
    let mut pdf = 0.0;
    for p in parts {
        f += p.material.eval_mode(wo, wi, mode) * p.weight;
        pdf += p.material.pdf(wo, wi) * p.weight;
    }
    (f, pdf)
}

/// Samples the mixture: a leaf by `u1` (then rescaled for the leaf), then its direction.
pub(super) fn sample(
    parts: &[Part],
    wo: Vec3A,
    u1: f32,
    u2: Vec2,
    mode: TransportMode,
) -> Option<BsdfSample> {
    let total: f32 = parts.iter().map(|p| p.weight).sum();
    let mut x = u1 * total;
    let mut chosen = parts.len() - 1;
    for (i, p) in parts.iter().enumerate() {
        if x < p.weight || i == parts.len() - 1 {
            chosen = i;
            break;
        }
        x -= p.weight;
    }
    let p = &parts[chosen];
    let u1 = (x / p.weight).clamp(0.0, 1.0 - f32::EPSILON / 2.0);
    let mut bs = p.material.sample(wo, u1, u2, mode)?;
    if bs.specular {
        return Some(bs);
    }
    let (f, pdf) = eval_pdf(parts, wo, bs.wi, mode);
    if !(pdf > 0.0) {
        return None;
    }
    bs.weight = f * (bs.wi.z.abs() / pdf);
    bs.pdf = pdf;
    Some(bs)
}

/// The mixture's albedo: the leaves' by their weights.
pub(super) fn albedo(parts: &[Part]) -> Color {
    parts.iter().map(|p| p.material.albedo() * p.weight).sum()
}
