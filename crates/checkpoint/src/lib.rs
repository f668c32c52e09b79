//! The checkpoint byte format: what a running simulation must keep to continue bit for bit,
//! written by each crate that owns a piece of state ([`Writer`]) and read back in the same
//! order ([`Reader`]), then sealed into a versioned file with a checksum ([`seal`], [`open`]).
//!
//! A body is a sequence of items: tags (a section name, so that a reader out of step with the
//! writer fails at once with both names), scalars, strings and arrays (a `u64` length, then the
//! elements). Everything is little-endian, so a checkpoint moves between machines. The same
//! writer serves in memory (a snapshot before a trial step, reused without allocating once its
//! buffer is large enough) and on disk.
//!
//! ```
//! use perifrac_checkpoint::{Reader, Writer};
//! let mut w = Writer::new();
//! w.tag("state");
//! w.u64(7);
//! w.array(&[[1.0, 2.0, 3.0]]);
//! let mut r = Reader::new(w.bytes());
//! r.tag("state")?;
//! assert_eq!(r.u64("steps")?, 7);
//! let mut p = [[0.0; 3]; 1];
//! r.array_into("positions", &mut p)?;
//! r.finish()?;
//! assert_eq!(p, [[1.0, 2.0, 3.0]]);
//! # Ok::<(), perifrac_checkpoint::CheckpointError>(())
//! ```

#![warn(missing_docs)]

mod elem;
mod file;

pub use elem::Elem;
pub use file::{fnv1a, fnv1a_from, open, seal, Header, FORMAT_VERSION, MAGIC};

/// What is wrong with a checkpoint.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum CheckpointError {
    /// The bytes end before `what`.
    #[error("the checkpoint ends before {what}")]
    Truncated {
        /// The item being read.
        what: String,
    },
    /// A section tag other than the expected one.
    #[error("the checkpoint has section '{got}' where '{expected}' belongs")]
    Tag {
        /// The section the reader expected.
        expected: String,
        /// The section found.
        got: String,
    },
    /// An array of the wrong length.
    #[error("{what}: {got} entries in the checkpoint, {expected} in this run")]
    Length {
        /// The array.
        what: String,
        /// Entries this run has.
        expected: usize,
        /// Entries in the checkpoint.
        got: usize,
    },
    /// A value that cannot be right (an index out of range, a flag other than 0 or 1).
    #[error("{what}: {message}")]
    Invalid {
        /// The item.
        what: String,
        /// Why it is refused.
        message: String,
    },
    /// Bytes left after the last item.
    #[error("{0} bytes follow the last item of the checkpoint")]
    Trailing(usize),
    /// Not a perifrac checkpoint, another format version, or damaged.
    #[error("{0}")]
    File(String),
}

/// Appends items to a byte buffer.
#[derive(Debug, Clone, Default)]
pub struct Writer {
    buf: Vec<u8>,
}

impl Writer {
    /// An empty writer.
    pub fn new() -> Self {
        Writer::default()
    }

    /// Empties the buffer, keeping its capacity (a snapshot taken every step allocates once).
    pub fn clear(&mut self) {
        self.buf.clear();
    }

    /// The bytes written so far.
    pub fn bytes(&self) -> &[u8] {
        &self.buf
    }

    /// The bytes written, as an owned buffer.
    pub fn into_bytes(self) -> Vec<u8> {
        self.buf
    }

    /// A section tag: the reader's [`Reader::tag`] must name the same section.
    pub fn tag(&mut self, name: &str) {
        self.str(name);
    }

    /// A `u64`.
    pub fn u64(&mut self, v: u64) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `usize`, as a `u64`.
    pub fn usize(&mut self, v: usize) {
        self.u64(v as u64);
    }

