//! The lane types the shading and sampling maths is written over, once: [`Float`] (f32
//! numbers, one or many lanes) and [`Vector3`] (three-component vectors of them).
//!
//! A formula written over these traits is compiled for the scalar path tracer with `f32`
//! (one lane, mask `bool`) and glam's `Vec3A`, for four lanes with glam's `Vec4` (the
//! packets' triangle and sphere tests), and for sixteen: the wavefront
//! ([`crate::integrator::wavefront`]) with its `F` and `V3` under AVX-512 (`avx512`, which
//! the packets' triangle test shares) or AVX2 — the manner of Mitsuba 3, whose plugins are
//! one source compiled to scalar and
//! vector variants by Dr.Jit. Every operation is the IEEE operation of the same name lane by
//! lane (no fused multiply-add, no approximations), and a branch is a `select` of both sides,
//! so each lane of a vector instance computes exactly the scalar instance's bits: equal by
//! construction. The functions built on them are `#[inline(always)]`, so that they are
//! compiled into their callers with the callers' target features (a call would lose them).

#[cfg(target_arch = "x86_64")]
pub(crate) mod avx;
#[cfg(target_arch = "x86_64")]
pub(crate) mod avx2;
#[cfg(target_arch = "x86_64")]
pub(crate) mod avx512;
pub mod math;

use glam::{BVec4A, Vec3, Vec3A, Vec4};
use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// The lanes of a bit mask (bit i: lane i), lowest first: the loop over a packet's or a
/// lane vector's active lanes.
#[inline(always)]
pub fn lanes_of(mask: u32) -> impl Iterator<Item = usize> {
    lanes_of64(mask.into())
}

/// [`lanes_of`] for a mask of up to 64 lanes.
#[inline(always)]
pub fn lanes_of64(mask: u64) -> impl Iterator<Item = usize> {
    let mut m = mask;
    std::iter::from_fn(move || {
        (m != 0).then(|| {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            l
        })
    })
}

/// f32 lanes: `f32` itself, or a SIMD vector of them.
pub trait Float:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// Which lanes a comparison holds in: `bool` for one lane, a bit a lane for vectors.
    type Mask: Copy
        + BitAnd<Output = Self::Mask>
        + BitOr<Output = Self::Mask>
        + Not<Output = Self::Mask>;
    fn splat(x: f32) -> Self;
    #[inline(always)]
    fn zero() -> Self {
        Self::splat(0.0)
    }
    fn sqrt(self) -> Self;
    /// |x|: the sign bit cleared.
    fn abs(self) -> Self;
    /// `f32::max` against an `o` that is not NaN (`o` where `self` is NaN).
    fn max_num(self, o: Self) -> Self;
    /// `f32::min` against an `o` that is not NaN (`o` where `self` is NaN).
    fn min_num(self, o: Self) -> Self;
    /// C's `fmax`, as `f32::max`: the larger, or where one side is NaN the other.
    #[inline(always)]
    fn fmax(self, o: Self) -> Self {
        // (`o.max_num(self)` is `self` where `o` is NaN; NaN fails `self == self`.)
        Self::select(self.eq(self), o.max_num(self), o)
    }
    /// The magnitude of `self` with the sign bit of `sign`.
    fn copysign(self, sign: Self) -> Self;
    /// Ordered comparisons: false where either side is NaN.
    fn lt(self, o: Self) -> Self::Mask;
    fn le(self, o: Self) -> Self::Mask;
    fn gt(self, o: Self) -> Self::Mask;
    fn ge(self, o: Self) -> Self::Mask;
    fn eq(self, o: Self) -> Self::Mask;
    /// `a` in the lanes of `m`, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    /// Whether any lane of `m` is set (for early exits that skip work no lane needs).
    fn any(m: Self::Mask) -> bool;
    /// 2ⁿ for n = `self`, an integer in [−126, 127]: the float whose exponent field is
    /// n + 127 and whose significand is zero.
    fn pow2i(self) -> Self;
    /// (m, e) with x = m·2ᵉ and m in [1, 2), for x positive and normal: the significand
    /// and exponent fields, read as they are (the sign is ignored; other x give other
    /// numbers, the same in every instance).
    fn frexp(self) -> (Self, Self);
    /// Rounded toward zero to a whole number (NaN and ±∞ kept).
    fn trunc(self) -> Self;
    /// `table[i]` in each lane for the lane's `index` i, a whole number (`trunc`'s) below
    /// 2³¹, clamped to the table: a tabulated function's lookup with any table in any lane
    /// (where the tables are concatenated). Panics on an empty table.
    fn gather(table: &[f32], index: Self) -> Self;
}

