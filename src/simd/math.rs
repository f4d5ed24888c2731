//! exp and log over any lanes, one source for one path and for sixteen: the polynomials of
//! Cephes' `expf` and `logf` (Moshier, *Methods and Programs for Mathematical Functions*,
//! 1989), built of the IEEE operations every [`Float`] instance performs alike, so a lane
//! computes the bits that `f32` computes. (libm's `expf` and `logf` are as accurate, but
//! a lane form must be the scalar form too, or the wavefront and the path tracer would
//! sample the Beckmann distribution with different numbers.) Both are within 2 ulp of the
//! exact value (`tests` below).

use super::Float;

/// e^x, within 2 ulp; results below 2⁻¹²⁵ flush to zero (x < −86.64: so that no step
/// makes a subnormal number, which costs x86 a microcode assist of a hundred cycles or
/// more, where e^(−z²) of a large z is common) and those above the largest float are +∞
/// (x > 88.723). Cephes' `expf`: x = n ln 2 + r with |r| ≤ ln 2 / 2 (ln 2 in two parts, so
/// that n ln 2 is exact), e^r by a degree-7 polynomial, times 2ⁿ.
/// −125 ln 2: [`exp`]'s least argument, whose 2ⁿ is 2⁻¹²⁵.
const LOW: f32 = -86.643_4;

#[allow(clippy::excessive_precision)]
#[inline(always)]
pub fn exp<T: Float>(x: T) -> T {
    let k = T::splat;
    let (zero, one) = (T::zero(), k(1.0));
    let xc = x.max_num(k(LOW)).min_num(k(88.722_84));
    // n = x log₂e rounded to the nearest integer, by adding and taking away 1.5·2²³ (at
    // that size a float's last bit is 1): two additions, where a floor takes two
    // conversions and a compare, on the sampler's chain of dependent steps.
    let round = k(12_582_912.0);
    let n = (k(std::f32::consts::LOG2_E) * xc + round) - round;
    let r = xc - n * k(0.693_359_375);
    let r = r - n * k(-2.121_944_4e-4);
    let r2 = r * r;
    let p = poly(
        r,
        [
            5.000_000_12e-1,
            1.666_666_55e-1,
            4.166_579_59e-2,
            8.333_451_9e-3,
            1.398_199_95e-3,
            1.987_569_15e-4,
        ],
    ) * r2
        + r
        + one;
    // 2ⁿ for n up to 128 as 2^min(n, 127), times 2 for 128.
    let big = n.gt(k(127.0));
    let y = p * n.min_num(k(127.0)).pow2i() * T::select(big, k(2.0), one);
    let y = T::select(x.gt(k(88.722_84)), k(f32::INFINITY), y);
    let y = T::select(x.lt(k(LOW)), zero, y);
    // NaN stays NaN.
    T::select(x.eq(x), y, x)
}

/// The natural logarithm, within 2 ulp: −∞ at zero, NaN below it, +∞ at +∞. Cephes'
/// `logf`: x = m·2ᵉ with m in [√½, √2), ln x = e ln 2 + ln m with ln(1 + f) by a degree-9
/// polynomial in f = m − 1.
#[allow(clippy::excessive_precision)]
#[inline(always)]
pub fn ln<T: Float>(x: T) -> T {
    let k = T::splat;
    let (zero, one) = (T::zero(), k(1.0));
    // Subnormals scaled by 2²³ into the normal range first.
    let tiny = x.lt(k(f32::MIN_POSITIVE));
    let (m, e) = T::select(tiny, x * k(8_388_608.0), x).frexp();
    let e = T::select(tiny, e - k(23.0), e);
    let big = m.ge(k(std::f32::consts::SQRT_2));
    let f = T::select(big, k(0.5) * m - one, m - one);
    let e = T::select(big, e + one, e);
    let z = f * f;
    let y = poly(
        f,
        [
            3.333_333_117_4e-1,
            -2.499_999_399_3e-1,
            2.000_071_476_5e-1,
            -1.666_805_766_5e-1,
            1.424_932_278_7e-1,
            -1.242_014_084_6e-1,
            1.167_699_874_0e-1,
            -1.151_461_031_0e-1,
            7.037_683_629_2e-2,
        ],
    ) * f
        * z;
    let y = y + k(-2.121_944_4e-4) * e;
    let y = y + k(-0.5) * z;
    let r = f + y + k(0.693_359_375) * e;
    let r = T::select(x.eq(zero), k(f32::NEG_INFINITY), r);
    let r = T::select(x.eq(k(f32::INFINITY)), x, r);
    // Below zero and NaN: NaN.
    T::select(x.ge(zero), r, k(f32::NAN))
}

/// c₀ + c₁x + … + c_{N−1}x^{N−1} (N ≤ 16) by Estrin's scheme: pairs c_{2i} + c_{2i+1}x,
/// then pairs of those with x², and so on, a tree of ⌈log₂ N⌉ levels where Horner's rule is
/// a chain of N − 1 dependent multiply-adds: the latency that one path's sampler waits on.
/// (The loops' bounds are constants once N is, so they unroll.)
#[inline(always)]
pub fn poly<T: Float, const N: usize>(x: T, c: [f32; N]) -> T {
    const { assert!(N >= 1 && N <= 16) };
    let mut t = [T::zero(); N];
    for i in 0..N {
        t[i] = T::splat(c[i]);
    }
    let (mut n, mut p) = (N, x);
    for _ in 0..4 {
        if n == 1 {
            break;
        }
        for i in 0..n / 2 {
            t[i] = t[2 * i] + t[2 * i + 1] * p;
        }
        if n % 2 == 1 {
            t[n / 2] = t[n - 1];
        }
        n = n.div_ceil(2);
        p = p * p;
    }
    t[0]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in ulps between `a` and the f64 value `exact` rounded to f32.
    fn ulps(a: f32, exact: f64) -> u32 {
        let e = exact as f32;
        if a == e {
            return 0;
        }
        (a.to_bits() as i64 - e.to_bits() as i64).unsigned_abs() as u32
    }

    /// exp and ln against f64's over their whole ranges (a million points each, spread
    /// over the exponents), within 2 ulp, and at their special values. (A coefficient off
    /// by 10⁻⁶, or one part of ln 2 off, fails it.)
    #[test]
    fn exp_and_ln_are_within_two_ulp() {
        let mut worst = (0, 0);
        for i in 0..1_000_000u32 {
            let x = -86.6 + 175.3 * (i as f32 / 1e6);
            worst.0 = worst.0.max(ulps(exp(x), (x as f64).exp()));
            // Positive floats from 1e-44 (subnormal) up, by their bits.
            let y = f32::from_bits(8 + i * 2_139);
            worst.1 = worst.1.max(ulps(ln(y), (y as f64).ln()));
        }
        assert!(
            worst.0 <= 2 && worst.1 <= 2,
            "worst ulps: exp {}, ln {}",
            worst.0,
            worst.1
        );
        assert_eq!(exp(0.0f32), 1.0);
        assert_eq!(exp(-100.0f32), 0.0);
        assert_eq!(exp(89.0f32), f32::INFINITY);
        assert!(ulps(exp(88.7f32), (88.7f32 as f64).exp()) <= 2);
        assert!(exp(f32::NAN).is_nan());
        assert_eq!(ln(1.0f32), 0.0);
        assert_eq!(ln(0.0f32), f32::NEG_INFINITY);
        assert_eq!(ln(f32::INFINITY), f32::INFINITY);
        assert!(ln(-1.0f32).is_nan() && ln(f32::NAN).is_nan());
        assert_eq!(ln(std::f32::consts::E), 1.0);
    }
}
