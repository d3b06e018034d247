//! Property tests: the streaming detectors agree with the reference algorithms, banks with
//! independent detectors, snapshots with uninterrupted runs; bad input changes nothing.

mod common;

use common::{signal, Rng, KINDS};
use cpd_core::{
    detect_cusum, detect_shewhart, Alarm, Bank, ChannelAlarm, Cusum, CusumBank, CusumConfig,
    Direction, Error, Shewhart, ShewhartBank, ShewhartConfig,
};
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;

/// `prop_assert!` for conditions whose source contains braces (patterns).
macro_rules! check {
    ($e:expr) => {{
        let ok = $e;
        prop_assert!(ok, "check failed: {}", stringify!($e));
    }};
}

/// The CUSUM online pass written plainly from the paper's Algorithm 1 / TSNet's loop:
/// `(alarm index, start, rise?, x[alarm] - x[start])`.
fn reference_cusum(x: &[f64], threshold: f64, drift: f64) -> Vec<(u64, u64, bool, f64)> {
    let (mut gp, mut gn, mut gp_real, mut gn_real) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let (mut tap, mut tan) = (0usize, 0usize);
    let mut alarms = Vec::new();
    for i in 1..x.len() {
        let s = x[i] - x[i - 1];
        gp = gp + s - drift;
        gp_real += s;
        gn = gn - s - drift;
        gn_real -= s;
        if gp < 0.0 {
            gp = 0.0;
            gp_real = 0.0;
            tap = i;
        }
        if gn < 0.0 {
            gn = 0.0;
            gn_real = 0.0;
            tan = i;
        }
        if gp_real > threshold || gn_real > threshold {
            let rise = gp_real > threshold;
            let start = if rise { tap } else { tan };
            alarms.push((i as u64, start as u64, rise, x[i] - x[start]));
            gp = 0.0;
            gn = 0.0;
            gp_real = 0.0;
            gn_real = 0.0;
        }
    }
    alarms
}

/// `cases` cases; failures are persisted in the crate's `proptest-regressions/` (committed).
fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(
            "proptest-regressions/properties.txt",
        ))),
        ..ProptestConfig::default()
    }
}

fn cusum_alarms(det: &mut Cusum, x: &[f64]) -> Vec<Alarm> {
    let mut out = Vec::new();
    det.update_slice(x, &mut out).unwrap();
    out
}

fn shewhart_alarms(det: &mut Shewhart, x: &[f64]) -> Vec<Alarm> {
    x.iter().filter_map(|&v| det.update(v).unwrap()).collect()
}

/// (kind, length, seed) of a test signal.
fn signal_spec(max_len: usize) -> impl Strategy<Value = (u64, usize, u64)> {
    (0..KINDS, 0..max_len, any::<u64>())
}

fn cusum_params() -> impl Strategy<Value = (f64, f64)> {
    (
        prop_oneof![Just(0.5), Just(1.0), Just(2.0), 0.01f64..10.0],
        prop_oneof![Just(0.0), Just(0.01), Just(0.5), 0.0f64..2.0],
    )
}

