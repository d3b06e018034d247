//! Fuzzing on stable Rust (proptest with byte-level inputs): the snapshot decoder and arbitrary
//! update sequences never panic, whatever the bytes or samples.
//!
//! `cargo test -p cpd-core --test fuzz` runs a bounded number of cases (proptest's default,
//! 256 per target). A longer run: `PROPTEST_CASES=100000 cargo test --release -p cpd-core --test
//! fuzz`. Failures are persisted in `proptest-regressions/fuzz.txt` (committed).

mod common;

use common::{payload, seal, signal, snapshots, Rng};
use cpd_core::snapshot::{self, Snapshot};
use cpd_core::{Bank, Cusum, CusumBank, CusumConfig, Shewhart, ShewhartBank, ShewhartConfig};
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;

/// Proptest's defaults (`PROPTEST_CASES` sets the number of cases), failures persisted.
fn config() -> ProptestConfig {
    ProptestConfig {
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(
            "proptest-regressions/fuzz.txt",
        ))),
        ..ProptestConfig::default()
    }
}

/// Any f64 bit pattern half of the time, else a head-like value.
fn sample() -> impl Strategy<Value = f64> {
    prop_oneof![
        any::<u64>().prop_map(f64::from_bits),
        (-1e3f64..1e3),
        Just(f64::MAX),
        Just(-f64::MAX),
        Just(1e160),
        Just(0.0),
    ]
}

/// Bit-exact equality: the same snapshot bytes (`==` on floats takes -0.0 for 0.0).
fn same<T: Snapshot>(a: &T, b: &T) -> bool {
    snapshot::to_bytes(a) == snapshot::to_bytes(b)
}

/// Decodes `bytes` as `T`; if that works, the value re-encodes to the same value and runs on.
fn decode_and_run<T: Snapshot>(bytes: &[u8], run: impl Fn(&mut T)) -> Result<(), TestCaseError> {
    if let Ok(mut value) = snapshot::from_bytes::<T>(bytes) {
        let again: T = snapshot::from_bytes(&snapshot::to_bytes(&value)).unwrap();
        prop_assert!(same(&again, &value));
        run(&mut value);
    }
    Ok(())
}

fn run_cusum(det: &mut Cusum) {
    let mut out = Vec::new();
    for v in [0.0, 1e308, -1e308, 200.0, f64::NAN] {
        let _ = det.update(v);
    }
    let _ = det.update_slice(&[1.0, 2.0, -5.0, 1e300], &mut out);
}

fn run_shewhart(det: &mut Shewhart) {
    let mut out = Vec::new();
    for v in [0.0, 1e308, -1e308, 200.0, f64::INFINITY] {
        let _ = det.update(v);
    }
    let _ = det.update_slice(&[1.0, 2.0, -5.0, 1e300], &mut out);
}

fn run_bank(bank: &mut Bank) {
    let mut out = Vec::new();
    let n = bank.channels().min(64);
    for v in [0.0, 1e308, -1e308, 200.0] {
        let _ = bank.step(&vec![v; n], &mut out);
    }
    let _ = bank.step_many(&vec![1.0; 3 * n], &mut out);
}

/// Decodes bytes as every kind; none may panic.
fn decode_all(bytes: &[u8]) -> Result<(), TestCaseError> {
    decode_and_run::<Cusum>(bytes, run_cusum)?;
    decode_and_run::<Shewhart>(bytes, run_shewhart)?;
    decode_and_run::<Bank>(bytes, run_bank)
}

/// One edit of a byte string.
#[derive(Debug, Clone)]
enum Edit {
    Set(usize, u8),
    Insert(usize, u8),
    Remove(usize),
    Truncate(usize),
    /// Overwrite 8 bytes with an f64 (e.g. a NaN where a float was).
    Float(usize, f64),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Set(i, b)),
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Insert(i, b)),
        any::<usize>().prop_map(Edit::Remove),
        any::<usize>().prop_map(Edit::Truncate),
        (any::<usize>(), sample()).prop_map(|(i, v)| Edit::Float(i, v)),
    ]
}

fn apply(bytes: &mut Vec<u8>, e: &Edit) {
    if bytes.is_empty() {
        return;
    }
    let at = |i: usize| i % bytes.len();
    match *e {
        Edit::Set(i, b) => {
            let i = at(i);
            bytes[i] = b;
        }
        Edit::Insert(i, b) => {
            let i = at(i);
            bytes.insert(i, b);
        }
        Edit::Remove(i) => {
            let i = at(i);
            bytes.remove(i);
        }
        Edit::Truncate(i) => {
            let i = at(i);
            bytes.truncate(i);
        }
        Edit::Float(i, v) => {
            let i = at(i).min(bytes.len().saturating_sub(8));
            let end = (i + 8).min(bytes.len());
            bytes[i..end].copy_from_slice(&v.to_be_bytes()[..end - i]);
        }
    }
}

