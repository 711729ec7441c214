//! The one little-endian byte codec of saved states: the simulator's
//! ([`crate::solver::Simulator::to_bytes`]) and the FMU's serialized states
//! are both written by [`ByteWriter`] and read by [`ByteReader`]. Floats are
//! stored as their bit patterns, so a restored state continues
//! bit-identically. Every read checks the remaining length: truncated input
//! gives an error, never a panic.

use crate::error::{Error, Result};

/// Appends little-endian values to a byte vector.
#[derive(Debug, Default)]
pub struct ByteWriter {
    /// The bytes written so far.
    pub bytes: Vec<u8>,
}

impl ByteWriter {
    /// Appends a u8.
    pub fn u8(&mut self, v: u8) {
        self.bytes.push(v);
    }
    /// Appends a u32.
    pub fn u32(&mut self, v: u32) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    /// Appends a u64.
    pub fn u64(&mut self, v: u64) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    /// Appends a u128.
    pub fn u128(&mut self, v: u128) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    /// Appends an f64 (bit pattern).
    pub fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    /// Appends a slice of f64 with its length.
    pub fn f64s(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        v.iter().for_each(|&x| self.f64(x));
    }
    /// Appends an optional f64: the tag 0 (none) or 1 and the value, as
    /// u64 words.
    pub fn optional_f64(&mut self, v: Option<f64>) {
        match v {
            Some(value) => {
                self.u64(1);
                self.f64(value);
            }
            None => self.u64(0),
        }
    }
    /// Appends raw bytes (no length).
    pub fn raw(&mut self, v: &[u8]) {
        self.bytes.extend_from_slice(v);
    }
}

/// Reads what [`ByteWriter`] wrote; every read checks the remaining length.
#[derive(Debug)]
pub struct ByteReader<'a> {
    bytes: &'a [u8],
    offset: usize,
}

impl<'a> ByteReader<'a> {
    /// Reads from `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        ByteReader { bytes, offset: 0 }
    }
    /// How many bytes were read so far.
    pub fn offset(&self) -> usize {
        self.offset
    }
    /// The next `n` bytes.
    pub fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        let left = self.bytes.len() - self.offset;
        if left < n {
            return Err(Error::InvalidState(format!(
                "truncated at byte {}: needed {n} more bytes, {left} left",
                self.offset
            )));
        }
        let out = &self.bytes[self.offset..self.offset + n];
        self.offset += n;
        Ok(out)
    }
    fn array<const N: usize>(&mut self) -> Result<[u8; N]> {
        let mut out = [0u8; N];
        out.copy_from_slice(self.take(N)?);
        Ok(out)
    }
    /// Reads a u8.
    pub fn u8(&mut self) -> Result<u8> {
        Ok(self.array::<1>()?[0])
    }
    /// Reads a u32.
    pub fn u32(&mut self) -> Result<u32> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    /// Reads a u64.
    pub fn u64(&mut self) -> Result<u64> {
        Ok(u64::from_le_bytes(self.array()?))
    }
    /// Reads a u128.
    pub fn u128(&mut self) -> Result<u128> {
        Ok(u128::from_le_bytes(self.array()?))
    }
    /// Reads an f64.
    pub fn f64(&mut self) -> Result<f64> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// Reads a length-prefixed slice of f64 (at most `max` values).
    pub fn f64s(&mut self, max: u64) -> Result<Vec<f64>> {
        let n = self.u64()?;
        if n > max || n.saturating_mul(8) > (self.bytes.len() - self.offset) as u64 {
            return Err(Error::InvalidState(format!("implausible length {n}")));
        }
        (0..n).map(|_| self.f64()).collect()
    }
    /// Reads what [`ByteWriter::optional_f64`] wrote; another tag is an
    /// error naming `what`.
    pub fn optional_f64(&mut self, what: &str) -> Result<Option<f64>> {
        match self.u64()? {
            0 => Ok(None),
            1 => Ok(Some(self.f64()?)),
            other => Err(Error::InvalidState(format!("{what} tag {other}"))),
        }
    }
    /// Every byte not read yet.
    pub fn rest(&mut self) -> &'a [u8] {
        let out = &self.bytes[self.offset..];
        self.offset = self.bytes.len();
        out
    }
    /// Whether every byte was consumed.
    pub fn is_empty(&self) -> bool {
        self.offset == self.bytes.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_round_trip_bit_for_bit() {
        let mut w = ByteWriter::default();
        w.u8(7);
        w.u32(0xdead_beef);
        w.u64(u64::MAX - 1);
        w.u128(1 << 100);
        w.f64(-0.0);
        w.f64s(&[f64::MIN_POSITIVE, 1.5]);
        w.raw(b"end");
        let mut r = ByteReader::new(&w.bytes);
        assert_eq!(r.u8().unwrap(), 7);
        assert_eq!(r.u32().unwrap(), 0xdead_beef);
        assert_eq!(r.u64().unwrap(), u64::MAX - 1);
        assert_eq!(r.u128().unwrap(), 1 << 100);
        assert_eq!(r.f64().unwrap().to_bits(), (-0.0f64).to_bits());
        assert_eq!(r.f64s(2).unwrap(), vec![f64::MIN_POSITIVE, 1.5]);
        assert!(!r.is_empty());
        assert_eq!(r.rest(), b"end");
        assert!(r.is_empty());
    }

    #[test]
    fn truncated_and_implausible_input_is_refused() {
        let mut r = ByteReader::new(&[1, 2, 3]);
        let e = r.u32().unwrap_err().to_string();
        assert!(
            e.contains("truncated at byte 0") && e.contains("3 left"),
            "{e}"
        );
        let mut w = ByteWriter::default();
        w.f64s(&[1.0, 2.0, 3.0]);
        assert!(ByteReader::new(&w.bytes).f64s(2).is_err());
        let mut w = ByteWriter::default();
        w.u64(1 << 60);
        assert!(ByteReader::new(&w.bytes).f64s(u64::MAX).is_err());
    }
}
