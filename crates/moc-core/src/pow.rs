//! `pow(x, 2.0)` of the C library, fast.

use core::hint::black_box;

/// `x` squared as the C library's `pow(x, 2.0)` computes it (what TSNet's `x**2` calls), to
/// the last bit, without calling it for most `x`.
///
/// `pow` is not correctly rounded: its result lies within 0.52 units in the last place (ULP)
/// of the exact square (glibc's and musl's bound), so it can differ from the correctly
/// rounded `x * x` only when the exact square lies near the midpoint between two doubles.
/// The rounding error of `x * x` is computed exactly (Dekker's product); when it is below
/// 0.45 ULP, `x * x` is the only double within 0.55 ULP of the exact square and therefore
/// `pow`'s result too. Otherwise (non-finite, very large or small values and powers of two,
/// where the argument does not hold, and about one value in ten) `pow` itself is called. The
/// exponent goes through [`black_box`] so that the compiler does not turn the call into
/// `x * x`. Zero (a junction without demand) is `pow`'s `+0`.
#[inline]
pub fn pow2(x: f64) -> f64 {
    if x == 0.0 {
        return 0.0;
    }
    let r = x * x;
    let ax = x.abs();
    let bits = r.to_bits();
    // Dekker's split is exact for |x| well inside the range; r must be normal and not a
    // power of two (whose lower neighbour is half an ULP away).
    if (1e-100..1e100).contains(&ax) && bits & 0x000f_ffff_ffff_ffff != 0 {
        let err = square_error(x, r);
        let ulp = f64::from_bits(bits & 0x7ff0_0000_0000_0000) * f64::EPSILON;
        if err.abs() < 0.45 * ulp {
            return r;
        }
    }
    x.powf(black_box(2.0))
}

/// `x * x - r` exactly, `r` being `x * x` rounded: one fused multiply-add where the CPU has
/// it (a build for the native CPU), else Dekker's product.
#[inline(always)]
fn square_error(x: f64, r: f64) -> f64 {
    #[cfg(target_feature = "fma")]
    {
        x.mul_add(x, -r)
    }
    #[cfg(not(target_feature = "fma"))]
    {
        const SPLIT: f64 = 134_217_729.0; // 2^27 + 1
        let c = SPLIT * x;
        let hi = c - (c - x);
        let lo = x - hi;
        ((hi * hi - r) + 2.0 * hi * lo) + lo * lo
    }
}

#[cfg(test)]
mod tests {
    use super::pow2;
    use core::hint::black_box;

    #[test]
    fn matches_the_c_library_on_many_values() {
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut differ = 0;
        for i in 0..2_000_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let unit = (state >> 11) as f64 / (1u64 << 53) as f64;
            let x = (unit - 0.5) * 10f64.powi((i % 12) - 4);
            let want = x.powf(black_box(2.0));
            assert_eq!(pow2(x).to_bits(), want.to_bits(), "x = {x:e}");
            differ += usize::from(want.to_bits() != (x * x).to_bits());
        }
        // the reason for pow2: pow and x * x do differ now and then
        assert!(differ > 0);
    }

    #[test]
    fn special_values() {
        for x in [
            0.0,
            -0.0,
            1.0,
            -2.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            1e200,
            1e-200,
        ] {
            assert_eq!(
                pow2(x).to_bits(),
                x.powf(black_box(2.0)).to_bits(),
                "x = {x:e}"
            );
        }
        assert!(pow2(f64::NAN).is_nan());
    }
}
