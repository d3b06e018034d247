//! `burstloc._core`: the PyO3 binding of [`cpd_core`].
//!
//! This crate only converts: Python arguments into Rust values, calls into `cpd-core`, and
//! turns the results (alarms, errors, snapshots) back into Python objects. The detectors'
//! logic lives in `cpd-core` alone. Users import the `burstloc` package, which re-exports the
//! names defined here.

mod alarm;
mod arrays;
mod bank;
mod batch;
mod detectors;
mod errors;
mod feed;
mod moc;
mod state;

use pyo3::prelude::*;

/// Streaming change-point detectors (CUSUM and Shewhart) implemented in Rust.
///
/// Private module of the `burstloc` package: import the names from `burstloc`.
#[pymodule(name = "_core")]
mod core_module {
    use pyo3::prelude::*;

    #[pymodule_export]
    use crate::alarm::PyAlarm;
    #[pymodule_export]
    use crate::bank::PyDetectorBank;
    #[pymodule_export]
    use crate::batch::{detect_cusum, detect_shewhart};
    #[pymodule_export]
    use crate::detectors::{PyCusum, PyShewhart};
    #[pymodule_export]
    use crate::errors::{ConfigError, InputError};
    #[pymodule_export]
    use crate::feed::feed_lines;
    #[pymodule_export]
    use crate::moc::moc_run;

    #[pymodule_init]
    fn init(m: &Bound<'_, PyModule>) -> PyResult<()> {
        m.add("__version__", env!("CARGO_PKG_VERSION"))
    }
}
