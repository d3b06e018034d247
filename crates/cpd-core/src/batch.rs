//! Batch reference algorithms, transcribed from the paper's Python sources.
//!
//! [`detect_cusum`] is TSNet 0.3.1's `tsnet.postprocessing.detect_cusum` (the paper's
//! Algorithm 1) line by line, NumPy quirks included; [`detect_shewhart`] is the paper's
//! Algorithm 2 with NumPy's summation order, so both agree bit for bit with the Python code.

use alloc::vec::Vec;

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

use crate::cusum::{CusumConfig, CusumLane, RISE};
use crate::error::{check_samples, positive, Error};
use crate::math::abs;
use crate::stats::{np_mean_std, out_of_control};

/// The changes found by [`detect_cusum`]: TSNet's `(tai, taf, amp)`.
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct CusumChanges {
    /// Index where each change started (`tai`).
    pub start: Vec<usize>,
    /// Index where each change ended (`taf`); empty when `ending` is false.
    pub end: Vec<usize>,
    /// `x[end] - x[start]` (`amp`); empty when `ending` is false.
    pub amplitude: Vec<f64>,
}

/// The out-of-control samples found by [`detect_shewhart`].
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct ShewhartChanges {
    /// Indices of the out-of-control samples, increasing.
    pub index: Vec<usize>,
    /// `|x[index] - μ|`.
    pub amplitude: Vec<f64>,
}

/// TSNet's online pass: alarm indices `ta` and start indices `tai`.
fn online_pass(x: &[f64], config: &CusumConfig) -> (Vec<usize>, Vec<usize>) {
    let mut ta = Vec::new();
    let mut tai = Vec::new();
    let mut lane = CusumLane::ZERO;
    let Some(&x0) = x.first() else {
        return (ta, tai);
    };
    lane.prime(x0);
    for (i, &xi) in x.iter().enumerate().skip(1) {
        let flags = lane.step(xi, i as u64, config.threshold(), config.drift());
        if flags != 0 {
            ta.push(i);
            tai.push(if flags & RISE != 0 {
                lane.tap
            } else {
                lane.tan
            } as usize);
        }
    }
    (ta, tai)
}

/// `np.argmax` of a boolean sequence: the first `true`, or 0 when there is none.
fn argmax_bool(it: impl Iterator<Item = bool>) -> usize {
    it.enumerate().find(|&(_, b)| b).map_or(0, |(k, _)| k)
}

/// `np.unique(v, return_index=True)`: sorted distinct values and the first index of each.
fn unique_with_index(v: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let mut order: Vec<usize> = (0..v.len()).collect();
    order.sort_by_key(|&k| v[k]); // stable, like NumPy's mergesort here
    order.dedup_by_key(|k| v[*k]);
    (order.iter().map(|&k| v[k]).collect(), order)
}

fn take(v: &[usize], idx: &[usize]) -> Vec<usize> {
    idx.iter().map(|&k| v[k]).collect()
}

