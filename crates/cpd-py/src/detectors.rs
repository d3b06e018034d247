//! `Cusum` and `Shewhart`: single-channel streaming detectors wrapping the core's.

use cpd_core::{Cusum, CusumConfig, Shewhart, ShewhartConfig};
use pyo3::exceptions::PyOverflowError;
use pyo3::prelude::*;

use crate::alarm::{float_repr, PyAlarm};
use crate::arrays;
use crate::errors::{config_err, core_err};
use crate::state::pymethods_with_snapshots;

/// The `#[pymethods]` block of a single-channel detector class: `update`, `update_many`,
/// `reset`, `samples_seen`, the snapshot methods, and `$extra`, the class's own methods.
macro_rules! detector_methods {
    ($py_type:ident, { $($extra:tt)* }) => {
        pymethods_with_snapshots!($py_type, {
            /// Feeds one sample; returns the alarm it raises, if any.
            ///
            /// A NaN, infinite or out-of-range (beyond +-1e100) sample raises `InputError` and
            /// leaves the state unchanged.
            fn update(&mut self, x: f64) -> PyResult<Option<PyAlarm>> {
                match self.inner.update(x) {
                    Ok(None) => Ok(None),
                    Ok(Some(alarm)) => Ok(Some(alarm.into())),
                    Err(err) => Err(core_err(err)),
                }
            }

            /// Feeds every sample of a 1-D float64 array, releasing the GIL; returns the alarms.
            ///
            /// A NaN, infinite or out-of-range sample anywhere raises `InputError` naming its
            /// index, and no sample is consumed: the detector is as before the call. Another
            /// dtype or shape raises `InputError` too. While the samples are processed other
            /// Python threads run; a call on this same detector from one of them meanwhile
            /// raises `RuntimeError`.
            fn update_many(&mut self, py: Python<'_>, x: &Bound<'_, PyAny>) -> PyResult<Vec<PyAlarm>> {
                let view = arrays::vector(x, "x")?;
                let samples = arrays::samples(&view);
                let inner = &mut self.inner;
                let mut alarms = Vec::new();
                py.detach(|| inner.update_slice(&samples, &mut alarms))
                    .map_err(core_err)?;
                Ok(alarms.into_iter().map(PyAlarm::from).collect())
            }

            /// Forgets every sample seen, keeping the configuration.
            fn reset(&mut self) {
                self.inner.reset();
            }

            /// Number of samples consumed since creation or the last `reset()`.
            #[getter]
            fn samples_seen(&self) -> u64 {
                self.inner.samples_seen()
            }

            $($extra)*
        });
    };
}

/// Two-sided CUSUM change detector (TSNet's `detect_cusum`, online form), one sample at a time.
///
/// `Cusum(threshold, drift=0.0)`: `threshold > 0` is the change (in the signal's units) that
/// raises an alarm, `drift >= 0` is subtracted from every step so that slow movements and noise
/// do not accumulate. Sample 0 only primes the previous value; from then on the drift-corrected
/// sums of the positive and negative differences (`gp`, `gn`) grow, and an alarm is raised
/// when one of their real twins (`gp_real`, `gn_real`) exceeds `threshold`; the sums then
/// reset. Alarms report where the change started (`start`) and its size (`amplitude`).
#[pyclass(name = "Cusum", module = "burstloc._core")]
pub struct PyCusum {
    inner: Cusum,
}

