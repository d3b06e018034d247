//! `Alarm`: the immutable Python view of a [`cpd_core::Alarm`].

use std::hash::{DefaultHasher, Hash, Hasher};

use cpd_core::{ChannelAlarm, Direction};
use pyo3::prelude::*;
use pyo3::types::{PyFloat, PyType};

use crate::errors::input_err;

/// A detected change: where it was raised, where the change started, its direction and size.
///
/// `index` is the sample at which the alarm fired and `start` the sample where the change
/// began (both counted from the detector's first sample, or its last `reset()`);
/// `direction` is `"rise"` or `"drop"`; `amplitude` is signed (CUSUM: `x[index] - x[start]`;
/// Shewhart: `x - mean`); `channel` is the sensor's column for alarms from a `DetectorBank`,
/// `None` otherwise.
#[pyclass(name = "Alarm", module = "burstloc._core", frozen, eq)]
#[derive(Clone, Copy, PartialEq)]
pub struct PyAlarm {
    /// Sample index at which the alarm fired.
    #[pyo3(get)]
    index: u64,
    /// Sample index at which the change started.
    #[pyo3(get)]
    start: u64,
    direction: Direction,
    /// Signed size of the change.
    #[pyo3(get)]
    amplitude: f64,
    /// Channel (sensor column) of a bank alarm, `None` for a single detector.
    #[pyo3(get)]
    channel: Option<usize>,
}

/// Python's `repr()` of a float (so reprs round-trip and read as Python users expect).
pub(crate) fn float_repr(py: Python<'_>, value: f64) -> PyResult<String> {
    Ok(PyFloat::new(py, value).repr()?.to_string())
}

/// The constructor arguments of an alarm, for pickle.
type AlarmArgs = (u64, u64, &'static str, f64, Option<usize>);

impl PyAlarm {
    fn direction_name(&self) -> &'static str {
        match self.direction {
            Direction::Rise => "rise",
            Direction::Drop => "drop",
        }
    }
}

impl From<cpd_core::Alarm> for PyAlarm {
    fn from(alarm: cpd_core::Alarm) -> Self {
        Self {
            index: alarm.index,
            start: alarm.start,
            direction: alarm.direction,
            amplitude: alarm.amplitude,
            channel: None,
        }
    }
}

impl From<ChannelAlarm> for PyAlarm {
    fn from(alarm: ChannelAlarm) -> Self {
        Self {
            channel: Some(alarm.channel),
            ..Self::from(alarm.alarm)
        }
    }
}

#[pymethods]
impl PyAlarm {
    #[new]
    #[pyo3(signature = (index, start, direction, amplitude, channel = None))]
    fn new(
        index: u64,
        start: u64,
        direction: &str,
        amplitude: f64,
        channel: Option<usize>,
    ) -> PyResult<Self> {
        let direction = match direction {
            "rise" => Direction::Rise,
            "drop" => Direction::Drop,
            other => {
                return Err(input_err(format!(
                    "direction must be 'rise' or 'drop', got {other:?}"
                )))
            }
        };
        Ok(Self {
            index,
            start,
            direction,
            amplitude,
            channel,
        })
    }

    /// `"rise"` or `"drop"`.
    #[getter]
    fn direction(&self) -> &'static str {
        self.direction_name()
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let amplitude = float_repr(py, self.amplitude)?;
        let mut text = format!(
            "Alarm(index={}, start={}, direction='{}', amplitude={}",
            self.index,
            self.start,
            self.direction_name(),
            amplitude
        );
        if let Some(channel) = self.channel {
            text.push_str(&format!(", channel={channel}"));
        }
        text.push(')');
        Ok(text)
    }

    fn __hash__(&self) -> u64 {
        let mut hasher = DefaultHasher::new();
        self.index.hash(&mut hasher);
        self.start.hash(&mut hasher);
        self.direction_name().hash(&mut hasher);
        // +0.0 == -0.0, so they must hash alike.
        let amplitude = if self.amplitude == 0.0 {
            0.0
        } else {
            self.amplitude
        };
        amplitude.to_bits().hash(&mut hasher);
        self.channel.hash(&mut hasher);
        hasher.finish()
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> (Bound<'py, PyType>, AlarmArgs) {
        let a = slf.get();
        (
            slf.get_type(),
            (a.index, a.start, a.direction_name(), a.amplitude, a.channel),
        )
    }
}
