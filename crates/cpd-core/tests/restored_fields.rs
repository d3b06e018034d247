//! A restored state is held to what a detector can reach: a NaN or an infinity written into
//! any float field of any snapshot kind (single CUSUM, single Shewhart, both banks) is refused
//! with an error naming the field, and so are finite values out of a field's range.
//!
//! The snapshots' payloads are decoded to CBOR values, every float found by walking them
//! (configs, sums, samples, rings, the compensations of the running sums), each one replaced in
//! turn, and the payload re-encoded and sealed with a valid checksum (the field validation is
//! what a snapshot written with bad values, not one altered later, meets): the test follows the
//! serde form, whatever fields it grows.

mod common;

use ciborium::Value;
use common::{payload, seal, snapshots};
use cpd_core::snapshot::{self, Snapshot};
use cpd_core::{Bank, Cusum, Error, Shewhart, ShewhartBank, ShewhartConfig};

/// One step of a path into a CBOR value: a map key or an array index.
#[derive(Debug, Clone)]
enum Step {
    Key(String),
    At(usize),
}

/// The paths of every float in `v`.
fn floats(v: &Value, path: &mut Vec<Step>, out: &mut Vec<Vec<Step>>) {
    match v {
        Value::Float(_) => out.push(path.clone()),
        Value::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                path.push(Step::At(i));
                floats(item, path, out);
                path.pop();
            }
        }
        Value::Map(entries) => {
            for (k, item) in entries {
                path.push(Step::Key(k.as_text().expect("text keys").to_string()));
                floats(item, path, out);
                path.pop();
            }
        }
        _ => {}
    }
}

/// The value at `path` in `v`.
fn at<'a>(v: &'a mut Value, path: &[Step]) -> &'a mut Value {
    path.iter().fold(v, |v, step| match (v, step) {
        (Value::Array(items), Step::At(i)) => &mut items[*i],
        (Value::Map(entries), Step::Key(k)) => entries
            .iter_mut()
            .find(|(key, _)| key.as_text() == Some(k))
            .map(|(_, item)| item)
            .expect("key on the path"),
        _ => unreachable!("the path was read from this value"),
    })
}

/// The field a path ends in: its last map key.
fn field(path: &[Step]) -> &str {
    path.iter()
        .rev()
        .find_map(|s| match s {
            Step::Key(k) => Some(k.as_str()),
            Step::At(_) => None,
        })
        .expect("a field")
}

/// The CBOR value of a snapshot's payload.
fn value(bytes: &[u8]) -> Value {
    ciborium::from_reader(payload(bytes)).unwrap()
}

/// Snapshot `bytes` with the float at `path` replaced by `x`, sealed with a valid checksum.
fn with_float(bytes: &[u8], path: &[Step], x: f64) -> Vec<u8> {
    let mut v = value(bytes);
    *at(&mut v, path) = Value::Float(x);
    let mut out = Vec::new();
    ciborium::into_writer(&v, &mut out).unwrap();
    seal(&out)
}

fn restore(kind: &str, bytes: &[u8]) -> Result<(), Error> {
    match kind {
        "Cusum" => snapshot::from_bytes::<Cusum>(bytes).map(drop),
        "Shewhart" => snapshot::from_bytes::<Shewhart>(bytes).map(drop),
        _ => snapshot::from_bytes::<Bank>(bytes).map(drop),
    }
}

#[test]
fn a_non_finite_value_in_any_float_field_of_any_snapshot_is_refused_by_name() {
    let mut fields_seen = std::collections::BTreeSet::new();
    for (n, seed) in [(0usize, 1u64), (3, 2), (9, 3), (2_500, 4), (2_501, 5)] {
        for (kind, bytes) in snapshots(seed, n) {
            restore(kind, &bytes).expect("a reached state restores");
            let v = value(&bytes);
            let mut paths = Vec::new();
            floats(&v, &mut Vec::new(), &mut paths);
            assert!(!paths.is_empty());
            for path in &paths {
                fields_seen.insert(format!("{kind}.{}", field(path)));
                for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                    let edited = with_float(&bytes, path, bad);
                    let err = restore(kind, &edited).expect_err(&format!(
                        "{kind} after {n} samples restored with {bad} at {path:?}"
                    ));
                    let text = err.to_string();
                    assert!(
                        text.contains(&format!("`{}`", field(path))),
                        "{kind} {path:?} = {bad}: {text}"
                    );
                }
            }
        }
    }
    // Every float field of every kind was edited (the walk found them all).
    for f in [
        "Cusum.threshold",
        "Cusum.drift",
        "Cusum.x_prev",
        "Cusum.gp",
        "Cusum.gn",
        "Cusum.gp_real",
        "Cusum.gn_real",
        "Cusum.x_tap",
        "Cusum.x_tan",
        "Shewhart.sigma",
        "Shewhart.threshold",
        "Shewhart.reference",
        "Shewhart.s1",
        "Shewhart.c1",
        "Shewhart.s2",
        "Shewhart.c2",
        "Shewhart.ring",
        "CusumBank.gp_real",
        "CusumBank.x_tan",
        "ShewhartBank.reference",
        "ShewhartBank.c2",
        "ShewhartBank.ring",
    ] {
        assert!(fields_seen.contains(f), "{f} not edited: {fields_seen:?}");
    }
}

#[test]
fn finite_values_no_detector_reaches_are_refused_by_name() {
    for (kind, bytes) in snapshots(7, 40) {
        let v = value(&bytes);
        let mut paths = Vec::new();
        floats(&v, &mut Vec::new(), &mut paths);
        for path in &paths {
            let name = field(path);
            // A sample field beyond the range no detector takes; a negative drift sum; a real
            // sum above the threshold (0.5).
            let bad = match name {
                "x_prev" | "x_tap" | "x_tan" | "ring" | "reference" => 1e300,
                "gp" | "gn" => -1e-9,
                "gp_real" | "gn_real" => 0.75,
                _ => continue,
            };
            let err = restore(kind, &with_float(&bytes, path, bad)).unwrap_err();
            let text = err.to_string();
            assert!(
                text.contains(&format!("invalid state field `{name}`")),
                "{kind} {path:?}: {text}"
            );
        }
    }
}

#[test]
fn an_invalid_state_error_names_the_channel_and_the_value() {
    let bank = ShewhartBank::new(3, ShewhartConfig::new(4, 1.0, 0.1).unwrap()).unwrap();
    let mut v = serde_json::to_value(&bank).unwrap();
    v["reference"][1] = serde_json::json!(-1e200);
    let err = serde_json::from_value::<ShewhartBank>(v)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("invalid state field `reference`[1] = -1e200: must be a sample"),
        "{err}"
    );
    let bytes = snapshot::to_bytes(&Bank::from(bank));
    let v = value(&bytes);
    let mut paths = Vec::new();
    floats(&v, &mut Vec::new(), &mut paths);
    let s2 = paths.iter().find(|p| field(p) == "s2").unwrap();
    match snapshot::from_bytes::<Bank>(&with_float(&bytes, s2, f64::NAN)) {
        Err(Error::InvalidSnapshot { kind, detail }) => {
            assert_eq!(kind, Bank::KIND);
            assert!(detail.contains("`s2`[0] = NaN: must be finite"), "{detail}");
        }
        other => panic!("{other:?}"),
    }
}
