//! Window statistics shared by the batch Shewhart reference, the streaming detector's exact
//! path and its periodic rebuild.

use crate::math::{abs, sqrt};

/// NumPy's block size for `np.add.reduce` (its ufunc buffer size).
const NP_BUFSIZE: usize = 8192;
/// NumPy's pairwise-summation block (`PW_BLOCKSIZE`).
const NP_PW_BLOCK: usize = 128;

/// NumPy 1.26's pairwise summation of `get(lo..lo + n)` (`pairwise_sum_DOUBLE`).
fn np_pairwise(lo: usize, n: usize, get: &impl Fn(usize) -> f64) -> f64 {
    if n < 8 {
        let mut res = 0.0;
        for i in lo..lo + n {
            res += get(i);
        }
        res
    } else if n <= NP_PW_BLOCK {
        let mut r = [0.0f64; 8];
        for (j, rj) in r.iter_mut().enumerate() {
            *rj = get(lo + j);
        }
        let whole = n - n % 8;
        let mut i = 8;
        while i < whole {
            for (j, rj) in r.iter_mut().enumerate() {
                *rj += get(lo + i + j);
            }
            i += 8;
        }
        let mut res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        while i < n {
            res += get(lo + i);
            i += 1;
        }
        res
    } else {
        let mut n2 = n / 2;
        n2 -= n2 % 8;
        np_pairwise(lo, n2, get) + np_pairwise(lo + n2, n - n2, get)
    }
}

/// `np.sum` of a contiguous float64 array whose element `i` is `get(i)`, `i < n`,
/// bit for bit (NumPy sums buffer-sized chunks pairwise and adds the chunks in order).
pub(crate) fn np_sum(n: usize, get: impl Fn(usize) -> f64) -> f64 {
    let mut total = 0.0;
    let mut lo = 0;
    while lo < n {
        let len = NP_BUFSIZE.min(n - lo);
        total += np_pairwise(lo, len, &get);
        lo += len;
    }
    total
}

/// `(np.mean(x), np.std(x))` (population std) of the `n >= 1` values `get(0..n)`, bit for bit.
pub(crate) fn np_mean_std(n: usize, get: impl Fn(usize) -> f64) -> (f64, f64) {
    let count = n as f64;
    let mean = np_sum(n, &get) / count;
    let var = np_sum(n, |i| {
        let d = get(i) - mean;
        d * d
    }) / count;
    (mean, sqrt(var))
}

/// The paper's modified Shewhart test (Algorithm 2): `|x - μ| > s·σ` and `|x - μ| > threshold`,
/// written exactly as the Python reference evaluates it.
#[inline]
pub(crate) fn out_of_control(x: f64, mean: f64, std: f64, sigma: f64, threshold: f64) -> bool {
    let a = abs(x - mean);
    a > sigma * std && a > threshold
}

/// Sum of `get(0..n)` in 8 interleaved lanes combined in a fixed order: fast (vectorizes),
/// accurate enough for the streaming detector's periodic rebuild, and identical whether the
/// values are contiguous (one detector) or strided (one channel of a bank).
#[inline]
pub(crate) fn lane_sum(n: usize, get: impl Fn(usize) -> f64) -> f64 {
    let mut acc = [0.0f64; 8];
    let whole = n - n % 8;
    let mut i = 0;
    while i < whole {
        for (j, a) in acc.iter_mut().enumerate() {
            *a += get(i + j);
        }
        i += 8;
    }
    for (j, k) in (whole..n).enumerate() {
        acc[j] += get(k);
    }
    ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairwise_matches_plain_sum_on_integers() {
        // Integers are summed exactly in any order: checks coverage of every index.
        for n in [
            0usize, 1, 7, 8, 9, 127, 128, 129, 1000, 8191, 8192, 8193, 20000,
        ] {
            let want = (n * n.saturating_sub(1) / 2) as f64;
            assert_eq!(np_sum(n, |i| i as f64), want, "n={n}");
            assert_eq!(lane_sum(n, |i| i as f64), want, "n={n}");
        }
    }

    #[test]
    fn mean_std_of_known_values() {
        let x = [2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0];
        let (m, s) = np_mean_std(x.len(), |i| x[i]);
        assert_eq!((m, s), (5.0, 2.0));
    }

    #[test]
    fn out_of_control_needs_both_conditions() {
        assert!(out_of_control(10.0, 0.0, 1.0, 3.0, 5.0));
        assert!(!out_of_control(4.0, 0.0, 1.0, 3.0, 5.0)); // above 3σ, below threshold
        assert!(!out_of_control(10.0, 0.0, 4.0, 3.0, 5.0)); // above threshold, below 3σ
        assert!(!out_of_control(-2.0, 0.0, 1.0, 2.0, 1.0)); // ties are in control
    }
}
