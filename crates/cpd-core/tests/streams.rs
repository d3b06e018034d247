//! Golden streams (hand-checked pressure traces), numerical stability and config validation.

mod common;

use common::Rng;
use cpd_core::{
    Alarm, Bank, ChannelAlarm, Cusum, CusumBank, CusumConfig, Direction, Error, Shewhart,
    ShewhartBank, ShewhartConfig,
};

/// 200 m heads with ±1 mm noise, then a drop to `200 - drop` m at sample `at`.
fn step_trace(n: usize, at: usize, drop: f64, seed: u64) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|i| 200.0 - if i >= at { drop } else { 0.0 } + 1e-3 * (rng.uniform() - 0.5))
        .collect()
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn cusum_step_down_alarms_at_the_step() {
    let x = step_trace(300, 120, 1.5, 1);
    let mut det = Cusum::new(CusumConfig::new(0.5, 0.01).unwrap());
    let mut alarms = Vec::new();
    det.update_slice(&x, &mut alarms).unwrap();
    // With drift 0.01 > the 1 mm noise, gn resets on every flat sample: the drop starts at 119.
    assert_eq!(alarms.len(), 1, "{alarms:?}");
    let a = alarms[0];
    assert_eq!((a.index, a.start, a.direction), (120, 119, Direction::Drop));
    assert_eq!(a.amplitude, x[120] - x[119]);
    assert!(close(a.amplitude, -1.5, 2e-3));
}

#[test]
fn cusum_ramp_down_gives_repeated_starts() {
    // A burst opening over 4 samples: 0.3 m per sample, threshold 0.5.
    let mut x = vec![200.0; 100];
    x.extend([199.7, 199.4, 199.1]);
    x.extend(vec![198.8; 50]);
    let mut det = Cusum::new(CusumConfig::new(0.5, 0.01).unwrap());
    let mut alarms = Vec::new();
    det.update_slice(&x, &mut alarms).unwrap();
    // First alarm when 0.6 m have accumulated; the sums reset but tan stays at 99 (gn never
    // went negative again), so TSNet reports the same start twice.
    let got: Vec<(u64, u64)> = alarms.iter().map(|a| (a.index, a.start)).collect();
    assert_eq!(got, vec![(101, 99), (103, 99)]);
    assert!(alarms.iter().all(|a| a.direction == Direction::Drop));
    assert!(close(alarms[0].amplitude, -0.6, 1e-9));
    assert!(close(alarms[1].amplitude, -1.2, 1e-9));
}

#[test]
fn cusum_rise_and_drift_free_start() {
    // drift = 0: flat samples never make the sums negative, so the start stays at 0.
    let mut x = vec![50.0; 10];
    x.extend(vec![51.0; 5]);
    let mut det = Cusum::new(CusumConfig::new(0.5, 0.0).unwrap());
    let alarms: Vec<Alarm> = x.iter().filter_map(|&v| det.update(v).unwrap()).collect();
    assert_eq!(alarms.len(), 1);
    assert_eq!(
        (alarms[0].index, alarms[0].start, alarms[0].direction),
        (10, 0, Direction::Rise)
    );
    assert_eq!(alarms[0].amplitude, 1.0);
}

#[test]
fn shewhart_step_down_alarms_while_the_step_is_an_outlier() {
    // W = 48, s = 3: with k post-step samples in the window, |x - μ| = 1.5 (1 - k/48) and
    // σ = 1.5 sqrt(k (48 - k)) / 48, so the test holds for k < 4.8: samples 120..=123.
    let x = step_trace(300, 120, 1.5, 2);
    let mut det = Shewhart::new(ShewhartConfig::new(48, 3.0, 0.5).unwrap()).unwrap();
    let mut alarms = Vec::new();
    det.update_slice(&x, &mut alarms).unwrap();
    let idx: Vec<u64> = alarms.iter().map(|a| a.index).collect();
    assert_eq!(idx, vec![120, 121, 122, 123]);
    for (k, a) in alarms.iter().enumerate() {
        assert_eq!(a.start, a.index);
        assert_eq!(a.direction, Direction::Drop);
        let want = -1.5 * (1.0 - (k + 1) as f64 / 48.0);
        assert!(close(a.amplitude, want, 2e-3), "{a:?} vs {want}");
    }
}

#[test]
fn shewhart_needs_a_full_window() {
    let mut det = Shewhart::new(ShewhartConfig::new(5, 1.0, 0.1).unwrap()).unwrap();
    for (i, x) in [0.0, 0.0, 0.0, 100.0].into_iter().enumerate() {
        assert_eq!(det.update(x).unwrap(), None, "sample {i}");
    }
    assert_eq!(det.len(), 4);
    // The 5th sample completes the window: a 100 outlier among zeros.
    let a = det.update(-100.0).unwrap().unwrap();
    assert_eq!((a.index, a.direction), (4, Direction::Drop));
    assert_eq!(a.amplitude, -100.0);
}