    /// An `f64`, bit for bit.
    pub fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }

    /// A flag, as one byte.
    pub fn bool(&mut self, v: bool) {
        self.buf.push(u8::from(v));
    }

    /// A UTF-8 string.
    pub fn str(&mut self, s: &str) {
        self.array(s.as_bytes());
    }

    /// An array: its length, then each element.
    pub fn array<T: Elem>(&mut self, v: &[T]) {
        self.usize(v.len());
        self.buf.reserve(v.len() * T::SIZE);
        T::put_all(v, &mut self.buf);
    }
}

/// Reads the items of a body in the order they were written; every read names what it reads,
/// for the message when the bytes do not fit.
#[derive(Debug, Clone)]
pub struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    /// Reads `bytes` from the start.
    pub fn new(bytes: &'a [u8]) -> Self {
        Reader { bytes, pos: 0 }
    }

    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], CheckpointError> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| CheckpointError::Truncated { what: what.into() })?;
        let out = &self.bytes[self.pos..end];
        self.pos = end;
        Ok(out)
    }

    /// Expects the section tag `name`.
    pub fn tag(&mut self, name: &str) -> Result<(), CheckpointError> {
        let got = self.str(name)?;
        if got == name {
            Ok(())
        } else {
            Err(CheckpointError::Tag {
                expected: name.into(),
                got,
            })
        }
    }

    /// A `u64`.
    pub fn u64(&mut self, what: &str) -> Result<u64, CheckpointError> {
        let b = self.take(8, what)?;
        Ok(u64::from_le_bytes(b.try_into().expect("8 bytes")))
    }

    /// A `usize`, refused when it does not fit this machine's.
    pub fn usize(&mut self, what: &str) -> Result<usize, CheckpointError> {
        let v = self.u64(what)?;
        usize::try_from(v).map_err(|_| CheckpointError::Invalid {
            what: what.into(),
            message: format!("{v} does not fit this machine's integers"),
        })
    }

    /// An `f64`.
    pub fn f64(&mut self, what: &str) -> Result<f64, CheckpointError> {
        Ok(f64::from_bits(self.u64(what)?))
    }

    /// A flag; bytes other than 0 and 1 are refused.
    pub fn bool(&mut self, what: &str) -> Result<bool, CheckpointError> {
        match self.take(1, what)?[0] {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(CheckpointError::Invalid {
                what: what.into(),
                message: format!("flag byte {b} is neither 0 nor 1"),
            }),
        }
    }

    /// A UTF-8 string.
    pub fn str(&mut self, what: &str) -> Result<String, CheckpointError> {
        let n = self.len(what, 1)?;
        let b = self.take(n, what)?;
        String::from_utf8(b.to_vec()).map_err(|_| CheckpointError::Invalid {
            what: what.into(),
            message: "not UTF-8".into(),
        })
    }

    /// An array's length, checked against the bytes left so that a damaged length cannot ask
    /// for a huge allocation.
    fn len(&mut self, what: &str, size: usize) -> Result<usize, CheckpointError> {
        let n = self.usize(what)?;
        let left = self.bytes.len() - self.pos;
        if n.checked_mul(size).is_none_or(|b| b > left) {
            return Err(CheckpointError::Truncated { what: what.into() });
        }
        Ok(n)
    }

    /// An array of exactly `out.len()` elements, into `out`.
    pub fn array_into<T: Elem>(
        &mut self,
        what: &str,
        out: &mut [T],
    ) -> Result<(), CheckpointError> {
        let n = self.len(what, T::SIZE)?;
        if n != out.len() {
            return Err(CheckpointError::Length {
                what: what.into(),
                expected: out.len(),
                got: n,
            });
        }
        let b = self.take(n * T::SIZE, what)?;
        for (x, chunk) in out.iter_mut().zip(b.chunks_exact(T::SIZE)) {
            *x = T::get(chunk);
        }
        Ok(())
    }

    /// An array of any length, replacing the contents of `out` (its capacity is reused).
    pub fn array_vec<T: Elem>(
        &mut self,
        what: &str,
        out: &mut Vec<T>,
    ) -> Result<(), CheckpointError> {
        let n = self.len(what, T::SIZE)?;
        let b = self.take(n * T::SIZE, what)?;
        out.clear();
        out.extend(b.chunks_exact(T::SIZE).map(T::get));
        Ok(())
    }

    /// Bytes not read yet.
    pub fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    /// Refuses bytes left after the last item.
    pub fn finish(&self) -> Result<(), CheckpointError> {
        match self.bytes.len() - self.pos {
            0 => Ok(()),
            n => Err(CheckpointError::Trailing(n)),
        }
    }
}

