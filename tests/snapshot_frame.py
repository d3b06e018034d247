"""The frame of a detector snapshot (format 2, see crates/cpd-core/README.md), for tests that
edit what lies behind the checksum: the magic ``CPDS``, a version byte, the total length
(``u64``, little-endian), the CBOR payload, a CRC-32C of everything before it (``u32``,
little-endian). A pure-Python CRC-32C, the oracle of the Rust one."""

from __future__ import annotations

import struct

MAGIC = b"CPDS"
VERSION = 2
HEADER = 13  # magic, version, length


def crc32c(data: bytes) -> int:
    """CRC-32C (Castagnoli, reflected polynomial 0x82F63B78), bit by bit."""
    crc = 0xFFFFFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ (0x82F63B78 if crc & 1 else 0)
    return crc ^ 0xFFFFFFFF


def payload(snapshot: bytes) -> bytes:
    """The CBOR payload of a format-2 snapshot, its frame checked."""
    assert snapshot[:4] == MAGIC and snapshot[4] == VERSION
    assert struct.unpack("<Q", snapshot[5:HEADER])[0] == len(snapshot)
    assert struct.unpack("<I", snapshot[-4:])[0] == crc32c(snapshot[:-4])
    return snapshot[HEADER:-4]


def seal(cbor: bytes) -> bytes:
    """A CBOR payload framed as a format-2 snapshot with its valid length and checksum."""
    head = MAGIC + bytes([VERSION]) + struct.pack("<Q", HEADER + len(cbor) + 4)
    return head + cbor + struct.pack("<I", crc32c(head + cbor))


def format1_of(snapshot: bytes) -> bytes:
    """The format-1 snapshot of a format-2 one, as the package wrote it before format 2: the
    payload ``{kind, state}`` (a CBOR map of two entries) with ``format: 1`` put first."""
    body = payload(snapshot)
    assert body[0] == 0xA2, "a CBOR map of two entries"
    return b"\xa3\x66format\x01" + body[1:]