fn shewhart_params() -> impl Strategy<Value = (usize, f64, f64)> {
    (2usize..40)
        .prop_flat_map(|w| {
            let tie = ((w - 1) as f64).sqrt(); // the largest possible z-score: exact ties
            (
                Just(w),
                prop_oneof![Just(1.0), Just(2.0), Just(3.0), Just(tie), 0.1f64..4.0],
                prop_oneof![Just(1e-3), Just(0.1), Just(0.5), Just(1.0), 1e-4f64..3.0],
            )
        })
        .prop_map(|(w, s, t)| (w, s, t))
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn cusum_stream_equals_reference_online_pass(
        (kind, n, seed) in signal_spec(600), (thr, drift) in cusum_params()
    ) {
        let x = signal(kind, n, &mut Rng::new(seed));
        let mut det = Cusum::new(CusumConfig::new(thr, drift).unwrap());
        let got = cusum_alarms(&mut det, &x);
        let want = reference_cusum(&x, thr, drift);
        prop_assert_eq!(got.len(), want.len());
        for (a, &(index, start, rise, amp)) in got.iter().zip(&want) {
            prop_assert_eq!(a.index, index);
            prop_assert_eq!(a.start, start);
            prop_assert_eq!(a.direction, if rise { Direction::Rise } else { Direction::Drop });
            prop_assert_eq!(a.amplitude.to_bits(), amp.to_bits());
        }
        // The batch function's raw starts (ending = false) are the same online pass.
        let batch = detect_cusum(&x, thr, drift, false).unwrap();
        let starts: Vec<usize> = got.iter().map(|a| a.start as usize).collect();
        prop_assert_eq!(batch.start, starts);
        prop_assert_eq!(det.samples_seen(), n as u64);
        prop_assert!(det.gp() >= 0.0 && det.gn() >= 0.0);
    }

    #[test]
    fn shewhart_stream_equals_batch_on_trailing_window(
        (kind, n, seed) in signal_spec(400), (w, sigma, thr) in shewhart_params()
    ) {
        let x = signal(kind, n, &mut Rng::new(seed));
        let mut det = Shewhart::new(ShewhartConfig::new(w, sigma, thr).unwrap()).unwrap();
        for (i, &xi) in x.iter().enumerate() {
            let got = det.update(xi).unwrap();
            if i + 1 < w {
                prop_assert!(got.is_none());
                continue;
            }
            let batch = detect_shewhart(&x[i + 1 - w..=i], sigma, thr).unwrap();
            let want = batch.index.last() == Some(&(w - 1));
            prop_assert_eq!(got.is_some(), want, "sample {}", i);
            if let Some(a) = got {
                let amp = *batch.amplitude.last().unwrap();
                prop_assert_eq!((a.index, a.start), (i as u64, i as u64));
                prop_assert!((a.amplitude.abs() - amp).abs() <= 1e-9 * (1.0 + xi.abs()));
                let want_dir = if a.amplitude > 0.0 { Direction::Rise } else { Direction::Drop };
                prop_assert_eq!(a.direction, want_dir);
            }
        }
    }

    #[test]
    fn shewhart_long_stream_with_rebuilds_equals_batch(
        seed in any::<u64>(), kind in 0..KINDS, w in 2usize..12, sigma in 0.5f64..3.0
    ) {
        // Long enough to cross several periodic rebuilds of the running sums.
        let x = signal(kind, 3500, &mut Rng::new(seed));
        let mut det = Shewhart::new(ShewhartConfig::new(w, sigma, 0.05).unwrap()).unwrap();
        for (i, &xi) in x.iter().enumerate() {
            let got = det.update(xi).unwrap().is_some();
            if i + 1 >= w {
                let batch = detect_shewhart(&x[i + 1 - w..=i], sigma, 0.05).unwrap();
                prop_assert_eq!(got, batch.index.last() == Some(&(w - 1)), "sample {}", i);
            }
        }
    }
}

/// Feeds `matrix` (T x channels) to independent detectors built by `make`, merging alarms in
/// (step, channel) order, as a bank reports them.
fn independent<D>(
    channels: usize,
    matrix: &[f64],
    mut make: impl FnMut() -> D,
    mut update: impl FnMut(&mut D, f64) -> Option<Alarm>,
) -> Vec<ChannelAlarm> {
    let mut dets: Vec<D> = (0..channels).map(|_| make()).collect();
    let mut out = Vec::new();
    for row in matrix.chunks_exact(channels) {
        for (c, (d, &v)) in dets.iter_mut().zip(row).enumerate() {
            if let Some(alarm) = update(d, v) {
                out.push(ChannelAlarm { channel: c, alarm });
            }
        }
    }
    out
}

/// A T x channels matrix whose columns are signals of random families.
fn matrix(channels: usize, steps: usize, seed: u64) -> Vec<f64> {
    let mut rng = Rng::new(seed);
    let cols: Vec<Vec<f64>> = (0..channels)
        .map(|_| {
            let kind = rng.below(KINDS);
            signal(kind, steps, &mut rng)
        })
        .collect();
    (0..steps)
        .flat_map(|t| cols.iter().map(move |c| c[t]))
        .collect()
}

fn channel_counts() -> impl Strategy<Value = usize> {
    // Small banks, and banks crossing the internal 256-channel block.
    prop_oneof![1usize..8, 255usize..260]
}

