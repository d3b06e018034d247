//! Snapshots: a detector's configuration and state as bytes (CBOR of the core's serde form),
//! used by `snapshot()`/`restore()`, pickle and copy.

use pyo3::PyResult;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::errors::input_err;

/// Bumped when the snapshot layout changes incompatibly.
const FORMAT: u32 = 1;

#[derive(Serialize)]
struct Envelope<'a, T> {
    format: u32,
    kind: &'a str,
    state: &'a T,
}

#[derive(Deserialize)]
struct OwnedEnvelope {
    format: u32,
    kind: String,
    state: ciborium::Value,
}

/// Serializes `state`, tagged with the detector `kind`.
pub(crate) fn encode<T: Serialize>(kind: &str, state: &T) -> Vec<u8> {
    let mut bytes = Vec::new();
    ciborium::into_writer(
        &Envelope {
            format: FORMAT,
            kind,
            state,
        },
        &mut bytes,
    )
    .expect("detector state is plain data and always serializes");
    bytes
}

/// Deserializes a snapshot made by [`encode`] for the same `kind`; `InputError` otherwise.
pub(crate) fn decode<T: DeserializeOwned>(kind: &str, bytes: &[u8]) -> PyResult<T> {
    let envelope: OwnedEnvelope = ciborium::from_reader(bytes)
        .map_err(|e| input_err(format!("not a valid {kind} snapshot: {e}")))?;
    if envelope.format != FORMAT {
        return Err(input_err(format!(
            "{kind} snapshot has format {}, this version reads format {FORMAT}",
            envelope.format
        )));
    }
    if envelope.kind != kind {
        return Err(input_err(format!(
            "snapshot is of a {}, not of a {kind}",
            envelope.kind
        )));
    }
    envelope
        .state
        .deserialized()
        .map_err(|e| input_err(format!("not a valid {kind} snapshot: {e}")))
}

/// A class's `#[pymethods]` block with the snapshot methods every detector class shares:
/// `snapshot()`, `restore()`, pickle (`__reduce__` to `restore`) and copy. `$extra` holds the
/// class's own methods (PyO3 takes one `#[pymethods]` block per class). The class must wrap
/// its core value in a field `inner` that is `Clone + Serialize + Deserialize`.
macro_rules! pymethods_with_snapshots {
    ($py_type:ident, $kind:expr, { $($extra:tt)* }) => {
        #[pymethods]
        impl $py_type {
            /// The configuration and full state as bytes, for `restore()`.
            fn snapshot<'py>(&self, py: Python<'py>) -> Bound<'py, pyo3::types::PyBytes> {
                pyo3::types::PyBytes::new(py, &$crate::state::encode($kind, &self.inner))
            }

            /// An object in exactly the state captured by `snapshot()`.
            ///
            /// The core re-validates the configuration and the state's shape while decoding.
            #[classmethod]
            fn restore(_cls: &Bound<'_, pyo3::types::PyType>, state: &[u8]) -> PyResult<Self> {
                Ok(Self { inner: $crate::state::decode($kind, state)? })
            }

            fn __reduce__<'py>(
                slf: &Bound<'py, Self>,
            ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, pyo3::types::PyTuple>)> {
                let restore = slf.get_type().getattr("restore")?;
                let snapshot = slf.borrow().snapshot(slf.py());
                Ok((restore, pyo3::types::PyTuple::new(slf.py(), [snapshot])?))
            }

            fn __copy__(&self) -> Self {
                Self { inner: self.inner.clone() }
            }

            fn __deepcopy__(&self, _memo: &Bound<'_, PyAny>) -> Self {
                Self { inner: self.inner.clone() }
            }

            $($extra)*
        }
    };
}

pub(crate) use pymethods_with_snapshots;
