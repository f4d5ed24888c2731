//! Smooth conductors (metals): a delta reflection weighted by the unpolarised Fresnel
//! reflectance of a complex index of refraction η + ik, as Mitsuba 3's `conductor` plugin.
//! Also the RGB indices of refraction of Mitsuba's named conductors.

use super::mirror::reflect_local;
use super::BsdfSample;
use crate::simd::{Float, Vector3};
use crate::Color;
use glam::Vec3A;

#[derive(Clone, Copy, Debug)]
pub struct Conductor {
    /// Real part of the relative index of refraction, per channel.
    pub eta: Color,
    /// Imaginary part (absorption coefficient), per channel.
    pub k: Color,
    /// A factor on the reflection (1 for physical realism).
    pub specular_reflectance: Color,
}

/// Unpolarised Fresnel reflectance of a conductor with complex relative index η + ik, for
/// light arriving from outside (`cos_i` ≥ 0). The closed form of Mitsuba's
/// `fresnel_conductor` (after K. D. Möller, *Optics*, 1988; see also pbrt-v3 §8.2.1,
/// `FrConductor`): with a² + b² = √((η² − k² − sin²θ)² + 4η²k²) and
/// a = √((a² + b² + η² − k² − sin²θ)/2),
/// R_s = (a² + b² + cos²θ − 2a cos θ)/(a² + b² + cos²θ + 2a cos θ),
/// R_p = R_s·(cos²θ (a² + b²) + sin⁴θ − 2a cos θ sin²θ)/(cos²θ (a² + b²) + sin⁴θ + 2a cos θ sin²θ),
/// R = (R_s + R_p)/2. With η = 0, k = 1 (Mitsuba's "none") R = 1 at every angle.
#[inline]
pub fn fresnel_conductor(cos_i: f32, eta: f32, k: f32) -> f32 {
    fresnel_conductor_lanes(cos_i, eta, k)
}

/// [`fresnel_conductor`] over any lanes.
#[inline(always)]
pub fn fresnel_conductor_lanes<T: Float>(cos_i: T, eta: T, k: T) -> T {
    let (zero, one, half, two) = (T::zero(), T::splat(1.0), T::splat(0.5), T::splat(2.0));
    let c2 = cos_i * cos_i;
    let s2 = one - c2;
    let s4 = s2 * s2;
    let temp1 = eta * eta - k * k - s2;
    let a2pb2 = (temp1 * temp1 + T::splat(4.0) * k * k * eta * eta)
        .max_num(zero)
        .sqrt();
    let a = (half * (a2pb2 + temp1)).max_num(zero).sqrt();
    let term1 = a2pb2 + c2;
    let term2 = two * cos_i * a;
    let rs = (term1 - term2) / (term1 + term2);
    let term3 = a2pb2 * c2 + s4;
    let term4 = term2 * s2;
    let rp = rs * (term3 - term4) / (term3 + term4);
    half * (rs + rp)
}

/// `fresnel_conductor` per colour channel.
#[inline]
pub fn fresnel_conductor_rgb(cos_i: f32, eta: Color, k: Color) -> Color {
    fresnel_conductor_rgb_lanes(cos_i, eta, k)
}

/// [`fresnel_conductor_rgb`] over any lanes.
#[inline(always)]
pub fn fresnel_conductor_rgb_lanes<C: Vector3>(cos_i: C::F, eta: C, k: C) -> C {
    C::new(
        fresnel_conductor_lanes(cos_i, eta.x(), k.x()),
        fresnel_conductor_lanes(cos_i, eta.y(), k.y()),
        fresnel_conductor_lanes(cos_i, eta.z(), k.z()),
    )
}

impl Conductor {
    pub fn new(eta: Color, k: Color, specular_reflectance: Color) -> Self {
        Conductor {
            eta,
            k,
            specular_reflectance,
        }
    }

    /// Reflectance at incidence cos θ (the sample weight).
    #[inline]
    pub fn reflectance(&self, cos_i: f32) -> Color {
        self.specular_reflectance * fresnel_conductor_rgb(cos_i, self.eta, self.k)
    }

