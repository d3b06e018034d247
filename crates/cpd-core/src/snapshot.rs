//! Versioned, checksummed snapshots: a detector's or bank's configuration and full state as
//! bytes (feature `snapshot`; `no_std` + `alloc` compatible).
//!
//! # Format 2 (written by this version)
//!
//! | offset | bytes | field |
//! |---|---|---|
//! | 0 | 4 | magic [`MAGIC`], `b"CPDS"` |
//! | 4 | 1 | format version, [`FORMAT`] (`2`) |
//! | 5 | 8 | total length of the snapshot in bytes, these 17 included, `u64` little-endian |
//! | 13 | n | payload: a CBOR map `{kind, state}` |
//! | 13 + n | 4 | CRC-32C (Castagnoli, [`crc32c`]) of bytes `0..13 + n`, `u32` little-endian |
//!
//! `kind` names the type ([`Snapshot::KIND`]: `"Cusum"`, `"Shewhart"`, `"DetectorBank"`) and
//! `state` is the type's serde form. CBOR keeps field names (clear errors) and every `f64` bit
//! pattern. These are exactly the bytes of the Python package's `snapshot()` / `restore()`
//! (and pickle), so a Rust gateway and Python read each other's snapshots. Later formats keep
//! this frame (magic, version, length, trailing CRC-32C) and change only the payload, so this
//! version names the version of a newer snapshot instead of misreading it.
//!
//! Restoring checks the frame before it decodes anything: the magic, the declared length
//! against the bytes (truncated, or bytes after the end), the checksum, then the version; any
//! problem is an [`Error::UnreadableSnapshot`] naming it ([`SnapshotProblem`]). A truncation,
//! an extension or an altered byte (up to four in a row) is always refused there, whatever the
//! values the altered bytes would decode to (a finite but absurd window sum passes any range
//! check, not the checksum): the length is checked, and a CRC-32C catches every burst of up to
//! 32 altered bits (any other alteration but for a chance of 2^-32). Then the payload is decoded and
//! validated like any deserialized state: the kind, the configuration and every state field
//! (finite values, counters and indices in range); a problem there is an
//! [`Error::InvalidSnapshot`]. Nothing is built until everything passed. Sizes come from the
//! bytes themselves, so a corrupt length cannot make the decoder allocate more than the input
//! holds.
//!
//! # Format 1 (read, never written)
//!
//! Snapshots written before format 2 are a bare CBOR map `{format: 1, kind, state}`, with no
//! checksum. They are still read, validated as before (configuration and every state field),
//! so that saved gateway state, pickles and the live monitor's state files survive an upgrade;
//! a detector restored from one writes format 2 from then on. Without a checksum, a format-1
//! snapshot altered into finite values a detector can reach restores: re-snapshot old files.
//!
//! ```
//! use cpd_core::{snapshot, Cusum, CusumConfig, Error, SnapshotProblem};
//!
//! let mut det = Cusum::new(CusumConfig::new(0.5, 0.01)?);
//! det.update(200.0)?;
//! let bytes = snapshot::to_bytes(&det);
//! assert_eq!((&bytes[..4], bytes[4]), (&b"CPDS"[..], snapshot::FORMAT));
//! let restored: Cusum = snapshot::from_bytes(&bytes)?;
//! assert_eq!(restored, det);
//! let mut altered = bytes.clone();
//! altered[40] ^= 1;
//! assert!(matches!(
//!     snapshot::from_bytes::<Cusum>(&altered),
//!     Err(Error::UnreadableSnapshot { problem: SnapshotProblem::ChecksumMismatch { .. }, .. })
//! ));
//! assert!(snapshot::from_bytes::<Cusum>(&bytes[..bytes.len() / 2]).is_err());
//! # Ok::<(), cpd_core::Error>(())
//! ```

