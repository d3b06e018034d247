//! Fresh seeded pressure-like traces and the detector parameters calibrated for them, shared
//! by the criterion benchmarks (`benches/detectors.rs`) and the instruction counts
//! (`examples/kernel_counts.rs`), so that both measure the same data.
//!
//! Heads of 200 m with near-Gaussian sensor noise (a sum of 4 uniforms) of σ = 0.05 m and a
//! burst (a 0.5–2 m drop with damped ringing) every ~50 000 samples; every call gets a new seed.

use cpd_core::{Cusum, CusumConfig, ShewhartConfig};

/// SplitMix64: seeded, tiny.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1].
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 / (1u64 << 53) as f64
    }

    /// Approximately standard normal: the sum of 4 uniforms (Irwin-Hall), cheap to draw.
    fn normal(&mut self) -> f64 {
        let s = self.uniform() + self.uniform() + self.uniform() + self.uniform();
        (s - 2.0) * 3f64.sqrt()
    }
}

/// Sensor noise (m) and the calibrated detector parameters for it.
pub const NOISE: f64 = 0.05;
pub const CUSUM_THRESHOLD: f64 = 0.3;
pub const CUSUM_DRIFT: f64 = 0.01;
pub const SHEWHART_SIGMA: f64 = 3.0;
pub const SHEWHART_THRESHOLD: f64 = 0.2;

/// Samples per single-channel trace.
pub const SAMPLES: usize = 100_000;
/// The Shewhart windows measured.
pub const WINDOWS: [usize; 3] = [10, 100, 10_000];

/// A source of fresh traces: every call gets a new seed.
pub struct Traces {
    seed: u64,
}

impl Traces {
    pub fn new(seed: u64) -> Self {
        Traces { seed }
    }

    /// `n` samples of one meter: 200 m + noise of σ = NOISE, a burst every ~50 000 samples.
    pub fn heads(&mut self, n: usize) -> Vec<f64> {
        self.seed += 1;
        let mut rng = Rng(self.seed.wrapping_mul(0xD1B5_4A32_D192_ED03));
        let mut level = 200.0;
        let mut ring = 0.0f64;
        let mut since = u32::MAX;
        (0..n)
            .map(|_| {
                if rng.next_u64().is_multiple_of(50_000) {
                    ring = 0.5 + 1.5 * rng.uniform();
                    level -= ring;
                    since = 0;
                }
                let t = since as f64;
                since = since.saturating_add(1);
                let transient = if since < 4_000 {
                    0.5 * ring * (-t / 400.0).exp() * (t / 15.0).cos()
                } else {
                    0.0
                };
                level + transient + NOISE * rng.normal()
            })
            .collect()
    }

    /// `steps` rows of `channels` meters (row-major), each column a fresh trace.
    pub fn matrix(&mut self, steps: usize, channels: usize) -> Vec<f64> {
        let cols: Vec<Vec<f64>> = (0..channels).map(|_| self.heads(steps)).collect();
        (0..steps)
            .flat_map(|t| cols.iter().map(move |c| c[t]))
            .collect()
    }
}

/// A CUSUM at the calibrated threshold with drift `drift`.
pub fn cusum(drift: f64) -> Cusum {
    Cusum::new(CusumConfig::new(CUSUM_THRESHOLD, drift).unwrap())
}

/// A Shewhart config of window `w` at the calibrated sigma and threshold.
pub fn shewhart_config(w: usize) -> ShewhartConfig {
    ShewhartConfig::new(w, SHEWHART_SIGMA, SHEWHART_THRESHOLD).unwrap()
}

/// Time steps per timed iteration of a bank benchmark (about 2 M channel-samples).
pub fn bank_steps(channels: usize) -> usize {
    (2_097_152 / channels).clamp(16, 4096)
}
