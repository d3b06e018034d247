//! Snapshots refuse any corruption. For a CUSUM, a Shewhart (window 37), a CUSUM bank and a
//! Shewhart bank (window 37), each fed a seeded signal, every byte offset of the snapshot is
//! altered in turn, exhaustively: the 8-byte patterns of NaN, +inf and -inf (big-endian, as
//! CBOR writes floats, and little-endian) written there, each of its 8 bits flipped, the byte
//! deleted, a zero byte inserted before it; and the snapshot truncated to every shorter length
//! and extended by 1 to 8 zero bytes and by a copy of itself. Every altered snapshot is refused
//! with [`Error::UnreadableSnapshot`] naming the expected problem, and the detector the
//! snapshot was taken from is untouched (equal, and writing the same bytes).
//!
//! Before snapshots carried a checksum, a few of these restored: NaN or inf bytes written
//! across two CBOR items decode to finite, absurd values (a window sum of -3.7e19) that pass
//! every range check, into detectors that never alarm again.

mod common;

use common::{signal, Rng};
use cpd_core::snapshot::{self, Snapshot};
use cpd_core::{
    Bank, Cusum, CusumBank, CusumConfig, Error, Shewhart, ShewhartBank, ShewhartConfig,
    SnapshotProblem,
};
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;

/// Bytes of the header before the payload (magic 0..4, version 4, length 5..13).
const HEADER: usize = 13;

/// One alteration of a snapshot's bytes.
#[derive(Debug, Clone, Copy)]
enum Mutation {
    /// These 8 bytes written at this offset (cut at the end of the snapshot).
    Pattern(usize, [u8; 8]),
    /// This bit of the byte at this offset flipped.
    Flip(usize, u8),
    /// The byte at this offset deleted.
    Delete(usize),
    /// A zero byte inserted at this offset.
    Insert(usize),
    /// Cut to this length.
    Truncate(usize),
    /// This many zero bytes appended.
    Extend(usize),
    /// The snapshot followed by a copy of itself.
    Doubled,
}

/// The f64 patterns written at every offset: NaN, +inf, -inf, big- and little-endian.
fn patterns() -> [[u8; 8]; 6] {
    let [n, p, m] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
    [
        n.to_be_bytes(),
        p.to_be_bytes(),
        m.to_be_bytes(),
        n.to_le_bytes(),
        p.to_le_bytes(),
        m.to_le_bytes(),
    ]
}

/// Every mutation of a snapshot of `len` bytes: `17 * len + 10` of them.
fn mutations(len: usize) -> Vec<Mutation> {
    let mut all = Vec::new();
    for at in 0..len {
        all.extend(patterns().map(|p| Mutation::Pattern(at, p)));
        all.extend((0..8).map(|bit| Mutation::Flip(at, bit)));
        all.push(Mutation::Delete(at));
        all.push(Mutation::Insert(at));
        all.push(Mutation::Truncate(at));
    }
    all.push(Mutation::Insert(len));
    all.extend((1..=8).map(Mutation::Extend));
    all.push(Mutation::Doubled);
    assert_eq!(all.len(), 17 * len + 10);
    all
}

fn apply(bytes: &[u8], m: Mutation) -> Vec<u8> {
    let mut b = bytes.to_vec();
    match m {
        Mutation::Pattern(at, p) => {
            let end = (at + 8).min(b.len());
            b[at..end].copy_from_slice(&p[..end - at]);
        }
        Mutation::Flip(at, bit) => b[at] ^= 1 << bit,
        Mutation::Delete(at) => {
            b.remove(at);
        }
        Mutation::Insert(at) => b.insert(at, 0),
        Mutation::Truncate(len) => b.truncate(len),
        Mutation::Extend(k) => b.resize(b.len() + k, 0),
        Mutation::Doubled => b.extend_from_slice(bytes),
    }
    b
}

/// The problem an altered snapshot must be refused with: the frame is checked in order (the
/// magic, the declared length, the checksum, the version), so the first part altered names it.
fn expected(original: &[u8], altered: &[u8]) -> &'static str {
    if !altered.starts_with(b"CPDS") {
        "not a snapshot or truncated"
    } else if altered.len() < HEADER + 4 || altered[5..HEADER] != original[5..HEADER] {
        "truncated or trailing bytes"
    } else if altered.len() != original.len() {
        if altered.len() < original.len() {
            "truncated"
        } else {
            "trailing bytes"
        }
    } else {
        "checksum mismatch"
    }
}

/// Whether `problem` is what `expected` named.
fn is(problem: &SnapshotProblem, expected: &str) -> bool {
    use SnapshotProblem::*;
    match expected {
        "not a snapshot or truncated" => matches!(problem, NotASnapshot | Truncated { .. }),
        "truncated or trailing bytes" => matches!(problem, Truncated { .. } | TrailingBytes { .. }),
        "truncated" => matches!(problem, Truncated { .. }),
        "trailing bytes" => matches!(problem, TrailingBytes { .. }),
        "checksum mismatch" => matches!(problem, ChecksumMismatch { .. }),
        _ => unreachable!(),
    }
}