/// Sixteen f32 lanes in registers ([`avx512::F`], [`avx2::F`]): what code written once for
/// either needs besides [`Float`].
#[cfg(target_arch = "x86_64")]
pub trait Sixteen: Float {
    fn load(a: &[f32; 16]) -> Self;
    fn to_array(self) -> [f32; 16];
    /// The lanes of `m` as bits, bit i for lane i.
    fn bits(m: Self::Mask) -> u32;
    /// The mask of the lanes whose bit is set in `bits` (bit i for lane i).
    fn from_bits(bits: u32) -> Self::Mask;
    /// `f32::next_up` of positive finite numbers: the next float up (one more in the bits).
    fn next_up(self) -> Self;
    /// `first + i` in lane i.
    fn iota(first: f32) -> Self;
    /// The least lane of `t` (none NaN), and of the lanes that hold it the least `key`.
    fn min_by_key(t: Self, key: Self) -> (f32, f32);
}

/// Three-component vectors of [`Float`] lanes, with glam's order of operations (the dot
/// product is (x·x' + y·y') + z·z').
pub trait Vector3:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self>
{
    type F: Float;
    fn new(x: Self::F, y: Self::F, z: Self::F) -> Self;
    fn x(self) -> Self::F;
    fn y(self) -> Self::F;
    fn z(self) -> Self::F;
    fn dot(self, o: Self) -> Self::F;
    /// Each component times `s`.
    fn scale(self, s: Self::F) -> Self;
    /// Each component divided by `s`.
    fn div(self, s: Self::F) -> Self;
    fn select(m: Mask<Self>, a: Self, b: Self) -> Self;
    /// `v` in every lane.
    fn broadcast(v: Vec3A) -> Self;
    /// Each component's |x|.
    fn abs(self) -> Self;
    /// The cross product, as glam's: x = a.y·b.z − b.y·a.z, and so on.
    fn cross(self, o: Self) -> Self;
    /// The unit vector: each component divided by the length (glam's SSE `normalize`).
    fn normalize(self) -> Self;
    /// The largest component, as glam's `Vec3::max_element`: x.max(y.max(z)) with
    /// `f32::max`.
    #[inline(always)]
    fn max_element(self) -> Self::F {
        self.x().fmax(self.y().fmax(self.z()))
    }
}

/// The lane mask of a vector type.
pub type Mask<V> = <<V as Vector3>::F as Float>::Mask;

