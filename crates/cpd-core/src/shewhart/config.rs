//! The validated Shewhart configuration and the hot-path constants derived from it.

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

use super::sums::{Derived, MARGIN};
use crate::error::{positive, Error};

/// Validated Shewhart parameters.
///
/// `window >= 2`; `sigma` (the paper's `s`, width of the control limits in standard deviations)
/// and `threshold` (minimum `|x - μ|`) finite and `> 0`. The paper uses one value for both.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "ShewhartConfigRepr"))]
pub struct ShewhartConfig {
    pub(super) window: usize,
    pub(super) sigma: f64,
    pub(super) threshold: f64,
    #[cfg_attr(feature = "serde", serde(skip_serializing))]
    pub(super) derived: Derived,
}

impl ShewhartConfig {
    /// Builds a config, naming the offending parameter on error.
    ///
    /// ```
    /// use cpd_core::ShewhartConfig;
    /// assert!(ShewhartConfig::new(50, 0.3, 0.3).is_ok());
    /// let err = ShewhartConfig::new(1, 0.3, 0.3).unwrap_err();
    /// assert!(err.to_string().contains("window"));
    /// ```
    pub fn new(window: usize, sigma: f64, threshold: f64) -> Result<Self, Error> {
        if window < 2 {
            return Err(Error::InvalidParameter {
                name: "window",
                value: window as f64,
                reason: "must be >= 2",
            });
        }
        let sigma = positive("sigma", sigma)?;
        let threshold = positive("threshold", threshold)?;
        let sigma2 = sigma * sigma;
        Ok(Self {
            window,
            sigma,
            threshold,
            derived: Derived {
                inv_w: 1.0 / window as f64,
                sigma2_hi: sigma2 * (1.0 + MARGIN),
                sigma2_lo: sigma2 * (1.0 - MARGIN),
            },
        })
    }

    /// The paper's single-parameter chart (section III): `sigma` defaults to `threshold`.
    ///
    /// Errors name `window` or `threshold`, the two parameters given.
    ///
    /// ```
    /// use cpd_core::ShewhartConfig;
    /// let config = ShewhartConfig::with_threshold(50, 0.3)?;
    /// assert_eq!(config, ShewhartConfig::new(50, 0.3, 0.3)?);
    /// let err = ShewhartConfig::with_threshold(50, -1.0).unwrap_err();
    /// assert!(err.to_string().contains("`threshold`"));
    /// # Ok::<(), cpd_core::Error>(())
    /// ```
    pub fn with_threshold(window: usize, threshold: f64) -> Result<Self, Error> {
        Self::new(window, threshold, threshold).map_err(|err| match err {
            Error::InvalidParameter {
                name: "sigma",
                value,
                reason,
            } => Error::InvalidParameter {
                name: "threshold",
                value,
                reason,
            },
            other => other,
        })
    }

    /// Window length `W` (the current sample included).
    pub fn window(&self) -> usize {
        self.window
    }

    /// Width of the control limits in standard deviations (the paper's `s`).
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// Minimum `|x - μ|` for an alarm.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    pub(crate) fn derived(&self) -> &Derived {
        &self.derived
    }
}

/// Unvalidated mirror used to validate deserialized configs.
#[cfg(feature = "serde")]
#[derive(Deserialize)]
struct ShewhartConfigRepr {
    window: usize,
    sigma: f64,
    threshold: f64,
}

#[cfg(feature = "serde")]
impl TryFrom<ShewhartConfigRepr> for ShewhartConfig {
    type Error = Error;
    fn try_from(r: ShewhartConfigRepr) -> Result<Self, Error> {
        ShewhartConfig::new(r.window, r.sigma, r.threshold)
    }
}