    /// `wo.z > 0` (one-sidedness is handled by `Material`).
    #[inline]
    pub fn sample(&self, wo: Vec3A) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wi: reflect_local(wo),
            weight: self.reflectance(wo.z),
            pdf: 0.0,
            specular: true,
            eta: 1.0,
        })
    }
}

/// The RGB (η, k) of Mitsuba 3's named conductors (`material` parameter of `conductor` and
/// `roughconductor`), or None for an unknown name. "none" is Mitsuba's default, a perfect
/// mirror: η = 0, k = 1, which reflects exactly 1 at every angle.
///
/// The values are what Mitsuba 3 (3.x, `scalar_rgb` variant) loads: its `ior_from_file`
/// reads the spectral tables resources/data/ior/<name>.eta.spd and .k.spd, scales them by
/// 1/∫ȳ (`MI_CIE_Y_NORMALIZATION`), integrates them against the CIE 1931 colour-matching
/// functions and converts XYZ to linear sRGB (`spectrum_to_rgb`), clamping negative
/// channels to 0. They were read back from Mitsuba itself
/// (`mi.traverse(mi.load_dict({'type': 'conductor', 'material': name}))`), so they match it
/// to f32 precision.
pub fn conductor_ior(name: &str) -> Option<(Color, Color)> {
    if name == "none" {
        return Some((Color::ZERO, Color::ONE));
    }
    CONDUCTORS
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, e, k)| (Color::from_array(*e), Color::from_array(*k)))
}

/// The names `conductor_ior` knows, besides "none".
pub fn conductor_names() -> impl Iterator<Item = &'static str> {
    CONDUCTORS.iter().map(|(n, _, _)| *n)
}

