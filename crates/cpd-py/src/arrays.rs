//! Checked access to NumPy arguments: `float64` arrays of the expected dimension, or an
//! `InputError` naming the argument and what was wrong with it.

use std::borrow::Cow;

use numpy::ndarray::Dimension;
use numpy::{
    PyArray, PyArrayMethods, PyReadonlyArray, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use crate::errors::input_err;

/// Describes why `obj` is not a `float64` array of `ndim` dimensions, as an `InputError`.
fn mismatch(obj: &Bound<'_, PyAny>, name: &str, ndim: usize) -> PyErr {
    let wanted = format!("{name} must be a {ndim}-D numpy array of float64");
    match obj.cast::<PyUntypedArray>() {
        Ok(array) if array.ndim() != ndim => {
            input_err(format!("{wanted}, got shape {:?}", array.shape()))
        }
        Ok(array) => {
            let dtype = array
                .dtype()
                .str()
                .map_or_else(|_| "?".to_owned(), |s| s.to_string());
            input_err(format!("{wanted}, got dtype {dtype}"))
        }
        Err(_) => {
            let type_name = obj
                .get_type()
                .name()
                .map_or_else(|_| "?".to_owned(), |s| s.to_string());
            input_err(format!("{wanted}, got {type_name}"))
        }
    }
}

/// A read-only view of a `float64` array of `D`'s dimension, or an `InputError`.
fn checked<'py, D: Dimension>(
    obj: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<PyReadonlyArray<'py, f64, D>> {
    let ndim = D::NDIM.expect("a fixed number of dimensions");
    let array = obj
        .cast::<PyArray<f64, D>>()
        .map_err(|_| mismatch(obj, name, ndim))?;
    array
        .try_readonly()
        .map_err(|e| input_err(format!("{name} cannot be read: {e}")))
}

/// A read-only view of a 1-D `float64` array.
pub(crate) fn vector<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<PyReadonlyArray1<'py, f64>> {
    checked(obj, name)
}

/// A read-only view of a 2-D `float64` array.
pub(crate) fn matrix<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<PyReadonlyArray2<'py, f64>> {
    checked(obj, name)
}

/// The samples of a 1-D view, borrowed when contiguous, copied otherwise.
pub(crate) fn samples<'a>(view: &'a PyReadonlyArray1<'_, f64>) -> Cow<'a, [f64]> {
    match view.as_slice() {
        Ok(slice) => Cow::Borrowed(slice),
        Err(_) => Cow::Owned(view.as_array().iter().copied().collect()),
    }
}

/// The samples of a 2-D view in row-major order, borrowed when C-contiguous, copied otherwise.
pub(crate) fn rows<'a>(view: &'a PyReadonlyArray2<'_, f64>) -> Cow<'a, [f64]> {
    match view.as_slice() {
        Ok(slice) if view.is_c_contiguous() => Cow::Borrowed(slice),
        _ => Cow::Owned(view.as_array().iter().copied().collect()),
    }
}
