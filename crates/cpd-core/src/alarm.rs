//! What detectors report.

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

/// The sign of a detected change.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub enum Direction {
    /// The signal went up (CUSUM: `gp_real` crossed the threshold; Shewhart: `x > μ`).
    Rise,
    /// The signal went down (CUSUM: `gn_real` crossed the threshold; Shewhart: `x < μ`).
    Drop,
}

/// One detection by a streaming detector.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct Alarm {
    /// Index (0-based, in the detector's stream) of the sample that raised the alarm.
    pub index: u64,
    /// Index where the change started: CUSUM's `tap`/`tan`; for Shewhart, equal to `index`.
    pub start: u64,
    /// Sign of the change.
    pub direction: Direction,
    /// Signed amplitude: CUSUM `x[index] - x[start]`; Shewhart `x - μ` of the window.
    pub amplitude: f64,
}

impl Alarm {
    /// A change detected at the sample it starts at (Shewhart's alarms): `start == index`.
    pub(crate) fn at(index: u64, (direction, amplitude): (Direction, f64)) -> Self {
        Self {
            index,
            start: index,
            direction,
            amplitude,
        }
    }
}

/// An alarm raised by one channel of a bank.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct ChannelAlarm {
    /// The channel (column of the readings) that alarmed.
    pub channel: usize,
    /// The alarm, with `index` counted in bank steps.
    pub alarm: Alarm,
}
