//! The stored photon: 24 bytes.
//!
//! | bytes | field |
//! |---|---|
//! | 12 | position, f32 × 3 |
//! | 7 | power: three 16-bit mantissas sharing one 8-bit exponent (relative error ≤ 2⁻¹⁶ of the largest channel) |
//! | 2 | incoming direction (towards where the photon came from), octahedral, 8 bits a coordinate |
//! | 1 | flags: kd-tree split axis (2 bits), path length in segments (4 bits, 15 = 15 or more), caustic, shadow |
//!
//! Ten million photons take 240 MB.

use crate::Color;
use glam::Vec3A;

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    pub p: [f32; 3],
    power: [u16; 3],
    exp: i8,
    dir: [u8; 2],
    flags: u8,
}

const AXIS_MASK: u8 = 0b11;
const DEPTH_SHIFT: u8 = 2;
const DEPTH_MASK: u8 = 0b1111 << DEPTH_SHIFT;
const CAUSTIC: u8 = 1 << 6;
const SHADOW: u8 = 1 << 7;
/// Largest path length a photon records; longer paths read as this.
pub const MAX_DEPTH: u32 = 15;

impl Photon {
    /// A photon at `p` carrying `power` (W), that arrived from direction `wi` (unit, pointing
    /// away from the surface towards where it came from) after `depth` path segments.
    pub fn new(p: Vec3A, power: Color, wi: Vec3A, depth: u32, caustic: bool) -> Photon {
        let (power, exp) = encode_power(power);
        let mut flags = (depth.min(MAX_DEPTH) as u8) << DEPTH_SHIFT;
        if caustic {
            flags |= CAUSTIC;
        }
        Photon {
            p: p.to_array(),
            power,
            exp,
            dir: encode_oct(wi),
            flags,
        }
    }

    /// A shadow photon: a point a light's direct photon would have reached had the first
    /// surface not stopped it.
    pub fn shadow(p: Vec3A, wi: Vec3A) -> Photon {
        let mut ph = Photon::new(p, Color::ZERO, wi, 1, false);
        ph.flags |= SHADOW;
        ph
    }

    #[inline]
    pub fn pos(&self) -> Vec3A {
        Vec3A::from_array(self.p)
    }
    #[inline]
    pub fn power(&self) -> Color {
        let s = exp2i(self.exp as i32) * (1.0 / 65535.0);
        Color::new(
            self.power[0] as f32 * s,
            self.power[1] as f32 * s,
            self.power[2] as f32 * s,
        )
    }
    /// Unit direction towards where the photon came from.
    #[inline]
    pub fn wi(&self) -> Vec3A {
        decode_oct(self.dir)
    }
    /// Path segments from the light to this photon (1: direct), at most [`MAX_DEPTH`].
    #[inline]
    pub fn depth(&self) -> u32 {
        ((self.flags & DEPTH_MASK) >> DEPTH_SHIFT) as u32
    }
    /// The photon's path since the light was specular only (mirror, glass) before this hit.
    #[inline]
    pub fn is_caustic(&self) -> bool {
        self.flags & CAUSTIC != 0
    }
    #[inline]
    pub fn is_shadow(&self) -> bool {
        self.flags & SHADOW != 0
    }
    #[inline]
    pub(crate) fn axis(&self) -> usize {
        (self.flags & AXIS_MASK) as usize
    }
    #[inline]
    pub(crate) fn set_axis(&mut self, a: usize) {
        self.flags = (self.flags & !AXIS_MASK) | a as u8;
    }
}

#[inline]
fn exp2i(e: i32) -> f32 {
    // 2^e for e in the normal range (the exponents stored come from normal floats).
    f32::from_bits(((e.clamp(-126, 127) + 127) as u32) << 23)
}

/// Shared-exponent encoding: the largest channel m = f·2^e with f in [0.5, 1); each channel
/// is stored as round(c / 2^e · 65535).
fn encode_power(c: Color) -> ([u16; 3], i8) {
    let c = c.max(Color::ZERO);
    let m = c.max_element();
    if m.is_nan() || m <= 1e-30 || !m.is_finite() {
        return ([0; 3], 0);
    }
    // Exponent of m as f·2^e with f in [0.5, 1).
    let e = ((m.to_bits() >> 23) & 0xff) as i32 - 126;
    let e = e.clamp(-100, 127);
    let s = 65535.0 / exp2i(e);
    let q = |v: f32| (v * s).round().clamp(0.0, 65535.0) as u16;
    ([q(c.x), q(c.y), q(c.z)], e as i8)
}

/// Octahedral encoding of a unit vector (Meyer et al. 2010), 8 bits a coordinate.
fn encode_oct(w: Vec3A) -> [u8; 2] {
    let l1 = w.x.abs() + w.y.abs() + w.z.abs();
    if l1.is_nan() || l1 <= 0.0 {
        return [128, 128];
    }
    let (mut x, mut y) = (w.x / l1, w.y / l1);
    if w.z < 0.0 {
        let (ox, oy) = (x, y);
        x = (1.0 - oy.abs()) * ox.signum();
        y = (1.0 - ox.abs()) * oy.signum();
    }
    let q = |v: f32| ((v * 0.5 + 0.5) * 255.0).round().clamp(0.0, 255.0) as u8;
    [q(x), q(y)]
}

fn decode_oct(d: [u8; 2]) -> Vec3A {
    let x = d[0] as f32 / 255.0 * 2.0 - 1.0;
    let y = d[1] as f32 / 255.0 * 2.0 - 1.0;
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum())
    } else {
        (x, y)
    };
    Vec3A::new(x, y, z).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let c = Color::new(0.3, 1e-3, 7.0);
        let ph = Photon::new(
            Vec3A::new(1.0, 2.0, 3.0),
            c,
            Vec3A::new(0.0, -0.6, -0.8),
            5,
            true,
        );
        let d = ph.power();
        assert!((d - c).abs().max_element() < 7.0 / 30000.0, "{d:?}");
        assert!(ph.wi().dot(Vec3A::new(0.0, -0.6, -0.8)) > 0.999);
        assert_eq!(ph.depth(), 5);
        assert!(ph.is_caustic() && !ph.is_shadow());
        assert_eq!(std::mem::size_of::<Photon>(), 24);
    }
}