/// Refuses `got` where this run has `expected` (a count that must match, such as balls).
pub fn expect_count(what: &str, expected: usize, got: usize) -> Result<(), CheckpointError> {
    if expected == got {
        Ok(())
    } else {
        Err(CheckpointError::Length {
            what: what.into(),
            expected,
            got,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn items_round_trip_bit_for_bit() {
        let mut w = Writer::new();
        w.tag("a");
        w.f64(-0.0);
        w.f64(f64::NAN);
        w.bool(true);
        w.str("résumé");
        w.array(&[1u32, u32::MAX]);
        w.array(&[[1u32, 2, 3, 4]]);
        w.array::<u8>(&[]);
        let mut r = Reader::new(w.bytes());
        r.tag("a").unwrap();
        assert_eq!(r.f64("z").unwrap().to_bits(), (-0.0f64).to_bits());
        assert_eq!(r.f64("n").unwrap().to_bits(), f64::NAN.to_bits());
        assert!(r.bool("b").unwrap());
        assert_eq!(r.str("s").unwrap(), "résumé");
        let mut v = vec![9u32; 5];
        r.array_vec("v", &mut v).unwrap();
        assert_eq!(v, [1, u32::MAX]);
        let mut t = [[0u32; 4]];
        r.array_into("t", &mut t).unwrap();
        assert_eq!(t, [[1, 2, 3, 4]]);
        let mut e: Vec<u8> = vec![1];
        r.array_vec("e", &mut e).unwrap();
        assert!(e.is_empty());
        r.finish().unwrap();
    }

    #[test]
    fn a_reader_out_of_step_names_both_sections() {
        let mut w = Writer::new();
        w.tag("mesh");
        let e = Reader::new(w.bytes()).tag("solver").unwrap_err();
        assert_eq!(
            e.to_string(),
            "the checkpoint has section 'mesh' where 'solver' belongs"
        );
    }

    #[test]
    fn wrong_lengths_and_trailing_bytes_are_refused() {
        let mut w = Writer::new();
        w.array(&[1.0f64, 2.0]);
        w.u64(3);
        let mut r = Reader::new(w.bytes());
        let mut out = [0.0f64; 3];
        let e = r.array_into("velocities", &mut out).unwrap_err();
        assert_eq!(
            e.to_string(),
            "velocities: 2 entries in the checkpoint, 3 in this run"
        );
        let mut r = Reader::new(w.bytes());
        let mut v = Vec::new();
        r.array_vec::<f64>("x", &mut v).unwrap();
        assert_eq!(r.finish(), Err(CheckpointError::Trailing(8)));
        assert!(Reader::new(&[1]).bool("flag").is_ok());
        assert!(Reader::new(&[2]).bool("flag").is_err());
    }

    proptest! {
        /// Any bytes, read as any item, give a value or an error: never a panic, and never an
        /// allocation beyond the bytes there are (a length of 2^60 is refused, not reserved).
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..64)) {
            let mut r = Reader::new(&bytes);
            let _ = r.tag("x");
            let mut r = Reader::new(&bytes);
            let mut v: Vec<[f64; 3]> = Vec::new();
            let _ = r.array_vec("v", &mut v);
            prop_assert!(v.len() * 24 <= bytes.len());
            let mut r = Reader::new(&bytes);
            let _ = r.str("s");
            let _ = r.bool("b");
            let _ = r.f64("f");
        }
    }
}
