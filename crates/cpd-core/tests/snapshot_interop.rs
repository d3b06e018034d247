//! Snapshots cross the language boundary both ways, and old snapshots still restore (fixtures
//! in `tests/data/snapshots/`, see `gen_snapshots.py` there):
//! - the `py_*.cbor` files, written by the Python package, decode here into detectors equal to
//!   ones fed the same samples in Rust, which then raise the same alarms, and Rust re-encodes
//!   them to the very same bytes (format 2);
//! - the `rust_*.cbor` files are what this test writes (`CPD_WRITE_SNAPSHOTS=1`); without the
//!   variable it checks that the committed files are still exactly what Rust writes. Python's
//!   `tests/test_snapshot_interop.py` restores them;
//! - format-1 snapshots (no header, no checksum: the bare CBOR map `{format: 1, kind, state}`,
//!   what the Python package wrote before format 2) are made here from the `py_*.cbor` payloads
//!   (`format1_of`, byte for byte what that package wrote): they still restore into the same
//!   detectors, which write format 2 from then on.

use std::path::PathBuf;

use cpd_core::snapshot::{self, Snapshot};
use cpd_core::{
    Alarm, Bank, ChannelAlarm, Cusum, CusumBank, CusumConfig, Shewhart, ShewhartBank,
    ShewhartConfig,
};
use serde::Deserialize;

#[derive(Deserialize)]
struct CusumParams {
    threshold: f64,
    drift: f64,
}

#[derive(Deserialize)]
struct ShewhartParams {
    window: usize,
    threshold: f64,
}

#[derive(Deserialize)]
struct Params {
    cusum: CusumParams,
    shewhart: ShewhartParams,
}

#[derive(Deserialize)]
struct Trace {
    channels: usize,
    py_cut: usize,
    rust_cut: usize,
    config: Params,
    rows: Vec<Vec<f64>>,
}

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/snapshots")
}