/// One lane.
macro_rules! one_lane {
    ($t:ty) => {
        impl Float for $t {
            type Mask = bool;
            #[inline(always)]
            fn splat(x: f32) -> $t {
                x as $t
            }
            #[inline(always)]
            fn sqrt(self) -> $t {
                <$t>::sqrt(self)
            }
            #[inline(always)]
            fn abs(self) -> $t {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn max_num(self, o: $t) -> $t {
                <$t>::max(self, o)
            }
            #[inline(always)]
            fn min_num(self, o: $t) -> $t {
                <$t>::min(self, o)
            }
            #[inline(always)]
            fn fmax(self, o: $t) -> $t {
                <$t>::max(self, o)
            }
            #[inline(always)]
            fn copysign(self, sign: $t) -> $t {
                <$t>::copysign(self, sign)
            }
            #[inline(always)]
            fn lt(self, o: $t) -> bool {
                self < o
            }
            #[inline(always)]
            fn le(self, o: $t) -> bool {
                self <= o
            }
            #[inline(always)]
            fn gt(self, o: $t) -> bool {
                self > o
            }
            #[inline(always)]
            fn ge(self, o: $t) -> bool {
                self >= o
            }
            #[inline(always)]
            fn eq(self, o: $t) -> bool {
                self == o
            }
            #[inline(always)]
            fn select(m: bool, a: $t, b: $t) -> $t {
                if m {
                    a
                } else {
                    b
                }
            }
            #[inline(always)]
            fn any(m: bool) -> bool {
                m
            }
            #[inline(always)]
            fn pow2i(self) -> $t {
                <$t>::from_bits(((self as i32 + 127) as u32) << 23)
            }
            #[inline(always)]
            fn frexp(self) -> ($t, $t) {
                let b = self.to_bits();
                let m = <$t>::from_bits((b & 0x007f_ffff) | 0x3f80_0000);
                (m, ((b >> 23) & 0xff) as $t - 127.0)
            }
            #[inline(always)]
            fn trunc(self) -> $t {
                // (Whole already from 2²³ up; the sign kept for −0.)
                if self.abs() < 8_388_608.0 {
                    ((self as i32) as $t).copysign(self)
                } else {
                    self
                }
            }
            #[inline(always)]
            fn gather(table: &[f32], index: $t) -> $t {
                // (`as usize` takes NaN and negatives to 0.)
                table[(index as usize).min(table.len() - 1)] as $t
            }
        }
    };
}
one_lane!(f32);

/// Four lanes in an SSE (or NEON) register: shadow-ray packets of four.
impl Float for Vec4 {
    type Mask = BVec4A;
    #[inline(always)]
    fn splat(x: f32) -> Vec4 {
        Vec4::splat(x)
    }
    #[inline(always)]
    fn sqrt(self) -> Vec4 {
        crate::geometry::sqrt4(self)
    }
    #[inline(always)]
    fn abs(self) -> Vec4 {
        Vec4::abs(self)
    }
    #[inline(always)]
    fn max_num(self, o: Vec4) -> Vec4 {
        Vec4::max(self, o)
    }
    #[inline(always)]
    fn min_num(self, o: Vec4) -> Vec4 {
        Vec4::min(self, o)
    }
    #[inline(always)]
    fn copysign(self, sign: Vec4) -> Vec4 {
        Vec4::copysign(self, sign)
    }
    #[inline(always)]
    fn lt(self, o: Vec4) -> BVec4A {
        self.cmplt(o)
    }
    #[inline(always)]
    fn le(self, o: Vec4) -> BVec4A {
        self.cmple(o)
    }
    #[inline(always)]
    fn gt(self, o: Vec4) -> BVec4A {
        self.cmpgt(o)
    }
    #[inline(always)]
    fn ge(self, o: Vec4) -> BVec4A {
        self.cmpge(o)
    }
    #[inline(always)]
    fn eq(self, o: Vec4) -> BVec4A {
        self.cmpeq(o)
    }
    #[inline(always)]
    fn select(m: BVec4A, a: Vec4, b: Vec4) -> Vec4 {
        Vec4::select(m, a, b)
    }
    #[inline(always)]
    fn any(m: BVec4A) -> bool {
        m.any()
    }
    #[inline(always)]
    fn pow2i(self) -> Vec4 {
        Vec4::from_array(self.to_array().map(f32::pow2i))
    }
    #[inline(always)]
    fn frexp(self) -> (Vec4, Vec4) {
        let [a, b, c, d] = self.to_array().map(f32::frexp);
        (Vec4::new(a.0, b.0, c.0, d.0), Vec4::new(a.1, b.1, c.1, d.1))
    }
    #[inline(always)]
    fn trunc(self) -> Vec4 {
        Vec4::from_array(self.to_array().map(f32::trunc))
    }
    #[inline(always)]
    fn gather(table: &[f32], index: Vec4) -> Vec4 {
        Vec4::from_array(index.to_array().map(|i| f32::gather(table, i)))
    }
}

/// glam's `Vec3A` (points, directions) and `Vec3` (colours, `crate::Color`): the same
/// operations on three scalars, one instance of each.
macro_rules! glam_vector3 {
    ($t:ty) => {
        impl Vector3 for $t {
            type F = f32;
            #[inline(always)]
            fn new(x: f32, y: f32, z: f32) -> $t {
                <$t>::new(x, y, z)
            }
            #[inline(always)]
            fn x(self) -> f32 {
                self.x
            }
            #[inline(always)]
            fn y(self) -> f32 {
                self.y
            }
            #[inline(always)]
            fn z(self) -> f32 {
                self.z
            }
            #[inline(always)]
            fn dot(self, o: $t) -> f32 {
                <$t>::dot(self, o)
            }
            #[inline(always)]
            fn scale(self, s: f32) -> $t {
                self * s
            }
            #[inline(always)]
            fn div(self, s: f32) -> $t {
                self / s
            }
            #[inline(always)]
            fn select(m: bool, a: $t, b: $t) -> $t {
                if m {
                    a
                } else {
                    b
                }
            }
            #[inline(always)]
            fn broadcast(v: Vec3A) -> $t {
                v.into()
            }
            #[inline(always)]
            fn abs(self) -> $t {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn cross(self, o: $t) -> $t {
                <$t>::cross(self, o)
            }
            #[inline(always)]
            fn normalize(self) -> $t {
                <$t>::normalize(self)
            }
        }
    };
}
glam_vector3!(Vec3A);
glam_vector3!(Vec3);

/// Three-component vectors of lanes, a component to a vector of lanes (structure of arrays):
/// the vector type of the wide instances, for points, directions and colours alike.
#[derive(Clone, Copy)]
pub struct V3<T> {
    pub x: T,
    pub y: T,
    pub z: T,
}

impl<T: Float> V3<T> {
    #[inline(always)]
    pub fn splat(v: [f32; 3]) -> Self {
        V3 {
            x: T::splat(v[0]),
            y: T::splat(v[1]),
            z: T::splat(v[2]),
        }
    }
    #[inline(always)]
    pub fn zero() -> Self {
        V3::splat([0.0; 3])
    }
    /// glam's `cross`: x = a.y·b.z − b.y·a.z, and so on.
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        V3 {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }
    /// Lanes where all three components equal zero (`Vec3 == Vec3::ZERO`).
    #[inline(always)]
    pub fn is_zero(self) -> T::Mask {
        let z = T::zero();
        self.x.eq(z) & self.y.eq(z) & self.z.eq(z)
    }
}

impl<T: Float> Vector3 for V3<T> {
    type F = T;
    #[inline(always)]
    fn new(x: T, y: T, z: T) -> Self {
        V3 { x, y, z }
    }
    #[inline(always)]
    fn x(self) -> T {
        self.x
    }
    #[inline(always)]
    fn y(self) -> T {
        self.y
    }
    #[inline(always)]
    fn z(self) -> T {
        self.z
    }
    /// glam's `dot`: (x·x' + y·y') + z·z'.
    #[inline(always)]
    fn dot(self, o: Self) -> T {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    #[inline(always)]
    fn scale(self, s: T) -> Self {
        V3::new(self.x * s, self.y * s, self.z * s)
    }
    #[inline(always)]
    fn div(self, s: T) -> Self {
        V3::new(self.x / s, self.y / s, self.z / s)
    }
    #[inline(always)]
    fn select(m: T::Mask, a: Self, b: Self) -> Self {
        V3::new(
            T::select(m, a.x, b.x),
            T::select(m, a.y, b.y),
            T::select(m, a.z, b.z),
        )
    }
    #[inline(always)]
    fn broadcast(v: Vec3A) -> Self {
        V3::splat(v.into())
    }
    #[inline(always)]
    fn abs(self) -> Self {
        V3::new(self.x.abs(), self.y.abs(), self.z.abs())
    }
    #[inline(always)]
    fn cross(self, o: Self) -> Self {
        V3::cross(self, o)
    }
    /// glam's SSE `normalize`: each component divided by the length.
    #[inline(always)]
    fn normalize(self) -> Self {
        self.div(self.dot(self).sqrt())
    }
}

impl<T: Float> Add for V3<T> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        V3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl<T: Float> Sub for V3<T> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        V3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl<T: Float> Mul for V3<T> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        V3::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
}
impl<T: Float> Neg for V3<T> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        V3::new(-self.x, -self.y, -self.z)
    }
}