#[test]
fn banks_report_the_step_on_its_channel_only() {
    let steps = 300;
    let cols = [
        step_trace(steps, usize::MAX, 0.0, 3),
        step_trace(steps, 120, 1.5, 4),
        step_trace(steps, usize::MAX, 0.0, 5),
    ];
    let matrix: Vec<f64> = (0..steps)
        .flat_map(|t| cols.iter().map(move |c| c[t]))
        .collect();
    let mut cusum = Bank::from(CusumBank::new(3, CusumConfig::new(0.5, 0.01).unwrap()).unwrap());
    let mut out: Vec<ChannelAlarm> = Vec::new();
    cusum.step_many(&matrix, &mut out).unwrap();
    assert_eq!(out.len(), 1);
    assert_eq!(
        (out[0].channel, out[0].alarm.index, out[0].alarm.start),
        (1, 120, 119)
    );
    let mut shew =
        Bank::from(ShewhartBank::new(3, ShewhartConfig::new(48, 3.0, 0.5).unwrap()).unwrap());
    let mut out = Vec::new();
    for row in matrix.chunks_exact(3) {
        shew.step(row, &mut out).unwrap();
    }
    let got: Vec<(usize, u64)> = out.iter().map(|a| (a.channel, a.alarm.index)).collect();
    assert_eq!(got, vec![(1, 120), (1, 121), (1, 122), (1, 123)]);
    assert_eq!(
        (shew.kind(), shew.channels(), shew.steps_seen()),
        ("shewhart", 3, 300)
    );
}

/// Two-pass mean and population std in plain f64: the accuracy reference.
fn two_pass(w: &[f64]) -> (f64, f64) {
    let n = w.len() as f64;
    let mean = w.iter().sum::<f64>() / n;
    let var = w.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    (mean, var.sqrt())
}

#[test]
fn shewhart_window_statistics_are_stable_on_pressure_heads() {
    // 300 000 heads near 200 m moving by millimetres, with a 10 m burst step and a slow drift:
    // plain Σx, Σx² would lose every digit of σ ≈ 1e-3 (x² ≈ 4e4, ε·x² ≈ 1e-11 ≈ σ²/100).
    let mut rng = Rng::new(7);
    let n = 300_000;
    let x: Vec<f64> = (0..n)
        .map(|i| {
            let level = if i >= 150_000 { 190.0 } else { 200.0 };
            level + 1e-7 * i as f64 + 1e-3 * rng.normal()
        })
        .collect();
    for w in [10usize, 1000, 10_000] {
        let mut det = Shewhart::new(ShewhartConfig::new(w, 3.0, 0.5).unwrap()).unwrap();
        let mut worst = 0.0f64;
        for (i, &xi) in x.iter().enumerate() {
            det.update(xi).unwrap();
            // Every sample for 3 windows after the step (W <= 1000), else a sample every 997.
            let after_step = (150_000..150_000 + 3 * w).contains(&i) && w <= 1000;
            if i + 1 >= w && (i % 997 == 0 || after_step) {
                let (mean, std) = two_pass(&x[i + 1 - w..=i]);
                assert!(
                    close(det.mean().unwrap(), mean, 1e-12 * mean),
                    "w={w} i={i}"
                );
                let rel = (det.std().unwrap() - std).abs() / std;
                worst = worst.max(rel);
            }
        }
        // Measured: below 1e-13 for every W.
        assert!(worst < 1e-10, "w={w}: worst relative std error {worst:e}");
    }
}

#[test]
fn configs_reject_bad_parameters_by_name() {
    let cases: Vec<(Error, &str)> = vec![
        (CusumConfig::new(0.0, 0.0).unwrap_err(), "threshold"),
        (CusumConfig::new(f64::NAN, 0.0).unwrap_err(), "threshold"),
        (
            CusumConfig::new(f64::INFINITY, 0.0).unwrap_err(),
            "threshold",
        ),
        (CusumConfig::new(1.0, -0.1).unwrap_err(), "drift"),
        (CusumConfig::new(1.0, f64::NAN).unwrap_err(), "drift"),
        (ShewhartConfig::new(1, 1.0, 1.0).unwrap_err(), "window"),
        (ShewhartConfig::new(0, 1.0, 1.0).unwrap_err(), "window"),
        (ShewhartConfig::new(5, 0.0, 1.0).unwrap_err(), "sigma"),
        (
            ShewhartConfig::new(5, f64::INFINITY, 1.0).unwrap_err(),
            "sigma",
        ),
        (ShewhartConfig::new(5, 1.0, -1.0).unwrap_err(), "threshold"),
        (
            CusumBank::new(0, CusumConfig::new(1.0, 0.0).unwrap()).unwrap_err(),
            "channels",
        ),
        (
            ShewhartBank::new(0, ShewhartConfig::new(5, 1.0, 1.0).unwrap()).unwrap_err(),
            "channels",
        ),
        (
            cpd_core::detect_cusum(&[1.0], -1.0, 0.0, true).unwrap_err(),
            "threshold",
        ),
        (
            cpd_core::detect_shewhart(&[1.0], 1.0, 0.0).unwrap_err(),
            "threshold",
        ),
    ];
    for (err, name) in cases {
        assert!(err.is_config(), "{err}");
        assert!(
            matches!(err, Error::InvalidParameter { name: n, .. } if n == name),
            "{err:?}"
        );
        assert!(err.to_string().contains(name), "{err}");
    }
    let ok = ShewhartConfig::new(50, 0.3, 0.2).unwrap();
    assert_eq!((ok.window(), ok.sigma(), ok.threshold()), (50, 0.3, 0.2));
    let ok = CusumConfig::new(0.3, 0.0).unwrap();
    assert_eq!((ok.threshold(), ok.drift()), (0.3, 0.0));
}