detector_methods!(PyCusum, {
    #[new]
    #[pyo3(signature = (threshold, drift = 0.0))]
    fn new(threshold: f64, drift: f64) -> PyResult<Self> {
        let config = CusumConfig::new(threshold, drift).map_err(core_err)?;
        Ok(Self {
            inner: Cusum::new(config),
        })
    }

    /// Alarm threshold on the real cumulative sums.
    #[getter]
    fn threshold(&self) -> f64 {
        self.inner.config().threshold()
    }

    /// Drift subtracted from each difference in the drift-corrected sums.
    #[getter]
    fn drift(&self) -> f64 {
        self.inner.config().drift()
    }

    /// Drift-corrected cumulative sum of positive changes.
    #[getter]
    fn gp(&self) -> f64 {
        self.inner.gp()
    }

    /// Drift-corrected cumulative sum of negative changes.
    #[getter]
    fn gn(&self) -> f64 {
        self.inner.gn()
    }

    /// Real (uncorrected) cumulative sum of positive changes, compared with `threshold`.
    #[getter]
    fn gp_real(&self) -> f64 {
        self.inner.gp_real()
    }

    /// Real (uncorrected) cumulative sum of negative changes, compared with `threshold`.
    #[getter]
    fn gn_real(&self) -> f64 {
        self.inner.gn_real()
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!(
            "Cusum(threshold={}, drift={})",
            float_repr(py, self.threshold())?,
            float_repr(py, self.drift())?,
        ))
    }
});

/// Shewhart control chart over a sliding window (the paper's Algorithm 2, streaming).
///
/// `Shewhart(window, threshold, sigma=None)`: the window holds the last `window >= 2` samples
/// including the current one. Once it is full, a sample raises an alarm when its distance to
/// the window mean exceeds both `sigma` times the window's (population) standard deviation and
/// `threshold` (both `> 0`; `sigma` defaults to `threshold`, the paper's single parameter).
/// The alarm's `amplitude` is the signed distance `x - mean`, its `start` its own index.
#[pyclass(name = "Shewhart", module = "burstloc._core")]
pub struct PyShewhart {
    inner: Shewhart,
}

/// A size argument (`window`, `channels`): a Python int of any magnitude. Negative values are a
/// `ConfigError` naming `rule`; values past `i64` a `ConfigError` too (no machine holds them);
/// other types keep PyO3's `TypeError`.
pub(crate) fn size(obj: &Bound<'_, PyAny>, name: &str, rule: &str) -> PyResult<usize> {
    match obj.extract::<i64>() {
        Ok(v) => usize::try_from(v)
            .map_err(|_| config_err(format!("{name} must be an integer {rule}, got {v}"))),
        Err(err) if err.is_instance_of::<PyOverflowError>(obj.py()) => Err(config_err(format!(
            "invalid parameter `{name}` = {obj}: needs more memory than can be allocated"
        ))),
        Err(err) => Err(err),
    }
}

/// A Shewhart config from Python arguments: `window` as a Python int, `sigma` left to the
/// core's default (the threshold) when not given.
pub(crate) fn shewhart_config(
    window: &Bound<'_, PyAny>,
    threshold: f64,
    sigma: Option<f64>,
) -> PyResult<ShewhartConfig> {
    let window = size(window, "window", ">= 2")?;
    match sigma {
        Some(sigma) => ShewhartConfig::new(window, sigma, threshold),
        None => ShewhartConfig::with_threshold(window, threshold),
    }
    .map_err(core_err)
}

detector_methods!(PyShewhart, {
    #[new]
    #[pyo3(signature = (window, threshold, sigma = None))]
    fn new(window: &Bound<'_, PyAny>, threshold: f64, sigma: Option<f64>) -> PyResult<Self> {
        Ok(Self {
            inner: Shewhart::new(shewhart_config(window, threshold, sigma)?).map_err(core_err)?,
        })
    }

    /// Number of samples in the sliding window (the current one included).
    #[getter]
    fn window(&self) -> usize {
        self.inner.config().window()
    }

    /// Width of the control limits, in window standard deviations.
    #[getter]
    fn sigma(&self) -> f64 {
        self.inner.config().sigma()
    }

    /// Minimum distance to the window mean for an alarm.
    #[getter]
    fn threshold(&self) -> f64 {
        self.inner.config().threshold()
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!(
            "Shewhart(window={}, threshold={}, sigma={})",
            self.window(),
            float_repr(py, self.threshold())?,
            float_repr(py, self.sigma())?,
        ))
    }
});