#[allow(clippy::approx_constant)]
const CONDUCTORS: &[(&str, [f32; 3], [f32; 3])] = &[
    (
        "Ag",
        [0.1552762, 0.116727956, 0.13838764],
        [4.8283544, 3.1222224, 2.1469011],
    ),
    (
        "Al",
        [1.6575009, 0.8804047, 0.52124447],
        [9.223811, 6.269502, 4.837004],
    ),
    (
        "AlAs",
        [3.605296, 3.2329378, 2.2163186],
        [0.0006794373, 0.0, 0.007512709],
    ),
    (
        "AlAs_palik",
        [3.605296, 3.2329378, 2.2163186],
        [0.0006794373, 0.0, 0.007512709],
    ),
    (
        "AlSb",
        [0.0, 4.1393747, 4.6692543],
        [0.0, 0.09400908, 1.30057],
    ),
    (
        "AlSb_palik",
        [0.0, 4.1393747, 4.6692543],
        [0.0, 0.09400908, 1.30057],
    ),
    (
        "Au",
        [0.14303598, 0.37530708, 1.4420453],
        [3.982997, 2.3855565, 1.6033592],
    ),
    (
        "Be",
        [4.1850123, 3.1850293, 2.7840612],
        [3.835466, 3.0101223, 2.868994],
    ),
    (
        "Be_palik",
        [4.1850123, 3.1850293, 2.7840612],
        [3.835466, 3.0101223, 2.868994],
    ),
    (
        "Cr",
        [4.3696675, 2.9165053, 1.6549046],
        [5.206547, 4.231306, 3.7546988],
    ),
    ("CsI", [2.1448996, 1.7023189, 1.6624272], [0.0, 0.0, 0.0]),
    (
        "CsI_palik",
        [2.1448996, 1.7023189, 1.6624272],
        [0.0, 0.0, 0.0],
    ),
    (
        "Cu",
        [0.20100547, 0.9237495, 1.1022154],
        [3.9132621, 2.4530451, 2.1420898],
    ),
    (
        "Cu2O",
        [3.5517726, 2.9498696, 2.7518754],
        [0.11420702, 0.19389686, 0.6061339],
    ),
    (
        "Cu2O_palik",
        [3.5517726, 2.9498696, 2.7518754],
        [0.11420702, 0.19389686, 0.6061339],
    ),
    (
        "CuO",
        [3.247541, 2.4478052, 2.2102196],
        [0.52108955, 0.57003075, 0.72217894],
    ),
    (
        "CuO_palik",
        [3.247541, 2.4478052, 2.2102196],
        [0.52108955, 0.57003075, 0.72217894],
    ),
    (
        "Cu_palik",
        [0.21322851, 0.9197154, 1.1024108],
        [3.9218733, 2.4573317, 2.136584],
    ),
    (
        "Hg",
        [2.3989387, 1.440028, 0.9095704],
        [6.327587, 4.371925, 3.4217637],
    ),
    (
        "HgTe",
        [4.77904, 3.2311962, 2.6599011],
        [1.6316127, 1.5808104, 1.7292874],
    ),
    (
        "HgTe_palik",
        [4.77904, 3.2311962, 2.6599011],
        [1.6316127, 1.5808104, 1.7292874],
    ),
    (
        "Hg_palik",
        [2.3989387, 1.440028, 0.9095704],
        [6.327587, 4.371925, 3.4217637],
    ),
    (
        "Ir",
        [3.0863, 2.0821905, 1.6179146],
        [5.592153, 4.067088, 3.267312],
    ),
    (
        "Ir_palik",
        [3.0863, 2.0821905, 1.6179146],
        [5.592153, 4.067088, 3.267312],
    ),
    (
        "K",
        [0.06404319, 0.046409767, 0.038184915],
        [2.1041996, 1.34894, 0.9131259],
    ),
    (
        "K_palik",
        [0.06404319, 0.046409767, 0.038184915],
        [2.1041996, 1.34894, 0.9131259],
    ),
    (
        "Li",
        [0.26579094, 0.19561832, 0.22094862],
        [3.540155, 2.3111234, 1.6686072],
    ),
    (
        "Li_palik",
        [0.26579094, 0.19561832, 0.22094862],
        [3.540155, 2.3111234, 1.6686072],
    ),
    (
        "MgO",
        [2.0895839, 1.6507235, 1.594879],
        [4.3326952e-12, 0.0, 2.4986457e-11],
    ),
    (
        "MgO_palik",
        [2.0895839, 1.6507235, 1.594879],
        [4.3326952e-12, 0.0, 2.4986457e-11],
    ),
    (
        "Mo",
        [4.483974, 3.5251307, 2.7763104],
        [4.1114373, 3.420827, 3.1506073],
    ),
    (
        "Mo_palik",
        [4.483974, 3.5251307, 2.7763104],
        [4.1114373, 3.420827, 3.1506073],
    ),
    (
        "Na_palik",
        [0.060269356, 0.056140948, 0.061988432],
        [3.1792734, 2.1124904, 1.5790411],
    ),
    (
        "Nb",
        [3.420074, 2.7900932, 2.3956294],
        [3.4413946, 2.7376661, 2.5797458],
    ),
    (
        "Nb_palik",
        [3.420074, 2.7900932, 2.3956294],
        [3.4413946, 2.7376661, 2.5797458],
    ),
    (
        "Ni_palik",
        [2.3673046, 1.6633731, 1.4670781],
        [4.4988117, 3.050153, 2.3454392],
    ),
    (
        "Rh",
        [2.5857935, 1.8602164, 1.5542634],
        [6.7822604, 4.702987, 3.976073],
    ),
    (
        "Rh_palik",
        [2.5857935, 1.8602164, 1.5542634],
        [6.7822604, 4.702987, 3.976073],
    ),
    (
        "Se",
        [4.0583115, 2.842935, 2.8208535],
        [0.75404954, 0.6384435, 0.52180755],
    ),
    (
        "Se-e",
        [5.722849, 4.165736, 4.0813384],
        [0.8711363, 1.1051575, 1.5653203],
    ),
    (
        "Se-e_palik",
        [5.722849, 4.165736, 4.0813384],
        [0.8711363, 1.1051575, 1.5653203],
    ),
    (
        "Se_palik",
        [4.0583115, 2.842935, 2.8208535],
        [0.75404954, 0.6384435, 0.52180755],
    ),
    (
        "SiC",
        [3.1723416, 2.5259717, 2.4793706],
        [7.5376636e-07, 0.0, 1.0192531e-05],
    ),
    (
        "SiC_palik",
        [3.1723416, 2.5259717, 2.4793706],
        [7.5376636e-07, 0.0, 1.0192531e-05],
    ),
    ("SnTe", [4.5242496, 1.981645, 1.2815913], [0.0, 0.0, 0.0]),
    (
        "SnTe_palik",
        [4.5242496, 1.981645, 1.2815913],
        [0.0, 0.0, 0.0],
    ),
    (
        "Ta",
        [2.062721, 2.3929389, 2.6279287],
        [2.4083598, 1.7414864, 1.9470278],
    ),
    (
        "Ta_palik",
        [2.062721, 2.3929389, 2.6279287],
        [2.4083598, 1.7414864, 1.9470278],
    ),
    (
        "Te",
        [7.3902335, 4.482105, 2.637106],
        [3.2560222, 3.5270588, 3.2920542],
    ),
    (
        "Te-e",
        [7.508907, 4.2964287, 2.3699877],
        [5.5839286, 4.947205, 3.9975922],
    ),
    (
        "Te-e_palik",
        [7.508907, 4.2964287, 2.3699877],
        [5.5839286, 4.947205, 3.9975922],
    ),
    (
        "Te_palik",
        [7.3902335, 4.482105, 2.637106],
        [3.2560222, 3.5270588, 3.2920542],
    ),
    ("ThF4", [1.8307136, 1.4422286, 1.3876476], [0.0, 0.0, 0.0]),
    (
        "ThF4_palik",
        [1.8307136, 1.4422286, 1.3876476],
        [0.0, 0.0, 0.0],
    ),
    (
        "TiC",
        [3.7005284, 2.8374221, 2.582287],
        [3.265635, 2.3515892, 2.1727905],
    ),
    (
        "TiC_palik",
        [3.7005284, 2.8374221, 2.582287],
        [3.265635, 2.3515892, 2.1727905],
    ),
    (
        "TiN",
        [1.6484497, 1.150516, 1.3798234],
        [3.368328, 1.9434981, 1.1020677],
    ),
    (
        "TiN_palik",
        [1.6484497, 1.150516, 1.3798234],
        [3.368328, 1.9434981, 1.1020677],
    ),
    (
        "TiO2",
        [3.45661, 2.8017359, 2.905175],
        [0.00010526484, 0.0, 0.0006528865],
    ),
    (
        "TiO2-e",
        [3.1065645, 2.5131683, 2.5824444],
        [2.9751605e-05, 0.0, 0.00018269809],
    ),
    (
        "TiO2-e_palik",
        [3.1065645, 2.5131683, 2.5824444],
        [2.9751605e-05, 0.0, 0.00018269809],
    ),
    (
        "TiO2_palik",
        [3.45661, 2.8017359, 2.905175],
        [0.00010526484, 0.0, 0.0006528865],
    ),
    (
        "VC",
        [3.657566, 2.752736, 2.532672],
        [3.0683007, 2.1986873, 1.9631927],
    ),
    (
        "VC_palik",
        [3.657566, 2.752736, 2.532672],
        [3.0683007, 2.1986873, 1.9631927],
    ),
    (
        "VN",
        [2.8656023, 2.119189, 1.9400911],
        [3.0322425, 2.0561156, 1.6163063],
    ),
    (
        "VN_palik",
        [2.8656023, 2.119189, 1.9400911],
        [3.0322425, 2.0561156, 1.6163063],
    ),
    (
        "V_palik",
        [4.277582, 3.5129488, 2.7610714],
        [3.4913008, 2.8894548, 3.111522],
    ),
    (
        "W",
        [4.3708167, 3.3002465, 2.9984074],
        [3.5006406, 2.604874, 2.2732332],
    ),
    (
        "a-C",
        [2.9440458, 2.2271364, 1.9681617],
        [0.8874649, 0.7992985, 0.81529],
    ),
    ("d-C", [2.7087197, 2.3188257, 2.2288976], [0.0, 0.0, 0.0]),
    (
        "d-C_palik",
        [2.7087197, 2.3188257, 2.2288976],
        [0.0, 0.0, 0.0],
    ),
];
