//! A line-tracking byte tokenizer shared by the ASCII readers.
//!
//! The whole file is in memory; tokens are whitespace-separated byte slices borrowed from it, so
//! walking a file allocates nothing. `#` starts a comment that runs to the end of the line
//! (switchable for formats where `#` is data). Every error it builds names the file and the
//! 1-based line.

use crate::IoError;
use std::path::Path;

/// Cursor over the bytes of one file.
pub(crate) struct Tokens<'a> {
    file: &'a Path,
    data: &'a [u8],
    pos: usize,
    line: usize,
    comments: bool,
}

impl<'a> Tokens<'a> {
    /// Starts at the beginning of `data`, line 1, with `#` comments enabled.
    pub fn new(file: &'a Path, data: &'a [u8]) -> Self {
        Tokens {
            file,
            data,
            pos: 0,
            line: 1,
            comments: true,
        }
    }

    /// Turns `#` comment handling on or off.
    pub fn set_comments(&mut self, on: bool) {
        self.comments = on;
    }

    /// Line of the cursor (after a token was read: that token's line).
    pub fn line(&self) -> usize {
        self.line
    }

    /// Skips whitespace (counting newlines) and comments.
    fn skip_blank(&mut self) {
        while let Some(&b) = self.data.get(self.pos) {
            match b {
                b'\n' => {
                    self.line += 1;
                    self.pos += 1;
                }
                b' ' | b'\t' | b'\r' | 0x0b | 0x0c => self.pos += 1,
                b'#' if self.comments => self.skip_line(),
                _ => break,
            }
        }
    }

    fn is_delimiter(&self, b: u8) -> bool {
        b.is_ascii_whitespace() || b == 0x0b || (b == b'#' && self.comments)
    }

    /// The next token, or `None` at end of file.
    pub fn next(&mut self) -> Option<&'a [u8]> {
        self.skip_blank();
        let start = self.pos;
        while let Some(&b) = self.data.get(self.pos) {
            if self.is_delimiter(b) {
                break;
            }
            self.pos += 1;
        }
        self.data.get(start..self.pos).filter(|t| !t.is_empty())
    }

    /// The next token without consuming it.
    pub fn peek(&mut self) -> Option<&'a [u8]> {
        self.skip_blank();
        let (pos, line) = (self.pos, self.line);
        let token = self.next();
        self.pos = pos;
        self.line = line;
        token
    }

    /// Moves to the end of the current line (its newline is consumed by the next read).
    pub fn skip_line(&mut self) {
        while let Some(&b) = self.data.get(self.pos) {
            if b == b'\n' {
                break;
            }
            self.pos += 1;
        }
    }

    /// The raw text of the rest of the current line, consuming it and its newline.
    pub fn rest_of_line(&mut self) -> &'a [u8] {
        let start = self.pos;
        self.skip_line();
        let text = self.data.get(start..self.pos).unwrap_or(&[]);
        if self.pos < self.data.len() {
            self.pos += 1;
            self.line += 1;
        }
        text
    }

    /// True when another token follows on the current line.
    pub fn more_on_line(&mut self) -> bool {
        while let Some(&b) = self.data.get(self.pos) {
            match b {
                b' ' | b'\t' | b'\r' | 0x0b | 0x0c => self.pos += 1,
                b'\n' => return false,
                b'#' if self.comments => return false,
                _ => return true,
            }
        }
        false
    }

    /// Line to report for "found end of file": the last line of the file.
    fn eof_line(&self) -> usize {
        if self.data.last() == Some(&b'\n') && self.line > 1 {
            self.line - 1
        } else {
            self.line
        }
    }

    /// An error at the cursor's line.
    pub fn error(&self, message: impl Into<String>) -> IoError {
        IoError::parse(self.file, self.line, message)
    }

    /// An error at an explicit line.
    pub fn error_at(&self, line: usize, message: impl Into<String>) -> IoError {
        IoError::parse(self.file, line, message)
    }

    /// "expected {what}, found end of file" at the last line.
    pub fn eof_error(&self, what: &str) -> IoError {
        IoError::parse(
            self.file,
            self.eof_line(),
            format!("expected {what}, found end of file"),
        )
    }

    /// The next token, or an end-of-file error naming `what` was expected.
    pub fn expect(&mut self, what: &str) -> Result<&'a [u8], IoError> {
        match self.next() {
            Some(t) => Ok(t),
            None => Err(self.eof_error(what)),
        }
    }

    /// "expected {what}, found "{token}"" at the cursor's line.
    pub fn unexpected(&self, what: &str, token: &[u8]) -> IoError {
        self.error(format!("expected {what}, found \"{}\"", show(token)))
    }

    /// Reads a non-negative integer.
    pub fn u64(&mut self, what: &str) -> Result<u64, IoError> {
        let t = self.expect(what)?;
        parse_u64(t).ok_or_else(|| self.unexpected(what, t))
    }

    /// Reads a non-negative integer that must fit a `usize` (counts).
    pub fn usize(&mut self, what: &str) -> Result<usize, IoError> {
        let t = self.expect(what)?;
        parse_u64(t)
            .and_then(|v| usize::try_from(v).ok())
            .ok_or_else(|| self.unexpected(what, t))
    }

    /// Reads a signed integer that fits an `i32` (labels, tags).
    pub fn i32(&mut self, what: &str) -> Result<i32, IoError> {
        let t = self.expect(what)?;
        parse_i64(t)
            .and_then(|v| i32::try_from(v).ok())
            .ok_or_else(|| self.unexpected(what, t))
    }

    /// Reads a signed integer.
    pub fn i64(&mut self, what: &str) -> Result<i64, IoError> {
        let t = self.expect(what)?;
        parse_i64(t).ok_or_else(|| self.unexpected(what, t))
    }

    /// Reads a finite floating-point number; NaN and infinities are errors.
    pub fn f64(&mut self, what: &str) -> Result<f64, IoError> {
        let t = self.expect(what)?;
        let v = parse_f64(t).ok_or_else(|| self.unexpected(what, t))?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.error(format!("{what} is NaN/infinite (found \"{}\")", show(t))))
        }
    }

    /// A capacity to reserve for `count` items announced by a header, capped by the bytes left
    /// (each item needs at least `min_bytes`), so a corrupt count cannot force a huge allocation.
    pub fn capacity_hint(&self, count: usize, min_bytes: usize) -> usize {
        let left = self.data.len().saturating_sub(self.pos);
        count.min(left / min_bytes.max(1) + 1)
    }
}