#[cfg(test)]
mod tests {
    use super::Float;

    /// Inputs at the edges of `trunc` and `gather`: signs, zeros, halves, the largest
    /// floats with a fraction, whole ones beyond, infinities and NaN.
    const EDGES: [f32; 16] = [
        0.0,
        -0.0,
        -0.5,
        0.5,
        1.0,
        62.99,
        63.0,
        -1.5,
        8_388_607.5,
        -8_388_607.5,
        16_777_216.0,
        3e9,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        1e-40,
    ];

    /// `trunc` of one lane is std's, bit for bit; `gather` reads the clamped entry.
    #[test]
    fn trunc_and_gather_of_one_lane() {
        for x in EDGES {
            assert_eq!(Float::trunc(x).to_bits(), x.trunc().to_bits(), "trunc {x}");
        }
        let table: Vec<f32> = (0..64).map(|i| i as f32 * 0.5).collect();
        assert_eq!(f32::gather(&table, 5.0), 2.5);
        assert_eq!(f32::gather(&table, -3.0), 0.0);
        assert_eq!(f32::gather(&table, f32::NAN), 0.0);
        assert_eq!(f32::gather(&table, 64.0), 31.5);
        assert_eq!(f32::gather(&table, 1e9), 31.5);
    }

    /// Sixteen lanes (AVX-512, AVX2) compute each lane's `trunc` and `gather` as one lane
    /// does.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn trunc_and_gather_in_lanes() {
        let table: Vec<f32> = (0..40).map(|i| (i * i) as f32).collect();
        // Whole indices below 2³¹ (and NaN and negatives), as the lookups make them.
        let index = EDGES.map(|x| {
            if x.abs() < 2e9 {
                x.trunc()
            } else {
                x.min(39.0)
            }
        });
        let want_t = EDGES.map(|x| Float::trunc(x).to_bits());
        let want_g = index.map(|i| f32::gather(&table, i).to_bits());
        if crate::cpu::avx512() {
            use super::avx512::F;
            // SAFETY: the CPU has AVX-512F.
            let (t, g) = unsafe { lanes512(&table, &index) };
            assert_eq!(t.map(f32::to_bits), want_t, "AVX-512 trunc");
            assert_eq!(g.map(f32::to_bits), want_g, "AVX-512 gather");
            #[target_feature(enable = "avx512f")]
            unsafe fn lanes512(table: &[f32], index: &[f32; 16]) -> ([f32; 16], [f32; 16]) {
                (
                    F::load(&EDGES).trunc().to_array(),
                    F::gather(table, F::load(index)).to_array(),
                )
            }
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            use super::avx2::F;
            // SAFETY: the CPU has AVX2.
            let (t, g) = unsafe { lanes256(&table, &index) };
            assert_eq!(t.map(f32::to_bits), want_t, "AVX2 trunc");
            assert_eq!(g.map(f32::to_bits), want_g, "AVX2 gather");
            #[target_feature(enable = "avx,avx2")]
            unsafe fn lanes256(table: &[f32], index: &[f32; 16]) -> ([f32; 16], [f32; 16]) {
                (
                    F::load(&EDGES).trunc().to_array(),
                    F::gather(table, F::load(index)).to_array(),
                )
            }
        }
    }
}
