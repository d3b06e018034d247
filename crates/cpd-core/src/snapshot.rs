//! Versioned snapshots: a detector's or bank's configuration and full state as bytes
//! (feature `snapshot`; `no_std` + `alloc` compatible).
//!
//! The bytes are a CBOR map `{format, kind, state}`: `format` is [`FORMAT`], `kind` names the
//! type ([`Snapshot::KIND`]: `"Cusum"`, `"Shewhart"`, `"DetectorBank"`) and `state` is the
//! type's serde form. CBOR keeps field names (clear errors) and every `f64` bit pattern. These
//! are exactly the bytes of the Python package's `snapshot()` / `restore()` (and pickle), so a
//! Rust gateway and Python read each other's snapshots.
//!
//! Decoding validates everything: the envelope, the kind, the configuration and every state
//! field (finite values, counters and indices in range); any problem is an
//! [`Error::InvalidSnapshot`] (an input error) and nothing is built. Sizes come from the bytes
//! themselves, so a corrupt length cannot make the decoder allocate more than the input holds.
//!
//! ```
//! use cpd_core::{snapshot, Cusum, CusumConfig};
//!
//! let mut det = Cusum::new(CusumConfig::new(0.5, 0.01)?);
//! det.update(200.0)?;
//! let bytes = snapshot::to_bytes(&det);
//! let restored: Cusum = snapshot::from_bytes(&bytes)?;
//! assert_eq!(restored, det);
//! assert!(snapshot::from_bytes::<Cusum>(&bytes[..bytes.len() / 2]).is_err());
//! # Ok::<(), cpd_core::Error>(())
//! ```

use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec::Vec;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::{Bank, Cusum, Error, Shewhart};

/// The snapshot layout written by this version (bumped, with the old one still read, when the
/// state's serde form changes).
pub const FORMAT: u32 = 1;

/// A type that can be snapshotted: its serde form plus the `kind` tag of the envelope.
pub trait Snapshot: Serialize + DeserializeOwned {
    /// The tag written in the envelope and checked when decoding.
    const KIND: &'static str;
}

impl Snapshot for Cusum {
    const KIND: &'static str = "Cusum";
}

impl Snapshot for Shewhart {
    const KIND: &'static str = "Shewhart";
}

impl Snapshot for Bank {
    const KIND: &'static str = "DetectorBank";
}

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
    state: ciborium::Value,
}

/// The snapshot bytes of `value` (format [`FORMAT`]).
pub fn to_bytes<T: Snapshot>(value: &T) -> Vec<u8> {
    let mut bytes = Vec::new();
    let envelope = Envelope {
        format: FORMAT,
        kind: T::KIND,
        state: value,
    };
    // Writing plain data into a Vec cannot fail.
    if ciborium::into_writer(&envelope, &mut bytes).is_err() {
        unreachable!("detector state is plain data and always serializes");
    }
    bytes
}

/// Decodes bytes written by [`to_bytes`] (or by the Python package) for the same type.
///
/// Errors with [`Error::InvalidSnapshot`] when the bytes are not a snapshot, are of another
/// kind or format, or hold an invalid configuration or state.
pub fn from_bytes<T: Snapshot>(bytes: &[u8]) -> Result<T, Error> {
    let invalid = |detail: String| Error::InvalidSnapshot {
        kind: T::KIND,
        detail,
    };
    let envelope: OwnedEnvelope =
        ciborium::from_reader(bytes).map_err(|e| invalid(e.to_string()))?;
    if envelope.format != FORMAT {
        return Err(invalid(format!(
            "format {}, this version reads format {FORMAT}",
            envelope.format
        )));
    }
    if envelope.kind != T::KIND {
        return Err(invalid(format!("it holds a {}", envelope.kind)));
    }
    envelope
        .state
        .deserialized()
        .map_err(|e| invalid(e.to_string()))
}
