//! The events metadata a PX4 log embeds: multi info `metadata_events` (an xz stream, split
//! over continued `M` messages), checked against info `metadata_events_sha256` (the SHA-256
//! of the compressed bytes), decompressed within limits, and read as
//! [`EventDefinitions`].

use std::io::Read;

use sha2::Digest;

use super::definitions::{DefinitionsError, EventDefinitions};
use crate::Value;
use crate::read::Metadata;

/// The multi info key of the compressed metadata.
pub const METADATA_KEY: &str = "metadata_events";
/// The info key of its SHA-256.
pub const SHA256_KEY: &str = "metadata_events_sha256";
/// Most bytes the metadata may decompress to (PX4's is about 165 KB).
pub const MAX_JSON_BYTES: u64 = 64 << 20;
/// Most memory the xz decoder may take, KiB (PX4 compresses with a 64 MiB dictionary).
const MAX_XZ_KIB: u32 = 128 * 1024;

/// What the log's `metadata_events_sha256` says of its metadata.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verification {
    /// The digest matches.
    Matches,
    /// The log has no digest to check.
    NoDigest,
    /// The digest differs: the metadata may not be the firmware's (it is read anyway, as
    /// PX4's tools read it).
    Mismatch {
        /// What the log says.
        expected: String,
        /// The digest of the metadata's bytes.
        actual: String,
    },
}

/// The decoded events metadata of a log.
#[derive(Debug, Clone)]
pub struct EventsMetadata {
    /// The event definitions.
    pub definitions: EventDefinitions,
    /// Whether the digest checked.
    pub verification: Verification,
    /// Bytes of the compressed metadata.
    pub compressed_len: usize,
    /// Bytes of its JSON.
    pub json_len: usize,
}

/// Why a log's events metadata could not be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MetadataError {
    /// The log has no `metadata_events` multi info.
    #[error("the log has no events metadata (multi info `metadata_events`)")]
    Missing,
    /// The multi info is not bytes.
    #[error("multi info `metadata_events` is not an array of bytes")]
    NotBytes,
    /// The xz stream is damaged or cut short.
    #[error("events metadata: the xz data ({len} bytes) does not decompress: {source}")]
    Xz {
        /// Bytes of compressed data.
        len: usize,
        /// The decoder's error.
        source: std::io::Error,
    },
    /// It decompresses to more than [`MAX_JSON_BYTES`].
    #[error("events metadata: decompresses to more than {MAX_JSON_BYTES} bytes")]
    TooLarge,
    /// The JSON is not an events metadata.
    #[error(transparent)]
    Definitions(#[from] DefinitionsError),
}

impl EventsMetadata {
    /// The events metadata of a log: the first `metadata_events` value with its
    /// continuations (as PX4's tools take it), checked, decompressed and read.
    pub fn of(meta: &Metadata) -> Result<EventsMetadata, MetadataError> {
        let multi = meta
            .multi_info()
            .iter()
            .find(|m| m.key == METADATA_KEY)
            .ok_or(MetadataError::Missing)?;
        let compressed = multi.joined(0).ok_or(MetadataError::NotBytes)?;
        let expected = match meta.info_value(SHA256_KEY) {
            Some(Value::String(s)) => Some(s.trim_end_matches('\0').to_owned()),
            _ => None,
        };
        EventsMetadata::decode(&compressed, expected.as_deref())
    }

    /// Decodes compressed metadata, checked against `sha256` (hex) if given.
    pub fn decode(
        compressed: &[u8],
        sha256: Option<&str>,
    ) -> Result<EventsMetadata, MetadataError> {
        let actual: String = sha2::Sha256::digest(compressed)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        let verification = match sha256 {
            None => Verification::NoDigest,
            Some(e) if e.eq_ignore_ascii_case(&actual) => Verification::Matches,
            Some(e) => Verification::Mismatch {
                expected: e.to_owned(),
                actual,
            },
        };
        let json = decompress(compressed)?;
        let definitions = EventDefinitions::from_json(&json)?;
        Ok(EventsMetadata {
            definitions,
            verification,
            compressed_len: compressed.len(),
            json_len: json.len(),
        })
    }
}

/// The bytes of an xz stream, at most [`MAX_JSON_BYTES`] of them.
pub fn decompress(compressed: &[u8]) -> Result<Vec<u8>, MetadataError> {
    let reader = lzma_rust2::XzReader::new_mem_limit(compressed, true, MAX_XZ_KIB);
    let mut out = Vec::new();
    reader
        .take(MAX_JSON_BYTES + 1)
        .read_to_end(&mut out)
        .map_err(|source| MetadataError::Xz {
            len: compressed.len(),
            source,
        })?;
    if out.len() as u64 > MAX_JSON_BYTES {
        return Err(MetadataError::TooLarge);
    }
    Ok(out)
}
