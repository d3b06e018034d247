//! Shared helpers for the integration tests: a seeded generator of pressure-like signals, and
//! snapshots of every kind fed one.
#![allow(dead_code)]

/// SplitMix64: tiny, seeded, good enough for test signals.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform integer in [0, n).
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n
    }

    /// Roughly normal (sum of 4 uniforms), mean 0, std 1.
    pub fn normal(&mut self) -> f64 {
        let s: f64 = (0..4).map(|_| self.uniform()).sum();
        (s - 2.0) * (3.0f64).sqrt()
    }
}

/// Signal families: each stresses something different.
pub const KINDS: u64 = 6;

/// `n` samples of signal family `kind` (see [`KINDS`]).
pub fn signal(kind: u64, n: usize, rng: &mut Rng) -> Vec<f64> {
    let mut x = Vec::with_capacity(n);
    let mut level = 200.0;
    for i in 0..n {
        let v = match kind {
            // Heads near 200 m with millimetre noise and occasional steps (bursts).
            0 => {
                if rng.below(100) == 0 {
                    level -= 0.5 + 2.0 * rng.uniform();
                }
                level + 1e-3 * rng.normal()
            }
            // Small integers: exact ties everywhere (repeated starts, |x - μ| == s·σ).
            1 => rng.below(5) as f64 - 2.0,
            // Wide uniform floats.
            2 => (rng.uniform() - 0.5) * 2e3,
            // Random walk.
            3 => {
                level += rng.normal();
                level
            }
            // Piecewise constant (plateaus) with rare jumps.
            4 => {
                if rng.below(25) == 0 {
                    level = (rng.below(7) as f64 - 3.0) * 0.75;
                }
                level
            }
            // Decaying oscillation after a drop: a water-hammer transient.
            _ => {
                let t = i as f64 * 0.05;
                200.0
                    - 2.0 * (1.0 + (-0.3 * t).exp() * (7.0 * t).cos()) * ((i > n / 3) as u8 as f64)
                    + 1e-3 * rng.normal()
            }
        };
        x.push(v);
    }
    x
}

/// The four snapshot kinds (a CUSUM, a Shewhart, a bank of each) fed `n` samples of a seeded
/// signal (the banks the same samples as rows of two channels), as snapshot bytes with the
/// kind's name: `"Cusum"`, `"Shewhart"`, `"CusumBank"`, `"ShewhartBank"`.
pub fn snapshots(seed: u64, n: usize) -> Vec<(&'static str, Vec<u8>)> {
    use cpd_core::snapshot::to_bytes;
    use cpd_core::{Bank, Cusum, CusumBank, CusumConfig, Shewhart, ShewhartBank, ShewhartConfig};
    let x = signal(seed % 6, n, &mut Rng::new(seed));
    let mut c = Cusum::new(CusumConfig::new(0.5, 0.01).unwrap());
    let mut s = Shewhart::new(ShewhartConfig::new(5, 2.0, 0.1).unwrap()).unwrap();
    let mut cb = Bank::from(CusumBank::new(2, CusumConfig::new(0.5, 0.0).unwrap()).unwrap());
    let mut sb =
        Bank::from(ShewhartBank::new(2, ShewhartConfig::new(4, 1.0, 0.1).unwrap()).unwrap());
    let (mut a, mut b) = (Vec::new(), Vec::new());
    c.update_slice(&x, &mut a).unwrap();
    s.update_slice(&x, &mut a).unwrap();
    let even = &x[..x.len() / 2 * 2];
    cb.step_many(even, &mut b).unwrap();
    sb.step_many(even, &mut b).unwrap();
    vec![
        ("Cusum", to_bytes(&c)),
        ("Shewhart", to_bytes(&s)),
        ("CusumBank", to_bytes(&cb)),
        ("ShewhartBank", to_bytes(&sb)),
    ]
}

/// The CBOR payload of format-2 snapshot bytes: what lies between the 13-byte header (magic,
/// version, length) and the 4-byte CRC-32C.
pub fn payload(bytes: &[u8]) -> &[u8] {
    assert_eq!(&bytes[..4], b"CPDS", "a format-2 snapshot");
    &bytes[13..bytes.len() - 4]
}

/// A CBOR payload framed as a format-2 snapshot with its valid length and checksum, as
/// `cpd_core::snapshot::to_bytes` frames it: for tests of what lies behind the checksum.
pub fn seal(payload: &[u8]) -> Vec<u8> {
    use cpd_core::snapshot::{crc32c, FORMAT, MAGIC};
    let mut bytes = MAGIC.to_vec();
    bytes.push(FORMAT);
    bytes.extend_from_slice(&((13 + payload.len() + 4) as u64).to_le_bytes());
    bytes.extend_from_slice(payload);
    let crc = crc32c(&bytes);
    bytes.extend_from_slice(&crc.to_le_bytes());
    bytes
}
