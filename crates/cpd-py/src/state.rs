//! Snapshots: a detector's configuration and state as bytes (JSON of the core's serde form),
//! used by `snapshot()`/`restore()`, pickle and copy.

use pyo3::PyResult;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::errors::input_err;

/// Bumped when the snapshot layout changes incompatibly.
const FORMAT: u32 = 1;

#[derive(Serialize)]
struct Envelope<'a, T> {
    format: u32,
    kind: &'a str,
    state: &'a T,
}

#[derive(Deserialize)]
struct OwnedEnvelope {
    format: u32,
    kind: String,
    state: serde_json::Value,
}

/// Serializes `state`, tagged with the detector `kind`.
pub(crate) fn encode<T: Serialize>(kind: &str, state: &T) -> Vec<u8> {
    serde_json::to_vec(&Envelope {
        format: FORMAT,
        kind,
        state,
    })
    .expect("detector state is plain data and always serializes")
}

/// Deserializes a snapshot made by [`encode`] for the same `kind`; `InputError` otherwise.
pub(crate) fn decode<T: DeserializeOwned>(kind: &str, bytes: &[u8]) -> PyResult<T> {
    let envelope: OwnedEnvelope = serde_json::from_slice(bytes)
        .map_err(|e| input_err(format!("not a valid {kind} snapshot: {e}")))?;
    if envelope.format != FORMAT {
        return Err(input_err(format!(
            "{kind} snapshot has format {}, this version reads format {FORMAT}",
            envelope.format
        )));
    }
    if envelope.kind != kind {
        return Err(input_err(format!(
            "snapshot is of a {}, not of a {kind}",
            envelope.kind
        )));
    }
    serde_json::from_value(envelope.state)
        .map_err(|e| input_err(format!("not a valid {kind} snapshot: {e}")))
}
