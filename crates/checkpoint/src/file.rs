//! The checkpoint file: magic, format version, a header saying what wrote it and for which
//! run, then the body with its length and checksum.

use crate::{CheckpointError, Reader, Writer};

/// The first bytes of every checkpoint file.
pub const MAGIC: &[u8; 8] = b"PFCKPT\r\n";

/// The layout version this build writes and reads; a file of another version is refused.
/// 2: the driver's self-contact counters; 3: its contact time; 4: its fragment ids; 5: a
/// shell's Newmark state; 6: a ghost layer's dropped ghosts; 7: the damage check's peak
/// shares; 8: the work of a shell's loads.
pub const FORMAT_VERSION: u32 = 8;

/// What a checkpoint says about itself.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Header {
    /// The program that wrote it, with its version (`perifrac 0.1.0`); a run continues only
    /// under the same one, since another build may step differently.
    pub program: String,
    /// A hash of what the state belongs to (the scene and the setup it gives); the reader
    /// compares its own.
    pub fingerprint: u64,
    /// One line for messages: the scene and where the run stood.
    pub summary: String,
}

/// 64-bit FNV-1a of `bytes`: the file checksum and the scene fingerprint (not for security).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    fnv1a_from(0xcbf2_9ce4_8422_2325, bytes)
}

/// FNV-1a continued from `hash`, to hash several pieces as one.
pub fn fnv1a_from(mut hash: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        hash ^= u64::from(b);
        hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
    }
    hash
}

/// The file bytes for `header` and `body`.
pub fn seal(header: &Header, body: &[u8]) -> Vec<u8> {
    let mut w = Writer::new();
    w.str(&header.program);
    w.u64(header.fingerprint);
    w.str(&header.summary);
    w.usize(body.len());
    let sum = fnv1a_from(fnv1a(w.bytes()), body);
    w.u64(sum);
    let head = w.into_bytes();
    let mut out = Vec::with_capacity(MAGIC.len() + 4 + head.len() + body.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&head);
    out.extend_from_slice(body);
    out
}

/// Splits a checkpoint file into its header and body, refusing another format, another
/// version, a truncated file or one whose checksum (over the header and the body) does not
/// match.
pub fn open(bytes: &[u8]) -> Result<(Header, &[u8]), CheckpointError> {
    let file = |m: String| CheckpointError::File(m);
    if bytes.len() < MAGIC.len() + 4 || &bytes[..MAGIC.len()] != MAGIC {
        return Err(file("not a perifrac checkpoint".into()));
    }
    let v = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if v != FORMAT_VERSION {
        return Err(file(format!(
            "checkpoint format version {v}; this build reads version {FORMAT_VERSION}"
        )));
    }
    let rest = &bytes[12..];
    let mut r = Reader::new(rest);
    let header = Header {
        program: r.str("the program name")?,
        fingerprint: r.u64("the fingerprint")?,
        summary: r.str("the summary")?,
    };
    let len = r.usize("the body length")?;
    let covered = &rest[..rest.len() - r.remaining()];
    let sum = r.u64("the checksum")?;
    let start = rest.len() - r.remaining();
    let body = &rest[start..];
    if body.len() != len {
        return Err(file(format!(
            "the checkpoint is cut short or padded: its body has {} bytes, its header says {len}",
            body.len()
        )));
    }
    if fnv1a_from(fnv1a(covered), body) != sum {
        return Err(file(
            "the checkpoint is damaged: its checksum does not match".into(),
        ));
    }
    Ok((header, body))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (Header, Vec<u8>) {
        let h = Header {
            program: "perifrac 0.1.0".into(),
            fingerprint: 42,
            summary: "wall.toml at step 10".into(),
        };
        (h, vec![1, 2, 3, 4, 5])
    }

    #[test]
    fn sealed_files_open_to_what_was_sealed() {
        let (h, body) = sample();
        let bytes = seal(&h, &body);
        let (h2, b2) = open(&bytes).unwrap();
        assert_eq!((h2, b2), (h, &body[..]));
    }

    #[test]
    fn damage_anywhere_is_refused() {
        let (h, body) = sample();
        let bytes = seal(&h, &body);
        assert!(open(b"ply\nformat")
            .unwrap_err()
            .to_string()
            .contains("not a perifrac"));
        let mut other = bytes.clone();
        other[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
        let e = open(&other).unwrap_err().to_string();
        assert!(
            e.contains(&format!("version {}", FORMAT_VERSION + 1)),
            "{e}"
        );
        // the checksum covers the header and the body: every single-byte change is caught
        for k in 12..bytes.len() {
            let mut b = bytes.clone();
            b[k] ^= 0x10;
            assert!(open(&b).is_err(), "byte {k} changed silently");
        }
        for cut in 0..bytes.len() {
            assert!(open(&bytes[..cut]).is_err(), "cut at {cut} accepted");
        }
    }
}
