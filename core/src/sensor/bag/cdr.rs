//! OMG CDR, little-endian, as ROS 2's middleware writes a message (XCDR1, "plain CDR"): a
//! 4-byte encapsulation header, then the fields in order, each primitive aligned to its own
//! size counted from the end of the header; a string is its byte count with the closing NUL,
//! the bytes and the NUL; a sequence is its element count, then the elements; a fixed array is
//! its elements alone.

/// A message being serialised.
pub struct Cdr {
    bytes: Vec<u8>,
}

/// `CDR_LE`: the representation identifier of little-endian plain CDR, and two option bytes.
const HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

impl Cdr {
    pub fn new() -> Self {
        Self::with_capacity(64)
    }

    /// A message that will hold about `bytes` bytes (an image's pixels): one allocation.
    pub fn with_capacity(bytes: usize) -> Self {
        let mut v = Vec::with_capacity(bytes + 64);
        v.extend_from_slice(&HEADER);
        Self { bytes: v }
    }

    pub fn into_bytes(self) -> Vec<u8> {
        self.bytes
    }

    /// Pads to a multiple of `n` bytes past the header.
    fn align(&mut self, n: usize) {
        let body = self.bytes.len() - HEADER.len();
        let pad = (n - body % n) % n;
        self.bytes.resize(self.bytes.len() + pad, 0);
    }

    pub fn u8(&mut self, v: u8) -> &mut Self {
        self.bytes.push(v);
        self
    }

    pub fn bool(&mut self, v: bool) -> &mut Self {
        self.u8(u8::from(v))
    }

    pub fn u32(&mut self, v: u32) -> &mut Self {
        self.align(4);
        self.bytes.extend_from_slice(&v.to_le_bytes());
        self
    }

    pub fn i32(&mut self, v: i32) -> &mut Self {
        self.align(4);
        self.bytes.extend_from_slice(&v.to_le_bytes());
        self
    }

    pub fn f64(&mut self, v: f64) -> &mut Self {
        self.align(8);
        self.bytes.extend_from_slice(&v.to_le_bytes());
        self
    }

    /// A fixed-size array of float64 (`float64[9] k`): no count.
    pub fn f64s(&mut self, values: &[f64]) -> &mut Self {
        for &v in values {
            self.f64(v);
        }
        self
    }

    /// A sequence of float64 (`float64[] d`): the count, then the values.
    pub fn f64_seq(&mut self, values: &[f64]) -> &mut Self {
        self.len(values.len());
        self.f64s(values)
    }

    pub fn string(&mut self, s: &str) -> &mut Self {
        self.len(s.len() + 1);
        self.bytes.extend_from_slice(s.as_bytes());
        self.bytes.push(0);
        self
    }

    /// A sequence of bytes (`uint8[] data`).
    pub fn byte_seq(&mut self, data: &[u8]) -> &mut Self {
        self.len(data.len());
        self.bytes.extend_from_slice(data);
        self
    }

    /// A sequence's element count.
    pub fn len(&mut self, n: usize) -> &mut Self {
        // A message's sequences are an image's bytes, a cloud's points or a few numbers; the
        // topics check the first two against 2^32 before they get here (`topics::frame`).
        self.u32(u32::try_from(n).expect("a sequence of fewer than 2^32 elements"))
    }
}

impl Default for Cdr {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitives_align_to_their_size_after_the_header() {
        let mut c = Cdr::new();
        c.u8(7).u32(1).u8(2).f64(1.5).string("ab").bool(true);
        let b = c.into_bytes();
        let mut want = vec![0, 1, 0, 0, 7, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0, 0];
        want.extend_from_slice(&1.5f64.to_le_bytes());
        want.extend_from_slice(&[3, 0, 0, 0, b'a', b'b', 0, 1]);
        assert_eq!(b, want);
    }

    #[test]
    fn sequences_carry_their_count_and_arrays_do_not() {
        let mut c = Cdr::new();
        c.f64s(&[1.0]).f64_seq(&[2.0]).byte_seq(&[9, 8]);
        let b = c.into_bytes();
        assert_eq!(
            b.len(),
            4 + 8 + 4 + 4 + 8 + 4 + 2,
            "the count is padded to the f64"
        );
        assert_eq!(&b[12..16], &[1, 0, 0, 0]);
        assert_eq!(&b[b.len() - 6..], &[2, 0, 0, 0, 9, 8]);
    }
}
