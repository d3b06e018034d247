//! The CUSUM's validated parameters.

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

use crate::error::{non_negative, positive, Error};

/// Validated CUSUM parameters.
///
/// `threshold` must be finite and `> 0`; `drift` finite and `>= 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "CusumConfigRepr"))]
pub struct CusumConfig {
    threshold: f64,
    drift: f64,
}

impl CusumConfig {
    /// Builds a config, naming the offending parameter on error.
    ///
    /// ```
    /// use cpd_core::CusumConfig;
    /// assert!(CusumConfig::new(0.5, 0.0).is_ok());
    /// let err = CusumConfig::new(-1.0, 0.0).unwrap_err();
    /// assert!(err.is_config());
    /// assert!(err.to_string().contains("threshold"));
    /// ```
    pub fn new(threshold: f64, drift: f64) -> Result<Self, Error> {
        Ok(Self {
            threshold: positive("threshold", threshold)?,
            drift: non_negative("drift", drift)?,
        })
    }

    /// Alarm threshold on the drift-free sums `gp_real` / `gn_real`.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// Drift subtracted from every difference in `gp` / `gn`.
    pub fn drift(&self) -> f64 {
        self.drift
    }
}

/// Unvalidated mirror used to validate deserialized configs.
#[cfg(feature = "serde")]
#[derive(Deserialize)]
struct CusumConfigRepr {
    threshold: f64,
    drift: f64,
}

#[cfg(feature = "serde")]
impl TryFrom<CusumConfigRepr> for CusumConfig {
    type Error = Error;
    fn try_from(r: CusumConfigRepr) -> Result<Self, Error> {
        CusumConfig::new(r.threshold, r.drift)
    }
}