/// One operation on a detector or bank.
#[derive(Debug, Clone)]
enum Op {
    Update(f64),
    Slice(Vec<f64>),
    /// A long slice (the single CUSUM runs it as segments): a seeded head-like signal of `n`
    /// samples with arbitrary values put in at a few places.
    Long(u64, usize, Vec<(usize, f64)>),
    Reset,
    Restore,
}

impl Op {
    /// The samples of a [`Op::Long`].
    fn long(seed: u64, n: usize, spikes: &[(usize, f64)]) -> Vec<f64> {
        let mut xs = signal(seed % 6, n, &mut Rng::new(seed));
        for &(at, v) in spikes {
            xs[at % n] = v;
        }
        xs
    }
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        6 => sample().prop_map(Op::Update),
        3 => prop::collection::vec(sample(), 0..12).prop_map(Op::Slice),
        1 => (any::<u64>(), 512usize..3_000, prop::collection::vec((any::<usize>(), sample()), 0..4))
            .prop_map(|(seed, n, spikes)| Op::Long(seed, n, spikes)),
        1 => Just(Op::Reset),
        1 => Just(Op::Restore),
    ]
}

/// A long slice fed to `det` (the single CUSUM runs it as segments): no panic; on error
/// nothing changes, else the alarms and the state are the sample-by-sample ones, bit for bit.
fn long_slice_as_one_by_one(det: &mut Cusum, xs: &[f64]) -> Result<(), TestCaseError> {
    let before = det.clone();
    let mut one = det.clone();
    let mut want = Vec::new();
    let stepped = xs.iter().try_for_each(|&v| {
        want.extend(one.update(v)?);
        Ok::<(), cpd_core::Error>(())
    });
    let mut got = Vec::new();
    match det.update_slice(xs, &mut got) {
        Err(_) => {
            prop_assert!(stepped.is_err());
            prop_assert!(same(&*det, &before) && got.is_empty());
        }
        Ok(()) => {
            prop_assert!(stepped.is_ok());
            prop_assert!(same(&*det, &one));
            prop_assert_eq!(got.len(), want.len());
            for (a, b) in got.iter().zip(&want) {
                prop_assert_eq!(
                    (a.index, a.start, a.direction),
                    (b.index, b.start, b.direction)
                );
                prop_assert_eq!(a.amplitude.to_bits(), b.amplitude.to_bits());
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn long_slices_with_extreme_values_run_as_one_by_one(
        seed in any::<u64>(), n in 512usize..6_000,
        spikes in prop::collection::vec((any::<usize>(), sample()), 0..4),
        thr in prop_oneof![Just(0.3), 1e-3f64..1e3], drift in prop_oneof![Just(0.01), 1e-6f64..10.0],
        lead in 0usize..3
    ) {
        let mut det = Cusum::new(CusumConfig::new(thr, drift).unwrap());
        let xs = Op::long(seed, n, &spikes);
        det.update_slice(&xs[..lead], &mut Vec::new()).unwrap_or(());
        long_slice_as_one_by_one(&mut det, &xs[lead..])?;
    }

    #[test]
    fn snapshot_decoder_never_panics_on_arbitrary_bytes(
        bytes in prop::collection::vec(any::<u8>(), 0..512)
    ) {
        decode_all(&bytes)?;
    }

    #[test]
    fn snapshot_decoder_never_panics_on_edited_snapshots(
        seed in any::<u64>(), n in 0usize..80, edits in prop::collection::vec(edit(), 1..6)
    ) {
        for (_, mut bytes) in snapshots(seed, n) {
            // The payload edited and sealed with a valid checksum (a hostile or buggy writer:
            // the decoder behind the checksum), then the snapshot itself edited.
            let mut inner = payload(&bytes).to_vec();
            for e in &edits {
                apply(&mut inner, e);
                apply(&mut bytes, e);
            }
            decode_all(&seal(&inner))?;
            decode_all(&bytes)?;
        }
    }

    #[test]
    fn arbitrary_update_sequences_never_panic_and_errors_change_nothing(
        thr in sample(), drift in sample(), w in 0usize..40, sigma in sample(),
        channels in 0usize..5, ops in prop::collection::vec(op(), 0..60)
    ) {
        // Detectors for whichever parameters are valid; invalid ones must be config errors.
        let cusum = CusumConfig::new(thr, drift).map(Cusum::new);
        let shewhart = ShewhartConfig::new(w, sigma, thr).and_then(Shewhart::new);
        let banks = [
            CusumConfig::new(thr, drift).and_then(|c| CusumBank::new(channels, c)).map(Bank::from),
            ShewhartConfig::new(w, sigma, thr)
                .and_then(|c| ShewhartBank::new(channels, c))
                .map(Bank::from),
        ];
        for r in [cusum.as_ref().err(), shewhart.as_ref().err()].into_iter().flatten() {
            prop_assert!(r.is_config());
        }
        let mut c = cusum.ok();
        let mut s = shewhart.ok();
        let mut banks: Vec<Bank> = banks
            .into_iter()
            .filter_map(|b| match b {
                Ok(b) => Some(b),
                Err(e) => {
                    assert!(e.is_config(), "{e}");
                    None
                }
            })
            .collect();
        let mut out = Vec::new();
        let mut bank_out = Vec::new();
        for op in &ops {
            match op {
                Op::Update(v) => {
                    if let Some(d) = c.as_mut() {
                        let before = d.clone();
                        if d.update(*v).is_err() { prop_assert!(same(&*d, &before)); }
                    }
                    if let Some(d) = s.as_mut() {
                        let before = d.clone();
                        if d.update(*v).is_err() { prop_assert!(same(&*d, &before)); }
                    }
                    for b in banks.iter_mut() {
                        let before = b.clone();
                        let row = vec![*v; b.channels()];
                        if b.step(&row, &mut bank_out).is_err() { prop_assert!(same(&*b, &before)); }
                    }
                }
                Op::Slice(xs) => {
                    if let Some(d) = c.as_mut() {
                        let before = d.clone();
                        if d.update_slice(xs, &mut out).is_err() { prop_assert!(same(&*d, &before)); }
                    }
                    if let Some(d) = s.as_mut() {
                        let before = d.clone();
                        if d.update_slice(xs, &mut out).is_err() { prop_assert!(same(&*d, &before)); }
                    }
                    for b in banks.iter_mut() {
                        let before = b.clone();
                        if b.step_many(xs, &mut bank_out).is_err() { prop_assert!(same(&*b, &before)); }
                    }
                }
                Op::Long(seed, n, spikes) => {
                    // As a slice: no panic; on error nothing changes, else the result is the
                    // sample-by-sample one, bit for bit (also with extreme values).
                    if let Some(d) = c.as_mut() {
                        long_slice_as_one_by_one(d, &Op::long(*seed, *n, spikes))?;
                    }
                }
                Op::Reset => {
                    if let Some(d) = c.as_mut() { d.reset(); }
                    if let Some(d) = s.as_mut() { d.reset(); }
                    for b in banks.iter_mut() { b.reset(); }
                }
                Op::Restore => {
                    // Every reachable state restores, to an equal value.
                    if let Some(d) = c.as_mut() {
                        let r: Cusum = snapshot::from_bytes(&snapshot::to_bytes(d)).unwrap();
                        prop_assert!(same(&r, &*d));
                    }
                    if let Some(d) = s.as_mut() {
                        let r: Shewhart = snapshot::from_bytes(&snapshot::to_bytes(d)).unwrap();
                        prop_assert!(same(&r, &*d));
                    }
                    for b in banks.iter_mut() {
                        let r: Bank = snapshot::from_bytes(&snapshot::to_bytes(b)).unwrap();
                        prop_assert!(same(&r, &*b));
                    }
                }
            }
        }
    }
}

/// CBOR headers declaring huge lengths (byte string, text, array, map) with no data behind
/// them are refused without allocating what they declare.
#[test]
fn huge_declared_lengths_are_refused() {
    let valid = &snapshots(3, 40)[0].1;
    for header in [0x5bu8, 0x7b, 0x9b, 0xbb] {
        let mut bytes = vec![header];
        bytes.extend_from_slice(&u64::MAX.to_be_bytes());
        assert!(snapshot::from_bytes::<Cusum>(&bytes).is_err());
        // The same after the first bytes of a valid snapshot's payload, sealed with a valid
        // checksum.
        let valid = payload(valid);
        let mut inner = valid[..valid.len() - 9].to_vec();
        inner.extend_from_slice(&bytes);
        let inner = seal(&inner);
        assert!(snapshot::from_bytes::<Cusum>(&inner).is_err());
        assert!(snapshot::from_bytes::<Bank>(&inner).is_err());
    }
}
