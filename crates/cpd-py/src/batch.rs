//! The batch references: `detect_cusum` (TSNet's function) and `detect_shewhart` (Algorithm 2).

use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;

use crate::arrays;
use crate::errors::{core_err, input_err};

/// An int64 NumPy array (TSNet's index arrays).
type Indices<'py> = Bound<'py, PyArray1<i64>>;
/// A float64 NumPy array.
type Values<'py> = Bound<'py, PyArray1<f64>>;

/// Indices as NumPy's default integer type (what TSNet returns).
fn indices(py: Python<'_>, values: Vec<usize>) -> Indices<'_> {
    values
        .into_iter()
        .map(|v| i64::try_from(v).expect("an index into a NumPy array fits in i64"))
        .collect::<Vec<i64>>()
        .into_pyarray(py)
}

/// TSNet's `detect_cusum(time, x, threshold, drift, show=False, ending=ending)`, in Rust.
///
/// Returns `(start, end, amplitude)`: the indices where changes start and end and their
/// amplitudes `x[end] - x[start]`, with TSNet 0.3.1's post-processing (duplicate starts
/// merged, overlapping changes dropped). With `ending=False`, `start` holds the raw start of
/// every alarm and `end` and `amplitude` are empty. `time` is only checked to have the length
/// of `x` (TSNet uses it for plotting).
#[pyfunction]
#[pyo3(signature = (time, x, threshold, drift, ending = true))]
pub fn detect_cusum<'py>(
    py: Python<'py>,
    time: &Bound<'py, PyAny>,
    x: &Bound<'py, PyAny>,
    threshold: f64,
    drift: f64,
    ending: bool,
) -> PyResult<(Indices<'py>, Indices<'py>, Values<'py>)> {
    let view = arrays::vector(x, "x")?;
    let samples = arrays::samples(&view);
    let time_len = time
        .len()
        .map_err(|_| input_err("time must be a sequence as long as x".to_owned()))?;
    if time_len != samples.len() {
        return Err(input_err(format!(
            "time and x must have the same length, got {time_len} and {}",
            samples.len()
        )));
    }
    let changes = py
        .detach(|| cpd_core::detect_cusum(&samples, threshold, drift, ending))
        .map_err(core_err)?;
    Ok((
        indices(py, changes.start),
        indices(py, changes.end),
        changes.amplitude.into_pyarray(py),
    ))
}

/// Algorithm 2 of the paper over the whole of `x`.
///
/// Returns `(index, amplitude)`: the samples whose distance `|x - mean(x)|` exceeds both
/// `sigma * std(x)` (population standard deviation) and `threshold`, and those distances.
#[pyfunction]
pub fn detect_shewhart<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    sigma: f64,
    threshold: f64,
) -> PyResult<(Indices<'py>, Values<'py>)> {
    let view = arrays::vector(x, "x")?;
    let samples = arrays::samples(&view);
    let changes = py
        .detach(|| cpd_core::detect_shewhart(&samples, sigma, threshold))
        .map_err(core_err)?;
    Ok((
        indices(py, changes.index),
        changes.amplitude.into_pyarray(py),
    ))
}