proptest! {
    #![proptest_config(config(48))]

    #[test]
    fn cusum_bank_equals_independent_detectors(
        channels in channel_counts(), steps in 0usize..150, seed in any::<u64>(),
        (thr, drift) in cusum_params()
    ) {
        let m = matrix(channels, steps, seed);
        let cfg = CusumConfig::new(thr, drift).unwrap();
        let want = independent(channels, &m, || Cusum::new(cfg), |d, v| d.update(v).unwrap());
        // One call per step...
        let mut bank = CusumBank::new(channels, cfg).unwrap();
        let mut got = Vec::new();
        for row in m.chunks_exact(channels) {
            bank.step(row, &mut got).unwrap();
        }
        prop_assert_eq!(&got, &want);
        prop_assert_eq!(bank.steps_seen(), steps as u64);
        // ...or the whole matrix at once, through the enum.
        let mut bank = Bank::from(CusumBank::new(channels, cfg).unwrap());
        let mut got = Vec::new();
        bank.step_many(&m, &mut got).unwrap();
        prop_assert_eq!(&got, &want);
    }

    #[test]
    fn cusum_bank_many_rows_equals_row_by_row(
        channels in 1usize..20, steps in 0usize..1300, split in 0usize..1300,
        seed in any::<u64>(), (thr, drift) in cusum_params()
    ) {
        // Crosses the chunk of rows and the tile of channels of the time-blocked kernel, and
        // splits the feed in two calls (the second starting mid-chunk).
        let m = matrix(channels, steps, seed);
        let cfg = CusumConfig::new(thr, drift).unwrap();
        let mut by_row = CusumBank::new(channels, cfg).unwrap();
        let mut want = Vec::new();
        for row in m.chunks_exact(channels) {
            by_row.step(row, &mut want).unwrap();
        }
        let (head, tail) = m.split_at(split.min(steps) * channels);
        let mut many = CusumBank::new(channels, cfg).unwrap();
        let mut got = Vec::new();
        many.step_many(head, &mut got).unwrap();
        many.step_many(tail, &mut got).unwrap();
        prop_assert_eq!(&got, &want);
        prop_assert_eq!(&many, &by_row);
    }

    #[test]
    fn shewhart_bank_equals_independent_detectors(
        channels in channel_counts(), steps in 0usize..1200, seed in any::<u64>(),
        (w, sigma, thr) in shewhart_params()
    ) {
        let m = matrix(channels.min(64), steps, seed); // keep the largest cases quick
        let channels = channels.min(64);
        let cfg = ShewhartConfig::new(w, sigma, thr).unwrap();
        let want = independent(channels, &m, || Shewhart::new(cfg).unwrap(), |d, v| d.update(v).unwrap());
        let mut bank = Bank::from(ShewhartBank::new(channels, cfg).unwrap());
        let mut got = Vec::new();
        bank.step_many(&m, &mut got).unwrap();
        prop_assert_eq!(&got, &want);
    }

    #[test]
    fn shewhart_bank_many_rows_equals_row_by_row(
        channels in 1usize..40, steps in 0usize..1300, split in 0usize..1300,
        seed in any::<u64>(), (w, sigma, thr) in shewhart_params()
    ) {
        // Crosses the tile of channels and the chunks of rows (ring wraps, rebuilds) of the
        // time-blocked kernel, and splits the feed in two calls (the second mid-chunk): the
        // alarms are the independent detectors', the state that of stepping row by row.
        let m = matrix(channels, steps, seed);
        let cfg = ShewhartConfig::new(w, sigma, thr).unwrap();
        let want = independent(channels, &m, || Shewhart::new(cfg).unwrap(), |d, v| d.update(v).unwrap());
        let mut by_row = ShewhartBank::new(channels, cfg).unwrap();
        let mut rows_out = Vec::new();
        for row in m.chunks_exact(channels) {
            by_row.step(row, &mut rows_out).unwrap();
        }
        prop_assert_eq!(&rows_out, &want);
        let (head, tail) = m.split_at(split.min(steps) * channels);
        let mut many = ShewhartBank::new(channels, cfg).unwrap();
        let mut got = Vec::new();
        many.step_many(head, &mut got).unwrap();
        many.step_many(tail, &mut got).unwrap();
        prop_assert_eq!(&got, &want);
        prop_assert_eq!(&many, &by_row);
    }

    #[test]
    fn shewhart_bank_crossing_blocks_equals_independent_detectors(
        channels in 255usize..262, steps in 0usize..80, seed in any::<u64>(),
        (w, sigma, thr) in shewhart_params()
    ) {
        let m = matrix(channels, steps, seed);
        let cfg = ShewhartConfig::new(w, sigma, thr).unwrap();
        let want = independent(channels, &m, || Shewhart::new(cfg).unwrap(), |d, v| d.update(v).unwrap());
        let mut bank = ShewhartBank::new(channels, cfg).unwrap();
        let mut got = Vec::new();
        for row in m.chunks_exact(channels) {
            bank.step(row, &mut got).unwrap();
        }
        prop_assert_eq!(&got, &want);
    }

    #[test]
    fn update_slice_in_chunks_equals_update_per_sample(
        (kind, n, seed) in signal_spec(2500), chunk in 1usize..300,
        (thr, drift) in cusum_params(), (w, sigma, sthr) in shewhart_params()
    ) {
        let x = signal(kind, n, &mut Rng::new(seed));
        let cc = CusumConfig::new(thr, drift).unwrap();
        let sc = ShewhartConfig::new(w, sigma, sthr).unwrap();
        let (mut c1, mut s1) = (Cusum::new(cc), Shewhart::new(sc).unwrap());
        let want_c: Vec<Alarm> = x.iter().filter_map(|&v| c1.update(v).unwrap()).collect();
        let want_s = shewhart_alarms(&mut s1, &x);
        let (mut c2, mut s2) = (Cusum::new(cc), Shewhart::new(sc).unwrap());
        let (mut got_c, mut got_s) = (Vec::new(), Vec::new());
        for part in x.chunks(chunk) {
            c2.update_slice(part, &mut got_c).unwrap();
            s2.update_slice(part, &mut got_s).unwrap();
        }
        prop_assert_eq!(got_c, want_c);
        prop_assert_eq!(got_s, want_s);
        prop_assert_eq!(&c2, &c1);
        prop_assert_eq!(&s2, &s1);
    }

    #[test]
    fn long_slice_equals_update_per_sample(
        (kind, n, seed) in (0..KINDS + 3, 512usize..20_000, any::<u64>()),
        lead in 0usize..40, (thr, drift) in cusum_params()
    ) {
        // Long slices run as segments guessed in a bank and joined to the true state: the
        // alarms and the end state must be those of the sample-by-sample run, from a fresh
        // detector and from one part-way through a stream (`lead` samples fed one by one).
        // Kinds past the signal families: a steep ramp (a side that never resets keeps its old
        // start: the guess never meets the truth, the slice falls back to sequential), a slow
        // one, and a constant (with drift 0 the sums stay 0 and never reset).
        let x: Vec<f64> = match kind {
            k if k < KINDS => signal(k, n, &mut Rng::new(seed)),
            k if k == KINDS => (0..n).map(|i| 200.0 - 0.05 * i as f64).collect(),
            k if k == KINDS + 1 => (0..n).map(|i| 200.0 - 1e-3 * i as f64).collect(),
            _ => vec![200.0; n],
        };
        let cc = CusumConfig::new(thr, drift).unwrap();
        let mut one = Cusum::new(cc);
        let want: Vec<Alarm> = x.iter().filter_map(|&v| one.update(v).unwrap()).collect();
        let mut det = Cusum::new(cc);
        let lead = lead.min(n);
        let mut got: Vec<Alarm> = x[..lead].iter().filter_map(|&v| det.update(v).unwrap()).collect();
        det.update_slice(&x[lead..], &mut got).unwrap();
        prop_assert_eq!(got.len(), want.len());
        for (a, b) in got.iter().zip(&want) {
            prop_assert_eq!((a.index, a.start, a.direction), (b.index, b.start, b.direction));
            prop_assert_eq!(a.amplitude.to_bits(), b.amplitude.to_bits());
        }
        prop_assert_eq!(&det, &one);
    }

    #[test]
    fn bad_sample_late_in_a_long_slice_changes_nothing(
        (kind, n, seed) in (0..KINDS, 4_200usize..20_000, any::<u64>()), frac in 0.0f64..1.0,
        lead in 0usize..3, bad in prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY)]
    ) {
        // Long slices are checked block by block as they run: a bad sample after blocks have
        // run (and raised alarms) must put their state and alarms back and name its index.
        let mut x = signal(kind, n, &mut Rng::new(seed));
        let pos = lead + ((n - 1 - lead) as f64 * frac) as usize;
        let cc = CusumConfig::new(0.3, 0.01).unwrap();
        let mut det = Cusum::new(cc);
        let mut out = Vec::new();
        det.update_slice(&x[..lead], &mut out).unwrap();
        let (before, given) = (det.clone(), out.clone());
        x[pos] = bad;
        let err = det.update_slice(&x[lead..], &mut out).unwrap_err();
        check!(matches!(err, Error::NonFiniteSample { index, .. } if index == pos as u64));
        prop_assert_eq!(&det, &before);
        prop_assert_eq!(&out, &given);
    }

    #[test]
    fn snapshot_restore_continues_identically(
        (kind, n, seed) in signal_spec(2500), cut in 0.0f64..1.0,
        (thr, drift) in cusum_params(), (w, sigma, sthr) in shewhart_params()
    ) {
        let x = signal(kind, n, &mut Rng::new(seed));
        let k = (cut * n as f64) as usize;
        let (head, tail) = x.split_at(k);

        let mut c = Cusum::new(CusumConfig::new(thr, drift).unwrap());
        cusum_alarms(&mut c, head);
        let mut c2: Cusum = serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
        prop_assert_eq!(&c2, &c);
        prop_assert_eq!(cusum_alarms(&mut c2, tail), cusum_alarms(&mut c, tail));
        prop_assert_eq!(&c2, &c);

        let mut s = Shewhart::new(ShewhartConfig::new(w, sigma, sthr).unwrap()).unwrap();
        shewhart_alarms(&mut s, head);
        let mut s2: Shewhart = serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
        prop_assert_eq!(&s2, &s);
        prop_assert_eq!(shewhart_alarms(&mut s2, tail), shewhart_alarms(&mut s, tail));
        prop_assert_eq!(&s2, &s);
    }

    #[test]
    fn bank_snapshot_restore_continues_identically(
        channels in 1usize..6, steps in 0usize..1500, seed in any::<u64>(), cut in 0.0f64..1.0,
        (w, sigma, thr) in shewhart_params()
    ) {
        let m = matrix(channels, steps, seed);
        let k = (cut * steps as f64) as usize * channels;
        let (head, tail) = m.split_at(k);
        for mut bank in [
            Bank::from(CusumBank::new(channels, CusumConfig::new(thr, 0.01).unwrap()).unwrap()),
            Bank::from(ShewhartBank::new(channels, ShewhartConfig::new(w, sigma, thr).unwrap()).unwrap()),
        ] {
            let mut sink = Vec::new();
            bank.step_many(head, &mut sink).unwrap();
            let json = serde_json::to_string(&bank).unwrap();
            let mut restored: Bank = serde_json::from_str(&json).unwrap();
            prop_assert_eq!(&restored, &bank);
            let (mut a, mut b) = (Vec::new(), Vec::new());
            bank.step_many(tail, &mut a).unwrap();
            restored.step_many(tail, &mut b).unwrap();
            prop_assert_eq!(a, b);
            prop_assert_eq!(&restored, &bank);
        }
    }

    #[test]
    fn bad_sample_leaves_state_unchanged(
        (kind, n, seed) in signal_spec(1500), bad in prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY)],
        pos in 0usize..20, (w, sigma, thr) in shewhart_params()
    ) {
        let x = signal(kind, n, &mut Rng::new(seed));
        let mut c = Cusum::new(CusumConfig::new(thr, 0.01).unwrap());
        let mut s = Shewhart::new(ShewhartConfig::new(w, sigma, thr).unwrap()).unwrap();
        cusum_alarms(&mut c, &x);
        shewhart_alarms(&mut s, &x);
        let (c0, s0) = (c.clone(), s.clone());
        let seen = n as u64;
        check!(matches!(c.update(bad), Err(Error::NonFiniteSample { index, .. }) if index == seen));
        check!(matches!(s.update(bad), Err(Error::NonFiniteSample { index, .. }) if index == seen));
        prop_assert_eq!(&c, &c0);
        prop_assert_eq!(&s, &s0);
        // A slice with a bad sample anywhere is rejected whole.
        let mut xs = signal(kind, 20, &mut Rng::new(seed ^ 1));
        xs[pos] = bad;
        let mut out = Vec::new();
        let err = c.update_slice(&xs, &mut out).unwrap_err();
        prop_assert!(!err.is_config());
        check!(matches!(err, Error::NonFiniteSample { index, .. } if index == seen + pos as u64));
        prop_assert!(s.update_slice(&xs, &mut out).is_err());
        prop_assert!(out.is_empty());
        prop_assert_eq!(&c, &c0);
        prop_assert_eq!(&s, &s0);
        // The next good samples continue as if the bad ones never arrived.
        xs[pos] = 200.0;
        let (mut c1, mut s1) = (c0.clone(), s0.clone());
        prop_assert_eq!(cusum_alarms(&mut c, &xs), cusum_alarms(&mut c1, &xs));
        prop_assert_eq!(shewhart_alarms(&mut s, &xs), shewhart_alarms(&mut s1, &xs));
    }

    #[test]
    fn bad_reading_leaves_bank_unchanged(
        channels in 1usize..6, steps in 0usize..200, seed in any::<u64>(),
        bad in prop_oneof![Just(f64::NAN), Just(f64::INFINITY)], row in 0usize..3,
        col in 0usize..6, (w, sigma, thr) in shewhart_params()
    ) {
        let col = col % channels;
        let m = matrix(channels, steps, seed);
        for mut bank in [
            Bank::from(CusumBank::new(channels, CusumConfig::new(thr, 0.0).unwrap()).unwrap()),
            Bank::from(ShewhartBank::new(channels, ShewhartConfig::new(w, sigma, thr).unwrap()).unwrap()),
        ] {
            let mut out = Vec::new();
            bank.step_many(&m, &mut out).unwrap();
            let before = bank.clone();
            let n_out = out.len();
            let mut readings = vec![200.0; channels];
            readings[col] = bad;
            check!(matches!(bank.step(&readings, &mut out),
                Err(Error::NonFiniteReading { channel, .. }) if channel == col));
            check!(matches!(bank.step(&readings[1..], &mut out),
                Err(Error::ChannelCount { expected, got }) if expected == channels && got == channels - 1));
            let mut many = vec![200.0; 3 * channels];
            many[row * channels + col] = bad;
            check!(matches!(bank.step_many(&many, &mut out),
                Err(Error::NonFiniteMatrixReading { row: r, channel, .. }) if r == row && channel == col));
            if channels > 1 {
                check!(matches!(bank.step_many(&many[1..], &mut out), Err(Error::MatrixShape { .. })));
            }
            prop_assert_eq!(out.len(), n_out);
            prop_assert_eq!(&bank, &before);
        }
    }

    #[test]
    fn reset_equals_new(
        (kind, n, seed) in signal_spec(1500), (thr, drift) in cusum_params(),
        (w, sigma, sthr) in shewhart_params(), channels in 1usize..5
    ) {
        let x = signal(kind, n, &mut Rng::new(seed));
        let cc = CusumConfig::new(thr, drift).unwrap();
        let sc = ShewhartConfig::new(w, sigma, sthr).unwrap();
        let mut c = Cusum::new(cc);
        let first = cusum_alarms(&mut c, &x);
        c.reset();
        prop_assert_eq!(&c, &Cusum::new(cc));
        prop_assert_eq!(cusum_alarms(&mut c, &x), first);

        let mut s = Shewhart::new(sc).unwrap();
        let first = shewhart_alarms(&mut s, &x);
        s.reset();
        prop_assert_eq!(&s, &Shewhart::new(sc).unwrap());
        prop_assert_eq!(shewhart_alarms(&mut s, &x), first);

        let m = matrix(channels, n / channels, seed);
        let fresh = [
            Bank::from(CusumBank::new(channels, cc).unwrap()),
            Bank::from(ShewhartBank::new(channels, sc).unwrap()),
        ];
        for f in fresh {
            let mut bank = f.clone();
            let mut out = Vec::new();
            bank.step_many(&m, &mut out).unwrap();
            bank.reset();
            prop_assert_eq!(&bank, &f);
        }
    }
}