use alloc::format;
use alloc::string::{String, ToString};
use alloc::vec::Vec;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::error::SnapshotProblem;
use crate::{Bank, Cusum, Error, Shewhart};

/// The format version written by this version of the crate (the byte after [`MAGIC`]).
pub const FORMAT: u8 = 2;

/// The first four bytes of every snapshot of format 2 or later.
pub const MAGIC: [u8; 4] = *b"CPDS";

/// Bytes before the payload: magic, version, length.
const HEADER: usize = 13;

/// Bytes of the trailing checksum.
const CHECKSUM: usize = 4;

/// How every format-1 snapshot begins: a CBOR map of three entries, the text `"format"`, the
/// unsigned integer 1. No format-2 snapshot altered in one byte begins so.
const FORMAT1_PREFIX: [u8; 9] = [0xA3, 0x66, b'f', b'o', b'r', b'm', b'a', b't', 0x01];

/// A type that can be snapshotted: its serde form plus the `kind` tag of the payload.
pub trait Snapshot: Serialize + DeserializeOwned {
    /// The tag written in the payload and checked when decoding.
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
struct Payload<'a, T> {
    kind: &'a str,
    state: &'a T,
}

#[derive(Deserialize)]
struct OwnedPayload {
    kind: String,
    state: ciborium::Value,
}

#[derive(Deserialize)]
struct Format1 {
    format: u32,
    kind: String,
    state: ciborium::Value,
}

/// The CRC-32C table: reflected Castagnoli polynomial `0x82F63B78`, one entry per byte value.
const CRC32C_TABLE: [u32; 256] = {
    let mut table = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut crc = i as u32;
        let mut bit = 0;
        while bit < 8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0x82F6_3B78
            } else {
                crc >> 1
            };
            bit += 1;
        }
        table[i] = crc;
        i += 1;
    }
    table
};

/// The CRC-32C (Castagnoli; iSCSI, ext4, SCTP) of `bytes`: the checksum that ends every
/// snapshot. `crc32c(b"123456789") == 0xE306_9283`.
pub fn crc32c(bytes: &[u8]) -> u32 {
    !bytes.iter().fold(!0u32, |crc, &b| {
        CRC32C_TABLE[((crc ^ u32::from(b)) & 0xFF) as usize] ^ (crc >> 8)
    })
}

/// The snapshot bytes of `value` (format [`FORMAT`], see the module docs for the layout).
pub fn to_bytes<T: Snapshot>(value: &T) -> Vec<u8> {
    let mut bytes = Vec::new();
    bytes.extend_from_slice(&MAGIC);
    bytes.push(FORMAT);
    bytes.extend_from_slice(&[0; 8]);
    let payload = Payload {
        kind: T::KIND,
        state: value,
    };
    // Writing plain data into a Vec cannot fail.
    if ciborium::into_writer(&payload, &mut bytes).is_err() {
        unreachable!("detector state is plain data and always serializes");
    }
    let len = (bytes.len() + CHECKSUM) as u64;
    bytes[5..HEADER].copy_from_slice(&len.to_le_bytes());
    let crc = crc32c(&bytes);
    bytes.extend_from_slice(&crc.to_le_bytes());
    bytes
}