fn trace() -> Trace {
    let text = std::fs::read_to_string(dir().join("trace.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Fresh detectors with the fixture's configurations (Shewhart: `sigma` = `threshold`).
struct Fresh {
    cusum: Cusum,
    shewhart: Shewhart,
    bank_cusum: Bank,
    bank_shewhart: Bank,
}

impl Fresh {
    fn new(t: &Trace) -> Self {
        let cc = CusumConfig::new(t.config.cusum.threshold, t.config.cusum.drift).unwrap();
        let s = &t.config.shewhart;
        let sc = ShewhartConfig::with_threshold(s.window, s.threshold).unwrap();
        Fresh {
            cusum: Cusum::new(cc),
            shewhart: Shewhart::new(sc).unwrap(),
            bank_cusum: CusumBank::new(t.channels, cc).unwrap().into(),
            bank_shewhart: ShewhartBank::new(t.channels, sc).unwrap().into(),
        }
    }

    /// Feeds rows `range` (single detectors: channel 1); returns every alarm raised.
    fn feed(&mut self, t: &Trace, range: std::ops::Range<usize>) -> Fed {
        let rows = &t.rows[range];
        let column: Vec<f64> = rows.iter().map(|r| r[1]).collect();
        let matrix: Vec<f64> = rows.iter().flatten().copied().collect();
        let mut fed = Fed::default();
        self.cusum.update_slice(&column, &mut fed.cusum).unwrap();
        self.shewhart
            .update_slice(&column, &mut fed.shewhart)
            .unwrap();
        self.bank_cusum
            .step_many(&matrix, &mut fed.bank_cusum)
            .unwrap();
        self.bank_shewhart
            .step_many(&matrix, &mut fed.bank_shewhart)
            .unwrap();
        fed
    }
}

#[derive(Default, Debug, PartialEq)]
struct Fed {
    cusum: Vec<Alarm>,
    shewhart: Vec<Alarm>,
    bank_cusum: Vec<ChannelAlarm>,
    bank_shewhart: Vec<ChannelAlarm>,
}

/// The format-1 snapshot of a format-2 one: its payload `{kind, state}` (a CBOR map of two
/// entries) with `format: 1` put first, as the Python package wrote it before format 2.
fn format1_of(format2: &[u8]) -> Vec<u8> {
    let payload = &format2[13..format2.len() - 4];
    assert_eq!(payload[0], 0xa2, "a CBOR map of two entries");
    let mut old = b"\xa3\x66format\x01".to_vec();
    old.extend_from_slice(&payload[1..]);
    old
}

/// A format-1 snapshot made from the format-2 fixture `py_NAME.cbor`, and what it restores to.
fn read_format1<T: Snapshot>(name: &str) -> (Vec<u8>, T) {
    let bytes = format1_of(&std::fs::read(dir().join(format!("py_{name}.cbor"))).unwrap());
    let value = snapshot::from_bytes(&bytes).unwrap();
    (bytes, value)
}

fn read<T: Snapshot>(name: &str) -> (Vec<u8>, T) {
    let bytes = std::fs::read(dir().join(name)).unwrap();
    let value = snapshot::from_bytes(&bytes).unwrap();
    (bytes, value)
}

#[test]
fn python_snapshots_restore_in_rust_and_continue_identically() {
    let t = trace();
    let n = t.rows.len();
    let mut fed = Fresh::new(&t);
    fed.feed(&t, 0..t.py_cut);
    let (b_c, cusum) = read::<Cusum>("py_cusum.cbor");
    let (b_s, shewhart) = read::<Shewhart>("py_shewhart.cbor");
    let (b_bc, bank_cusum) = read::<Bank>("py_bank_cusum.cbor");
    let (b_bs, bank_shewhart) = read::<Bank>("py_bank_shewhart.cbor");
    // Same state as Rust fed the same samples, and the same bytes when Rust writes it.
    assert_eq!(cusum, fed.cusum);
    assert_eq!(shewhart, fed.shewhart);
    assert_eq!(bank_cusum, fed.bank_cusum);
    assert_eq!(bank_shewhart, fed.bank_shewhart);
    assert_eq!(snapshot::to_bytes(&fed.cusum), b_c);
    assert_eq!(snapshot::to_bytes(&fed.shewhart), b_s);
    assert_eq!(snapshot::to_bytes(&fed.bank_cusum), b_bc);
    assert_eq!(snapshot::to_bytes(&fed.bank_shewhart), b_bs);
    // The restored detectors raise exactly the alarms of the never-stopped ones.
    let mut restored = Fresh {
        cusum,
        shewhart,
        bank_cusum,
        bank_shewhart,
    };
    let want = fed.feed(&t, t.py_cut..n);
    let got = restored.feed(&t, t.py_cut..n);
    assert_eq!(got, want);
    // The tail holds the trace's changes, so the comparison covers alarms.
    for alarms in [want.cusum.len(), want.shewhart.len()] {
        assert!(alarms > 0, "{want:?}");
    }
    assert!(want.bank_cusum.iter().any(|a| a.channel == 2), "{want:?}");
    assert!(
        want.bank_shewhart.iter().any(|a| a.channel == 2),
        "{want:?}"
    );
}

#[test]
fn format1_snapshots_still_restore_and_are_written_back_as_format_2() {
    let t = trace();
    let mut fed = Fresh::new(&t);
    fed.feed(&t, 0..t.py_cut);
    let (b_c, cusum) = read_format1::<Cusum>("cusum");
    let (b_s, shewhart) = read_format1::<Shewhart>("shewhart");
    let (b_bc, bank_cusum) = read_format1::<Bank>("bank_cusum");
    let (b_bs, bank_shewhart) = read_format1::<Bank>("bank_shewhart");
    for old in [&b_c, &b_s, &b_bc, &b_bs] {
        // The format-1 envelope `{format: 1, kind, state}`, not the format-2 frame.
        assert_eq!(old[..9], *b"\xa3\x66format\x01");
    }
    assert_eq!(cusum, fed.cusum);
    assert_eq!(shewhart, fed.shewhart);
    assert_eq!(bank_cusum, fed.bank_cusum);
    assert_eq!(bank_shewhart, fed.bank_shewhart);
    // Written back in format 2: the bytes of the Python package's snapshots of the same state.
    assert_eq!(snapshot::to_bytes(&cusum), read::<Cusum>("py_cusum.cbor").0);
    assert_eq!(snapshot::to_bytes(&bank_shewhart)[..4], snapshot::MAGIC);
    let mut restored = Fresh {
        cusum,
        shewhart,
        bank_cusum,
        bank_shewhart,
    };
    let n = t.rows.len();
    assert_eq!(restored.feed(&t, t.py_cut..n), fed.feed(&t, t.py_cut..n));
    // Format 1 is read as it always was: the same validation, nothing after the CBOR map.
    let mut longer = b_c.clone();
    longer.push(0);
    let err = snapshot::from_bytes::<Cusum>(&longer).unwrap_err();
    assert!(err.to_string().contains("1 bytes after the end"), "{err}");
    assert!(snapshot::from_bytes::<Cusum>(&b_c[..b_c.len() - 1]).is_err());
    assert!(snapshot::from_bytes::<Cusum>(&b_s).is_err());
}

#[test]
fn rust_snapshot_fixtures_are_what_rust_writes() {
    let t = trace();
    let mut fed = Fresh::new(&t);
    fed.feed(&t, 0..t.rust_cut);
    let files = [
        ("rust_cusum.cbor", snapshot::to_bytes(&fed.cusum)),
        ("rust_shewhart.cbor", snapshot::to_bytes(&fed.shewhart)),
        ("rust_bank_cusum.cbor", snapshot::to_bytes(&fed.bank_cusum)),
        (
            "rust_bank_shewhart.cbor",
            snapshot::to_bytes(&fed.bank_shewhart),
        ),
    ];
    let write = std::env::var_os("CPD_WRITE_SNAPSHOTS").is_some_and(|v| v == "1");
    for (name, bytes) in files {
        let path = dir().join(name);
        if write {
            std::fs::write(&path, &bytes).unwrap();
        }
        let committed = std::fs::read(&path).unwrap();
        assert!(
            committed == bytes,
            "{name} differs from what Rust writes: rerun with CPD_WRITE_SNAPSHOTS=1"
        );
    }
}
