//! The materials the lanes do not shade in their registers (plastic, principled, Oren–Nayar,
//! smooth conductors, blends, normal and bump maps, textured roughness, glass of other
//! factors): each lane's [`Material`] at its hit, the one the path tracer finds there, its
//! `eval_pdf` and `sample` called a lane at a time. The maths is the path tracer's own, so
//! those lanes compute its bits by construction; the rest of their vertex (the hit, the
//! light sample and its shadow ray, MIS, the roulette) stays in the lanes. pbrt-v4's
//! wavefront integrator likewise runs one material kernel over the queue of the paths that
//! hit it (`src/pbrt/wavefront/surfscatter.cpp`); here the queue is the lanes of a vector.

use super::bsdf::Sample;
use super::simd::{F, M, V3};
use super::{Bits, LaneMask};
use crate::material::{Material, TransportMode};
use crate::simd::lanes_of;
use glam::{Vec2, Vec3A};

/// A lane's material: the scene's own where it is the same at every hit, else the one at
/// the lane's hit (`Scene::material_at`: textures evaluated, a blend resolved, a normal
/// map's perturbation).
pub enum At<'a> {
    Scene(&'a Material),
    Hit(Material),
}

impl std::ops::Deref for At<'_> {
    type Target = Material;
    #[inline(always)]
    fn deref(&self) -> &Material {
        match self {
            At::Scene(m) => m,
            At::Hit(m) => m,
        }
    }
}

/// The lanes of a vertex whose material is one of these.
pub struct General<'a> {
    /// The lanes whose path goes on from here (the others' materials are black: the path
    /// ends, as `PathState::step` ends it).
    pub lanes: M,
    /// Of those, the ones whose material has a lobe that is not a delta (next-event
    /// estimation there: `Material::is_specular` is false).
    pub glossy: M,
    materials: [Option<At<'a>>; 16],
}

impl<'a> General<'a> {
    /// The materials of `lanes` (`material(l)` gives lane l's), those of black ones
    /// dropped from `lanes`.
    #[inline(always)]
    pub fn new(lanes: M, mut material: impl FnMut(usize) -> At<'a>) -> General<'a> {
        let mut materials: [Option<At<'a>>; 16] = std::array::from_fn(|_| None);
        let (mut live, mut glossy): (Bits, Bits) = (0, 0);
        for l in lanes_of(u32::from(lanes.bits())) {
            let m = material(l);
            if !m.is_black() {
                live |= 1 << l;
                glossy |= (!m.is_specular() as Bits) << l;
            }
            materials[l] = Some(m);
        }
        General {
            lanes: M::from_bits(live),
            glossy: M::from_bits(glossy),
            materials,
        }
    }

    /// `Material::eval_pdf` of each lane in `glossy` for local directions `wo`, `wi`;
    /// zero in the other lanes.
    #[inline(always)]
    pub fn eval_pdf(&self, wo: V3, wi: V3) -> (V3, F) {
        let (wo, wi) = (wo.to_arrays(), wi.to_arrays());
        let mut f = [[0f32; 16]; 3];
        let mut pdf = [0f32; 16];
        for l in lanes_of(u32::from(self.glossy.bits())) {
            let m = self.materials[l].as_ref().expect("a material in every lane");
            let (v, p) = m.eval_pdf(lane(&wo, l), lane(&wi, l));
            (f[0][l], f[1][l], f[2][l], pdf[l]) = (v.x, v.y, v.z, p);
        }
        (V3::load(&f), F::load(&pdf))
    }

    /// `Material::sample` of each lane in `lanes`, for the local direction `wo` and the
    /// numbers `[ux, uy, u1]` (the direction's pair and the lobe's choice); the other
    /// lanes hold no sample.
    #[inline(always)]
    pub fn sample(&self, wo: V3, [ux, uy, u1]: [F; 3]) -> Sample {
        let wo = wo.to_arrays();
        let (ux, uy, u1) = (ux.to_array(), uy.to_array(), u1.to_array());
        let (mut wi, mut weight) = ([[0f32; 16]; 3], [[0f32; 16]; 3]);
        let (mut pdf, mut eta) = ([0f32; 16], [1f32; 16]);
        let (mut ok, mut glossy): (Bits, Bits) = (0, 0);
        for l in lanes_of(u32::from(self.lanes.bits())) {
            let m = self.materials[l].as_ref().expect("a material in every lane");
            let u2 = Vec2::new(ux[l], uy[l]);
            let Some(bs) = m.sample(lane(&wo, l), u1[l], u2, TransportMode::Radiance) else {
                continue;
            };
            ok |= 1 << l;
            glossy |= (!bs.specular as Bits) << l;
            (wi[0][l], wi[1][l], wi[2][l]) = (bs.wi.x, bs.wi.y, bs.wi.z);
            (weight[0][l], weight[1][l], weight[2][l]) = (bs.weight.x, bs.weight.y, bs.weight.z);
            (pdf[l], eta[l]) = (bs.pdf, bs.eta);
        }
        Sample {
            ok: M::from_bits(ok),
            wi: V3::load(&wi),
            weight: V3::load(&weight),
            pdf: F::load(&pdf),
            eta: F::load(&eta),
            glossy: M::from_bits(glossy),
        }
    }
}

/// Lane `l` of `a` as one vector.
#[inline(always)]
pub fn lane(a: &[[f32; 16]; 3], l: usize) -> Vec3A {
    Vec3A::new(a[0][l], a[1][l], a[2][l])
}