/// Decodes bytes written by [`to_bytes`] (or by the Python package) for the same type, or a
/// format-1 snapshot written before format 2.
///
/// Errors with [`Error::UnreadableSnapshot`] when the frame is wrong (not a snapshot,
/// truncated, bytes after its end, a checksum mismatch, an unknown version), and with
/// [`Error::InvalidSnapshot`] when the payload is of another kind or holds an invalid
/// configuration or state.
pub fn from_bytes<T: Snapshot>(bytes: &[u8]) -> Result<T, Error> {
    let unreadable = |problem| Error::UnreadableSnapshot {
        kind: T::KIND,
        problem,
    };
    if !bytes.starts_with(&MAGIC) {
        if bytes.starts_with(&FORMAT1_PREFIX) {
            return from_format1(bytes);
        }
        return Err(unreadable(if MAGIC.starts_with(bytes) {
            SnapshotProblem::Truncated {
                len: bytes.len(),
                expected: (HEADER + CHECKSUM) as u64,
            }
        } else {
            SnapshotProblem::NotASnapshot
        }));
    }
    let len = bytes.len();
    if len < HEADER + CHECKSUM {
        return Err(unreadable(SnapshotProblem::Truncated {
            len,
            expected: (HEADER + CHECKSUM) as u64,
        }));
    }
    let expected = u64::from_le_bytes(bytes[5..HEADER].try_into().expect("8 bytes"));
    if (len as u64) < expected {
        return Err(unreadable(SnapshotProblem::Truncated { len, expected }));
    }
    if len as u64 > expected {
        return Err(unreadable(SnapshotProblem::TrailingBytes { len, expected }));
    }
    let (framed, trailer) = bytes.split_at(len - CHECKSUM);
    let stored = u32::from_le_bytes(trailer.try_into().expect("4 bytes"));
    let computed = crc32c(framed);
    if stored != computed {
        return Err(unreadable(SnapshotProblem::ChecksumMismatch {
            stored,
            computed,
        }));
    }
    if bytes[4] != FORMAT {
        return Err(unreadable(SnapshotProblem::UnknownVersion {
            version: bytes[4],
        }));
    }
    let payload: OwnedPayload = decode_all::<T, _>(&framed[HEADER..])?;
    into_state(payload.kind, payload.state)
}

/// A format-1 snapshot: the bare CBOR map `{format: 1, kind, state}`, nothing after it.
fn from_format1<T: Snapshot>(bytes: &[u8]) -> Result<T, Error> {
    let envelope: Format1 = decode_all::<T, _>(bytes)?;
    if envelope.format != 1 {
        return Err(invalid::<T>(format!(
            "format {}, this version reads formats 1 and {FORMAT}",
            envelope.format
        )));
    }
    into_state(envelope.kind, envelope.state)
}

/// One CBOR item that takes up all of `bytes`.
fn decode_all<T: Snapshot, D: DeserializeOwned>(bytes: &[u8]) -> Result<D, Error> {
    let mut rest = bytes;
    let value = ciborium::from_reader(&mut rest).map_err(|e| invalid::<T>(e.to_string()))?;
    if !rest.is_empty() {
        return Err(invalid::<T>(format!(
            "{} bytes after the end of its CBOR payload",
            rest.len()
        )));
    }
    Ok(value)
}

/// The state of the payload's `kind` and `state`, decoded and validated.
fn into_state<T: Snapshot>(kind: String, state: ciborium::Value) -> Result<T, Error> {
    if kind != T::KIND {
        return Err(invalid::<T>(format!("it holds a {kind}")));
    }
    state
        .deserialized()
        .map_err(|e| invalid::<T>(e.to_string()))
}

fn invalid<T: Snapshot>(detail: String) -> Error {
    Error::InvalidSnapshot {
        kind: T::KIND,
        detail,
    }
}

#[cfg(test)]
mod tests {
    use super::crc32c;

    #[test]
    fn crc32c_matches_the_standard_check_values() {
        // The check value of the CRC-32C catalogue entry (Castagnoli, reflected, xor-out ~0).
        assert_eq!(crc32c(b"123456789"), 0xE306_9283);
        assert_eq!(crc32c(b""), 0);
        // RFC 3720 (iSCSI), appendix B.4: 32 bytes of zeros, of ones, ascending.
        assert_eq!(crc32c(&[0u8; 32]), 0x8A91_36AA);
        assert_eq!(crc32c(&[0xFFu8; 32]), 0x62A8_AB43);
        let ascending: [u8; 32] = core::array::from_fn(|i| i as u8);
        assert_eq!(crc32c(&ascending), 0x46DD_794E);
    }
}