/// TSNet 0.3.1's `detect_cusum(time, x, threshold, drift, show=False, ending=ending)`.
///
/// With `ending = false` the result is the raw start index of every alarm (repeats kept) and
/// empty `end`/`amplitude`. With `ending = true` (and at least one alarm): the backward pass on
/// the reversed series estimates the ends, repeated starts are removed (`np.unique`), start/end
/// counts are reconciled with TSNet's `np.argmax` selections (including the `-1` index that
/// wraps to the last alarm), intercalated changes are deleted once, and
/// `amplitude = x[end] - x[start]`.
///
/// Errors: [`Error::InvalidParameter`] for a bad threshold/drift (TSNet does not check),
/// [`Error::NonFiniteSample`] for a NaN/inf (or a value beyond ±[`crate::MAX_SAMPLE`]) in `x`.
///
/// ```
/// use cpd_core::detect_cusum;
/// let x = [10.0, 10.0, 10.0, 7.0, 7.0, 7.0, 10.0, 10.0];
/// let c = detect_cusum(&x, 1.0, 0.1, true)?;
/// assert_eq!(c.start, vec![2, 5]);
/// assert_eq!(c.end, vec![3, 6]);
/// assert_eq!(c.amplitude, vec![-3.0, 3.0]);
/// # Ok::<(), cpd_core::Error>(())
/// ```
pub fn detect_cusum(
    x: &[f64],
    threshold: f64,
    drift: f64,
    ending: bool,
) -> Result<CusumChanges, Error> {
    let config = CusumConfig::new(threshold, drift)?;
    check_samples(x, 0)?;
    let (ta, tai) = online_pass(x, &config);
    if tai.is_empty() || !ending {
        return Ok(CusumChanges {
            start: tai,
            ..CusumChanges::default()
        });
    }
    let n = x.len();
    let reversed: Vec<f64> = x.iter().rev().copied().collect();
    let (_, tai2) = online_pass(&reversed, &config);
    // taf = x.size - tai2[::-1] - 1
    let mut taf: Vec<usize> = tai2.iter().rev().map(|&t| n - t - 1).collect();
    // tai, ind = np.unique(tai, return_index=True); ta = ta[ind]
    let (mut tai, ind) = unique_with_index(&tai);
    let ta = take(&ta, &ind);
    if tai.len() != taf.len() {
        if tai.len() < taf.len() {
            // taf = taf[[np.argmax(taf >= i) for i in ta]]
            let sel: Vec<usize> = ta
                .iter()
                .map(|&i| argmax_bool(taf.iter().map(|&t| t >= i)))
                .collect();
            taf = take(&taf, &sel);
        } else {
            // ind = [np.argmax(i >= ta[::-1]) - 1 for i in taf]; -1 wraps to the last element.
            let m = ta.len();
            let sel: Vec<usize> = taf
                .iter()
                .map(|&i| {
                    let k = argmax_bool(ta.iter().rev().map(|&t| i >= t));
                    if k == 0 {
                        m - 1
                    } else {
                        k - 1
                    }
                })
                .collect();
            // (TSNet also reselects `ta` here; it is only used for plotting from now on.)
            tai = take(&tai, &sel);
        }
    }
    // Delete intercalated changes: ind = taf[:-1] - tai[1:] > 0
    let overlap: Vec<bool> = taf
        .iter()
        .zip(tai.iter().skip(1))
        .map(|(&f, &s)| f > s)
        .collect();
    if overlap.iter().any(|&b| b) {
        let drop_start = |k: usize| k > 0 && overlap[k - 1];
        let drop_end = |k: usize| k < overlap.len() && overlap[k];
        tai = (0..tai.len())
            .filter(|&k| !drop_start(k))
            .map(|k| tai[k])
            .collect();
        taf = (0..taf.len())
            .filter(|&k| !drop_end(k))
            .map(|k| taf[k])
            .collect();
    }
    let amplitude = taf.iter().zip(&tai).map(|(&f, &s)| x[f] - x[s]).collect();
    Ok(CusumChanges {
        start: tai,
        end: taf,
        amplitude,
    })
}

/// The paper's Algorithm 2 over the whole slice as one window: the indices `i` with
/// `|x_i - μ| > sigma·σ` and `|x_i - μ| > threshold` (`μ`, `σ`: `np.mean(x)`, `np.std(x)`,
/// computed in NumPy's summation order, bit for bit), with amplitudes `|x_i - μ|`.
///
/// Errors: [`Error::InvalidParameter`] for a bad `sigma`/`threshold`,
/// [`Error::NonFiniteSample`] for a NaN/inf (or a value beyond ±[`crate::MAX_SAMPLE`]) in `x`. An empty slice gives no changes.
///
/// ```
/// use cpd_core::detect_shewhart;
/// let x = [200.0, 200.0, 200.0, 200.0, 200.0, 200.0, 200.0, 196.0];
/// let c = detect_shewhart(&x, 2.0, 1.0)?;
/// assert_eq!(c.index, vec![7]);
/// assert_eq!(c.amplitude, vec![3.5]);
/// # Ok::<(), cpd_core::Error>(())
/// ```
pub fn detect_shewhart(x: &[f64], sigma: f64, threshold: f64) -> Result<ShewhartChanges, Error> {
    let sigma = positive("sigma", sigma)?;
    let threshold = positive("threshold", threshold)?;
    check_samples(x, 0)?;
    let mut out = ShewhartChanges::default();
    if x.is_empty() {
        return Ok(out);
    }
    let (mean, std) = np_mean_std(x.len(), |i| x[i]);
    for (i, &xi) in x.iter().enumerate() {
        if out_of_control(xi, mean, std, sigma, threshold) {
            out.index.push(i);
            out.amplitude.push(abs(xi - mean));
        }
    }
    Ok(out)
}