/// A token for an error message: lossy UTF-8, cut at 40 characters.
pub(crate) fn show(token: &[u8]) -> String {
    let s = String::from_utf8_lossy(token);
    if s.chars().count() > 40 {
        let cut: String = s.chars().take(40).collect();
        format!("{cut}...")
    } else {
        s.into_owned()
    }
}

/// Decimal digits with an optional `+`.
pub(crate) fn parse_u64(token: &[u8]) -> Option<u64> {
    let digits = token.strip_prefix(b"+").unwrap_or(token);
    if digits.is_empty() {
        return None;
    }
    let mut value: u64 = 0;
    for &b in digits {
        let d = b.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        value = value.checked_mul(10)?.checked_add(u64::from(d))?;
    }
    Some(value)
}

/// Decimal digits with an optional sign.
pub(crate) fn parse_i64(token: &[u8]) -> Option<i64> {
    match token.strip_prefix(b"-") {
        Some(rest) if !rest.starts_with(b"+") => {
            let v = parse_u64(rest)?;
            0i64.checked_sub_unsigned(v)
        }
        Some(_) => None,
        None => i64::try_from(parse_u64(token)?).ok(),
    }
}

/// A float as Rust's standard library reads it (correctly rounded).
pub(crate) fn parse_f64(token: &[u8]) -> Option<f64> {
    std::str::from_utf8(token).ok()?.parse::<f64>().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_lines_and_comments() {
        let p = Path::new("t.txt");
        let mut t = Tokens::new(p, b"a b # c d\n\n  e#x\nf");
        assert_eq!(t.next(), Some(&b"a"[..]));
        assert_eq!(t.next(), Some(&b"b"[..]));
        assert!(!t.more_on_line());
        assert_eq!(t.next(), Some(&b"e"[..]));
        assert_eq!(t.line(), 3);
        assert_eq!(t.peek(), Some(&b"f"[..]));
        assert_eq!(t.next(), Some(&b"f"[..]));
        assert_eq!(t.line(), 4);
        assert_eq!(t.next(), None);
        let e = t.expect("a number").unwrap_err().to_string();
        assert_eq!(e, "t.txt:4: expected a number, found end of file");
    }

    #[test]
    fn integers() {
        assert_eq!(parse_u64(b"0012"), Some(12));
        assert_eq!(parse_u64(b"+7"), Some(7));
        assert_eq!(parse_u64(b"-7"), None);
        assert_eq!(parse_u64(b"99999999999999999999999"), None);
        assert_eq!(parse_i64(b"-7"), Some(-7));
        assert_eq!(parse_i64(b"-+7"), None);
        assert_eq!(parse_i64(b"-9223372036854775808"), Some(i64::MIN));
        assert_eq!(parse_u64(b""), None);
    }

    #[test]
    fn nan_is_rejected() {
        let p = Path::new("x.node");
        let mut t = Tokens::new(p, b"1\n2\nnan");
        t.next();
        t.next();
        let e = t.f64("coordinate").unwrap_err().to_string();
        assert!(e.starts_with("x.node:3: coordinate is NaN/infinite"), "{e}");
    }
}
