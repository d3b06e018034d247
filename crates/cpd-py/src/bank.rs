//! `DetectorBank`: one detector per sensor channel, stepped once per time step.

use cpd_core::{Bank, CusumBank, CusumConfig, ShewhartBank};
use numpy::PyUntypedArrayMethods;
use pyo3::prelude::*;

use crate::alarm::{float_repr, PyAlarm};
use crate::arrays;
use crate::detectors::{shewhart_config, size};
use crate::errors::{config_err, core_err, input_err};
use crate::state::pymethods_with_snapshots;

/// A bank of identical detectors, one per channel (sensor), advanced together.
///
/// `kind` is `"cusum"` (parameters `threshold`, `drift`) or `"shewhart"` (parameters
/// `window`, `threshold`, `sigma`). `step(readings)` feeds one reading per channel and returns
/// the alarms raised, in channel order, each with its `channel`; `run(matrix)` feeds a whole
/// `(T, channels)` trace. Bad readings raise `InputError` before any channel is advanced.
#[pyclass(name = "DetectorBank", module = "burstloc._core")]
pub struct PyDetectorBank {
    inner: Bank,
}

fn unused(kind: &str, name: &str, given: bool) -> PyResult<()> {
    if given {
        Err(config_err(format!(
            "{name} does not apply to a {kind:?} bank"
        )))
    } else {
        Ok(())
    }
}

impl PyDetectorBank {
    fn alarms(out: Vec<cpd_core::ChannelAlarm>) -> Vec<PyAlarm> {
        out.into_iter().map(PyAlarm::from).collect()
    }
}

pymethods_with_snapshots!(PyDetectorBank, {
    #[new]
    #[pyo3(signature = (kind, channels, *, threshold, drift = None, window = None, sigma = None))]
    fn new(
        kind: &str,
        channels: &Bound<'_, PyAny>,
        threshold: f64,
        drift: Option<f64>,
        window: Option<&Bound<'_, PyAny>>,
        sigma: Option<f64>,
    ) -> PyResult<Self> {
        let channels = size(channels, "channels", ">= 1")?;
        let inner = match kind {
            "cusum" => {
                unused(kind, "window", window.is_some())?;
                unused(kind, "sigma", sigma.is_some())?;
                let config = CusumConfig::new(threshold, drift.unwrap_or(0.0)).map_err(core_err)?;
                Bank::Cusum(CusumBank::new(channels, config).map_err(core_err)?)
            }
            "shewhart" => {
                unused(kind, "drift", drift.is_some())?;
                let window = window.ok_or_else(|| {
                    config_err("a \"shewhart\" bank needs window=<samples>".to_owned())
                })?;
                let config = shewhart_config(window, threshold, sigma)?;
                Bank::Shewhart(ShewhartBank::new(channels, config).map_err(core_err)?)
            }
            other => {
                return Err(config_err(format!(
                    "kind must be \"cusum\" or \"shewhart\", got {other:?}"
                )))
            }
        };
        Ok(Self { inner })
    }

    /// Feeds one reading per channel (a 1-D float64 array of length `channels`).
    fn step(&mut self, readings: &Bound<'_, PyAny>) -> PyResult<Vec<PyAlarm>> {
        let view = arrays::vector(readings, "readings")?;
        let readings = arrays::samples(&view);
        let mut out = Vec::new();
        self.inner.step(&readings, &mut out).map_err(core_err)?;
        Ok(Self::alarms(out))
    }

    /// Feeds a whole trace (a 2-D float64 array, one row per time step), releasing the GIL.
    fn run(&mut self, py: Python<'_>, matrix: &Bound<'_, PyAny>) -> PyResult<Vec<PyAlarm>> {
        let view = arrays::matrix(matrix, "matrix")?;
        let columns = view.shape()[1];
        if columns != self.inner.channels() {
            return Err(input_err(format!(
                "matrix must have one column per channel: expected {}, got shape {:?}",
                self.inner.channels(),
                view.shape()
            )));
        }
        let rows = arrays::rows(&view);
        let inner = &mut self.inner;
        let mut out = Vec::new();
        py.detach(|| inner.step_many(&rows, &mut out))
            .map_err(core_err)?;
        Ok(Self::alarms(out))
    }

    /// Forgets every reading seen, keeping the configuration.
    fn reset(&mut self) {
        self.inner.reset();
    }

    /// Number of channels (sensors).
    #[getter]
    fn channels(&self) -> usize {
        self.inner.channels()
    }

    /// `"cusum"` or `"shewhart"`.
    #[getter]
    fn kind(&self) -> &'static str {
        self.inner.kind()
    }

    /// Number of time steps consumed since creation or the last `reset()`.
    #[getter]
    fn steps_seen(&self) -> u64 {
        self.inner.steps_seen()
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let config = match &self.inner {
            Bank::Cusum(b) => format!(
                "threshold={}, drift={}",
                float_repr(py, b.config().threshold())?,
                float_repr(py, b.config().drift())?
            ),
            Bank::Shewhart(b) => format!(
                "window={}, threshold={}, sigma={}",
                b.config().window(),
                float_repr(py, b.config().threshold())?,
                float_repr(py, b.config().sigma())?
            ),
        };
        Ok(format!(
            "DetectorBank('{}', channels={}, {config})",
            self.kind(),
            self.channels()
        ))
    }
});
