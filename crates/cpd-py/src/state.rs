//! Snapshots: a detector's configuration and state as bytes (the core's versioned,
//! checksummed snapshot format, `cpd_core::snapshot`), used by `snapshot()`/`restore()`, pickle
//! and copy.

use cpd_core::snapshot::{self, Snapshot};
use pyo3::PyResult;

use crate::errors::core_err;

/// The snapshot bytes of a core value (`cpd_core::snapshot`: format 2, CRC-32C at the end).
pub(crate) fn encode<T: Snapshot>(state: &T) -> Vec<u8> {
    snapshot::to_bytes(state)
}

/// A core value from snapshot bytes (format 2, or format 1 written before the checksum);
/// `InputError` when they cannot be restored: altered, truncated, extended, of an unknown
/// version, of another kind or holding an invalid state.
pub(crate) fn decode<T: Snapshot>(bytes: &[u8]) -> PyResult<T> {
    snapshot::from_bytes(bytes).map_err(core_err)
}

/// A class's `#[pymethods]` block with the snapshot methods every detector class shares:
/// `snapshot()`, `restore()`, pickle (`__reduce__` to `restore`) and copy. `$extra` holds the
/// class's own methods (PyO3 takes one `#[pymethods]` block per class). The class must wrap
/// its core value in a field `inner` that is `Clone + cpd_core::snapshot::Snapshot`.
macro_rules! pymethods_with_snapshots {
    ($py_type:ident, { $($extra:tt)* }) => {
        #[pymethods]
        impl $py_type {
            /// The configuration and full state as bytes, for `restore()` (format 2: a
            /// header with the version and length, a CBOR payload, a CRC-32C at the end).
            fn snapshot<'py>(&self, py: Python<'py>) -> Bound<'py, pyo3::types::PyBytes> {
                pyo3::types::PyBytes::new(py, &$crate::state::encode(&self.inner))
            }

            /// An object in exactly the state captured by `snapshot()`.
            ///
            /// Altered, truncated or extended bytes (a checksum or length mismatch), an unknown
            /// format version, another kind or an invalid state raise `InputError` naming the
            /// problem; the core checks the checksum before it decodes, then re-validates the
            /// configuration and every state field. Format-1 snapshots (no checksum, written
            /// before) are still restored.
            #[classmethod]
            fn restore(_cls: &Bound<'_, pyo3::types::PyType>, state: &[u8]) -> PyResult<Self> {
                Ok(Self { inner: $crate::state::decode(state)? })
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
