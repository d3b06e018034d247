//! `detect_cusum` / `detect_shewhart` against outputs generated from TSNet 0.3.1 and NumPy
//! by `tests/data/gen_golden.py` (bit-exact comparisons).

use cpd_core::{detect_cusum, detect_shewhart};
use serde_json::Value;

fn load(name: &str) -> Value {
    let path = format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    serde_json::from_str(&text).expect("golden JSON")
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_f64().unwrap())
        .collect()
}

fn indices(v: &Value) -> Vec<usize> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_u64().unwrap() as usize)
        .collect()
}

#[test]
fn detect_cusum_matches_tsnet() {
    let golden = load("cusum_golden.json");
    let cases = golden["cases"].as_array().unwrap();
    assert!(cases.len() > 100);
    let mut branches = std::collections::BTreeSet::new();
    for case in cases {
        let name = case["name"].as_str().unwrap();
        let x = floats(&case["x"]);
        let ending = case["ending"].as_bool().unwrap();
        let got = detect_cusum(
            &x,
            case["threshold"].as_f64().unwrap(),
            case["drift"].as_f64().unwrap(),
            ending,
        )
        .unwrap();
        let ctx = format!("case {name} ending={ending}");
        assert_eq!(got.start, indices(&case["start"]), "start, {ctx}");
        assert_eq!(got.end, indices(&case["end"]), "end, {ctx}");
        let want_amp = floats(&case["amplitude"]);
        assert_eq!(got.amplitude.len(), want_amp.len(), "amplitude, {ctx}");
        for (g, w) in got.amplitude.iter().zip(&want_amp) {
            assert_eq!(g.to_bits(), w.to_bits(), "amplitude {g} vs {w}, {ctx}");
        }
        for b in case["branches"].as_array().unwrap() {
            branches.insert(b.as_str().unwrap().to_owned());
        }
    }
    // The golden data exercises every branch of TSNet's `ending` post-processing.
    for b in [
        "no_alarm",
        "equal",
        "fewer_starts",
        "more_starts",
        "wrap_minus_one",
        "intercalated",
    ] {
        assert!(branches.contains(b), "golden data misses branch {b}");
    }
}

#[test]
fn detect_shewhart_matches_numpy_algorithm_2() {
    let golden = load("shewhart_golden.json");
    let cases = golden["cases"].as_array().unwrap();
    assert!(cases.len() > 100);
    let mut alarms = 0;
    for (k, case) in cases.iter().enumerate() {
        let x = floats(&case["x"]);
        let got = detect_shewhart(
            &x,
            case["sigma"].as_f64().unwrap(),
            case["threshold"].as_f64().unwrap(),
        )
        .unwrap();
        assert_eq!(got.index, indices(&case["index"]), "case {k}");
        let want_amp = floats(&case["amplitude"]);
        for (g, w) in got.amplitude.iter().zip(&want_amp) {
            assert_eq!(g.to_bits(), w.to_bits(), "case {k}: amplitude {g} vs {w}");
        }
        alarms += got.index.len();
    }
    assert!(
        alarms > 0,
        "golden data should contain out-of-control samples"
    );
}