/// Every mutation of `original`'s snapshot refused with the expected problem, `original`
/// untouched; returns how many altered snapshots were tried (those a mutation left equal to
/// the snapshot, e.g. a zero bit pattern written over zeros, restore and are not counted).
fn sweep<T: Snapshot + Clone + PartialEq + core::fmt::Debug>(
    original: &T,
) -> Result<usize, TestCaseError> {
    let before = original.clone();
    let bytes = snapshot::to_bytes(original);
    let mut altered_count = 0;
    for m in mutations(bytes.len()) {
        let altered = apply(&bytes, m);
        if altered == bytes {
            prop_assert_eq!(&snapshot::from_bytes::<T>(&altered).unwrap(), original);
            continue;
        }
        altered_count += 1;
        // As a gateway restores: the detector is replaced only by a snapshot that restores.
        let mut detector = original.clone();
        match snapshot::from_bytes::<T>(&altered) {
            Ok(restored) => {
                detector = restored;
                prop_assert!(false, "{} {m:?} restored: {detector:?}", T::KIND);
            }
            Err(Error::UnreadableSnapshot { kind, problem }) => {
                let want = expected(&bytes, &altered);
                prop_assert_eq!(kind, T::KIND);
                prop_assert!(is(&problem, want), "{m:?}: {problem:?}, not {want}");
            }
            Err(other) => prop_assert!(false, "{m:?}: {other:?}"),
        }
        prop_assert_eq!(&detector, original);
    }
    prop_assert_eq!(original, &before);
    prop_assert_eq!(snapshot::to_bytes(original), bytes);
    Ok(altered_count)
}

/// The four kinds of the sweep fed `n` samples of signal family `family` (the banks the samples
/// as rows of three channels).
fn detectors(family: u64, n: usize, seed: u64) -> (Cusum, Shewhart, Bank, Bank) {
    let x = signal(family, n, &mut Rng::new(seed));
    let cc = CusumConfig::new(0.5, 0.01).unwrap();
    let sc = ShewhartConfig::with_threshold(37, 0.2).unwrap();
    let mut c = Cusum::new(cc);
    let mut s = Shewhart::new(sc).unwrap();
    let mut cb = Bank::from(CusumBank::new(3, cc).unwrap());
    let mut sb = Bank::from(ShewhartBank::new(3, sc).unwrap());
    let (mut alarms, mut channel_alarms) = (Vec::new(), Vec::new());
    c.update_slice(&x, &mut alarms).unwrap();
    s.update_slice(&x, &mut alarms).unwrap();
    let rows = &x[..x.len() / 3 * 3];
    cb.step_many(rows, &mut channel_alarms).unwrap();
    sb.step_many(rows, &mut channel_alarms).unwrap();
    (c, s, cb, sb)
}

fn config() -> ProptestConfig {
    ProptestConfig {
        // Each case tries some 60 000 altered snapshots.
        cases: 8,
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(
            "proptest-regressions/snapshot_corruption.txt",
        ))),
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn every_altered_byte_of_every_snapshot_kind_is_refused(
        family in 0u64..6, n in 0usize..300, seed in any::<u64>()
    ) {
        let (c, s, cb, sb) = detectors(family, n, seed);
        sweep(&c)?;
        sweep(&s)?;
        sweep(&cb)?;
        sweep(&sb)?;
    }
}

/// The sweep on full windows (the case that restored before the checksum), with its numbers.
#[test]
fn the_sweep_on_full_windows_refuses_every_altered_snapshot() {
    let (c, s, cb, sb) = detectors(0, 240, 20_261_128);
    let counts = [
        ("Cusum", snapshot::to_bytes(&c).len(), sweep(&c).unwrap()),
        ("Shewhart", snapshot::to_bytes(&s).len(), sweep(&s).unwrap()),
        (
            "CUSUM bank",
            snapshot::to_bytes(&cb).len(),
            sweep(&cb).unwrap(),
        ),
        (
            "Shewhart bank",
            snapshot::to_bytes(&sb).len(),
            sweep(&sb).unwrap(),
        ),
    ];
    for (name, len, altered) in counts {
        eprintln!("{name}: {len} bytes, {altered} altered snapshots, all refused");
        // Every mutation but the few that leave the bytes as they were.
        assert!(altered > 16 * len, "{name}: {altered} of {}", 17 * len + 10);
    }
}

/// Each problem names itself: the error's message says what is wrong with the bytes.
#[test]
fn each_problem_is_named() {
    let (c, ..) = detectors(3, 50, 9);
    let bytes = snapshot::to_bytes(&c);
    let message = |b: &[u8]| snapshot::from_bytes::<Cusum>(b).unwrap_err().to_string();
    let n = bytes.len();
    let mut altered = bytes.clone();
    altered[n / 2] ^= 0x10;
    let m = message(&altered);
    assert!(
        m.starts_with("unreadable Cusum snapshot: checksum mismatch (CRC-32C stored 0x"),
        "{m}"
    );
    assert_eq!(
        message(&bytes[..n - 1]),
        format!(
            "unreadable Cusum snapshot: truncated: {} bytes of {n}",
            n - 1
        )
    );
    let mut longer = bytes.clone();
    longer.extend_from_slice(b"xyz");
    assert_eq!(
        message(&longer),
        format!(
            "unreadable Cusum snapshot: 3 bytes after its end ({} bytes, the snapshot is {n})",
            n + 3
        )
    );
    assert_eq!(
        message(b"not a snapshot"),
        "unreadable Cusum snapshot: not a snapshot (no snapshot header)"
    );
    // A newer format, intact: its version named (the frame is the same in every format).
    let mut newer = bytes[..n - 4].to_vec();
    newer[4] = 3;
    let crc = snapshot::crc32c(&newer);
    newer.extend_from_slice(&crc.to_le_bytes());
    assert_eq!(
        message(&newer),
        "unreadable Cusum snapshot: unknown format version 3 (this version reads formats 1 and 2)"
    );
    // Another kind, intact: refused after the checksum, naming what it holds.
    let (_, s, ..) = detectors(3, 50, 9);
    let m = message(&snapshot::to_bytes(&s));
    assert_eq!(m, "invalid Cusum snapshot: it holds a Shewhart");
}
