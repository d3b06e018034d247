//! The two Python exception types and the mapping from [`cpd_core::Error`] onto them.

use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::PyErr;

create_exception!(
    burstloc._core,
    ConfigError,
    PyValueError,
    "A detector was configured with an invalid parameter; the message names it and its value."
);
create_exception!(
    burstloc._core,
    InputError,
    PyValueError,
    "A detector was fed invalid input (a NaN, infinite or out-of-range sample, beyond \
     +-1e100; a wrong dtype, shape or channel count; a snapshot that is altered, truncated or \
     of an unknown format version, or holds an invalid state; steps of readings that do not fit \
     their meters); the message names the sample, channel, argument, snapshot problem, state \
     field or step. The detector's state is unchanged."
);

/// Converts a core error: bad configuration becomes `ConfigError`, everything else `InputError`.
pub(crate) fn core_err(err: cpd_core::Error) -> PyErr {
    if err.is_config() {
        ConfigError::new_err(err.to_string())
    } else {
        InputError::new_err(err.to_string())
    }
}

/// A `ConfigError` with the given message (for parameters checked before reaching the core).
pub(crate) fn config_err(message: String) -> PyErr {
    ConfigError::new_err(message)
}

/// Converts a feed file's error (steps that do not fit their meters) into an `InputError`.
pub(crate) fn feed_err(err: feed_text::Error) -> PyErr {
    InputError::new_err(err.to_string())
}

/// An `InputError` with the given message.
pub(crate) fn input_err(message: String) -> PyErr {
    InputError::new_err(message)
}
