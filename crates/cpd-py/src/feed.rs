//! `feed_lines`: the lines of a readings feed file for a run of steps (`burstloc.readings.Step`),
//! made by `feed-text` with the GIL released: the GIL is held only to read the steps.

use std::collections::HashMap;

use numpy::{PyArray1, PyArrayMethods};
use pyo3::intern;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::errors::{feed_err, input_err};

/// An attribute of step `i`, or an `InputError` naming it.
fn field<'py>(
    step: &Bound<'py, PyAny>,
    name: &Bound<'py, pyo3::types::PyString>,
    i: usize,
) -> PyResult<Bound<'py, PyAny>> {
    step.getattr(name).map_err(|_| {
        input_err(format!(
            "steps[{i}] has no {name} (a burstloc.readings.Step is wanted)"
        ))
    })
}

/// Appends step `i`'s values (a float64 array read in place, else any sequence of numbers) to
/// `values`; an `InputError` unless there are `m`.
fn read_values(got: &Bound<'_, PyAny>, m: usize, i: usize, values: &mut Vec<f64>) -> PyResult<()> {
    let before = values.len();
    if let Ok(array) = got.cast::<PyArray1<f64>>() {
        let view = array
            .try_readonly()
            .map_err(|e| input_err(format!("steps[{i}].values cannot be read: {e}")))?;
        match view.as_slice() {
            Ok(slice) => values.extend_from_slice(slice),
            Err(_) => values.extend(view.as_array().iter().copied()),
        }
    } else {
        let listed: Vec<f64> = got
            .extract()
            .map_err(|_| input_err(format!("steps[{i}].values must be numbers")))?;
        values.extend(listed);
    }
    let count = values.len() - before;
    if count != m {
        return Err(input_err(format!(
            "a step with {count} values for {m} meters"
        )));
    }
    Ok(())
}

/// The lines `timestamp,meter,value` of `steps` (each with a `timestamp`, one value per meter
/// in `values` and the names of its `filled` meters), the columns named by `meters`: every
/// number as `repr` writes it, filled values and values that are not finite left out.
///
/// Raises `InputError` for a step without one value per meter, or without a finite timestamp.
#[pyfunction]
pub fn feed_lines<'py>(
    py: Python<'py>,
    steps: &Bound<'py, PyAny>,
    meters: Vec<String>,
) -> PyResult<Bound<'py, PyBytes>> {
    let m = meters.len();
    let column: HashMap<&str, usize> = meters
        .iter()
        .enumerate()
        .map(|(j, s)| (s.as_str(), j))
        .collect();
    let (timestamp, values_name, filled_name) = (
        intern!(py, "timestamp"),
        intern!(py, "values"),
        intern!(py, "filled"),
    );
    let mut stamps = Vec::new();
    let mut values = Vec::new();
    let mut left_out = Vec::new();
    for (i, step) in steps.try_iter()?.enumerate() {
        let step = step?;
        let t: f64 = field(&step, timestamp, i)?
            .extract()
            .map_err(|_| input_err(format!("steps[{i}].timestamp must be a number")))?;
        stamps.push(t);
        read_values(&field(&step, values_name, i)?, m, i, &mut values)?;
        for name in field(&step, filled_name, i)?.try_iter()? {
            let name = name?;
            if let Some(&j) = name.extract::<&str>().ok().and_then(|s| column.get(s)) {
                left_out.push(i * m + j);
            }
        }
    }
    let text = py
        .detach(|| {
            let mut filled = Vec::new();
            if !left_out.is_empty() {
                filled = vec![false; values.len()];
                left_out.iter().for_each(|&k| filled[k] = true);
            }
            let mut out = Vec::new();
            feed_text::write_lines(&mut out, &meters, &stamps, &values, &filled).map(|_| out)
        })
        .map_err(feed_err)?;
    Ok(PyBytes::new(py, &text))
}
