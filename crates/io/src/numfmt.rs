//! Number formatting for the ASCII writers.

use std::io::{self, Write};

/// Writes `x` as the shortest decimal that reads back to the same bits.
///
/// Rust's `{:?}` is used rather than `{}`: both print the shortest round-tripping digits, but
/// `{}` never uses an exponent, so `1e-300` would become 300 zeros; `{:?}` writes `1e-300`.
/// Every C `strtod`, POV-Ray and our own reader accept either.
pub(crate) fn write_f64<W: Write>(w: &mut W, x: f64) -> io::Result<()> {
    write!(w, "{x:?}")
}

/// Writes three coordinates separated by spaces.
pub(crate) fn write_xyz<W: Write>(w: &mut W, p: &[f64; 3]) -> io::Result<()> {
    write_xyz_sep(w, p, b" ")
}

/// Writes three coordinates separated by `sep`.
pub(crate) fn write_xyz_sep<W: Write>(w: &mut W, p: &[f64; 3], sep: &[u8]) -> io::Result<()> {
    write_f64(w, p[0])?;
    w.write_all(sep)?;
    write_f64(w, p[1])?;
    w.write_all(sep)?;
    write_f64(w, p[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shortest_round_trip() {
        for x in [
            0.1,
            1e-300,
            -123456.789,
            1.0 / 3.0,
            1.0,
            0.0,
            -0.0,
            5e-324,
            1e300,
        ] {
            let mut s = Vec::new();
            write_f64(&mut s, x).unwrap();
            let back: f64 = String::from_utf8(s).unwrap().parse().unwrap();
            assert_eq!(back.to_bits(), x.to_bits());
        }
        let mut s = Vec::new();
        write_f64(&mut s, 1e-300).unwrap();
        assert_eq!(s, b"1e-300");
    }
}