#[test]
fn batch_functions_reject_non_finite_samples() {
    let x = [1.0, 2.0, f64::NAN, 4.0];
    for err in [
        cpd_core::detect_cusum(&x, 1.0, 0.0, true).unwrap_err(),
        cpd_core::detect_shewhart(&x, 1.0, 1.0).unwrap_err(),
    ] {
        assert!(!err.is_config());
        assert!(matches!(err, Error::NonFiniteSample { index: 2, value } if value.is_nan()));
    }
    assert_eq!(
        cpd_core::detect_shewhart(&[], 1.0, 1.0).unwrap().index,
        Vec::<usize>::new()
    );
}

#[test]
fn deserialization_rejects_invalid_configs_and_corrupt_state() {
    let bad_cfg = r#"{"threshold":-1.0,"drift":0.0}"#;
    assert!(serde_json::from_str::<CusumConfig>(bad_cfg).is_err());
    let bad_cfg = r#"{"window":1,"sigma":1.0,"threshold":1.0}"#;
    assert!(serde_json::from_str::<ShewhartConfig>(bad_cfg).is_err());
    let cfg = serde_json::from_str::<ShewhartConfig>(r#"{"window":3,"sigma":1.0,"threshold":1.0}"#)
        .unwrap();
    assert_eq!(cfg, ShewhartConfig::new(3, 1.0, 1.0).unwrap());

    let mut det = Shewhart::new(cfg).unwrap();
    det.update(1.0).unwrap();
    let mut json: serde_json::Value = serde_json::to_value(&det).unwrap();
    json["ring"] = serde_json::json!([1.0, 0.0]); // wrong length
    assert!(serde_json::from_value::<Shewhart>(json).is_err());

    let bank = ShewhartBank::new(2, cfg).unwrap();
    let mut json = serde_json::to_value(&bank).unwrap();
    json["s1"] = serde_json::json!([0.0]);
    assert!(serde_json::from_value::<ShewhartBank>(json).is_err());
    let bank = CusumBank::new(2, CusumConfig::new(1.0, 0.0).unwrap()).unwrap();
    let mut json = serde_json::to_value(&bank).unwrap();
    json["tap"] = serde_json::json!([0, 0, 0]);
    assert!(serde_json::from_value::<CusumBank>(json).is_err());
}

/// A bad reading late in a large matrix (past the kernels' first chunks of rows) leaves the
/// bank and the alarms given so far exactly as they were, and is named by its row.
#[test]
fn a_bad_reading_late_in_a_large_matrix_changes_nothing() {
    let channels = 1024;
    let rows = 300; // over four chunks of 64 rows at 1 024 channels
    let mut rng = Rng::new(7);
    let mut matrix: Vec<f64> = (0..rows * channels)
        .map(|k| 200.0 - if k / channels >= 100 { 2.0 } else { 0.0 } + 0.01 * rng.uniform())
        .collect();
    let (bad_row, bad_channel) = (250, 7);
    matrix[bad_row * channels + bad_channel] = f64::NAN;
    let banks = [
        Bank::from(CusumBank::new(channels, CusumConfig::new(0.3, 0.0).unwrap()).unwrap()),
        Bank::from(
            ShewhartBank::new(channels, ShewhartConfig::new(50, 3.0, 0.2).unwrap()).unwrap(),
        ),
    ];
    for mut bank in banks {
        let mut out = Vec::new();
        bank.step_many(&matrix[..10 * channels], &mut out).unwrap();
        let (before, given) = (bank.clone(), out.clone());
        let err = bank.step_many(&matrix, &mut out).unwrap_err();
        assert!(
            matches!(err, Error::NonFiniteMatrixReading { row, channel, .. }
                if row == bad_row && channel == bad_channel),
            "{err:?}"
        );
        assert_eq!(bank, before);
        assert_eq!(out, given);
        // Without the bad reading the same call steps every row, and the drop at row 100 alarms.
        matrix[bad_row * channels + bad_channel] = 200.0;
        bank.step_many(&matrix, &mut out).unwrap();
        assert_eq!(bank.steps_seen(), 10 + rows as u64);
        assert!(out.len() > given.len());
        matrix[bad_row * channels + bad_channel] = f64::NAN;
    }
}
