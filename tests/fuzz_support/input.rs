//! Decoding fuzzer bytes: a cursor that yields zeros once the input is exhausted, so every byte
//! string is a valid input and libFuzzer's mutations stay meaningful.

/// A little-endian cursor over the fuzzer's bytes.
pub(crate) struct Input<'a> {
    data: &'a [u8],
}

impl<'a> Input<'a> {
    /// A cursor at the start of `data`.
    pub(crate) fn new(data: &'a [u8]) -> Self {
        Self { data }
    }

    /// Whether every byte has been read.
    pub(crate) fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The next byte, or 0.
    pub(crate) fn u8(&mut self) -> u8 {
        match self.data.split_first() {
            Some((&b, rest)) => {
                self.data = rest;
                b
            }
            None => 0,
        }
    }

    /// The next four bytes as a little-endian `u32` (missing bytes read as 0).
    pub(crate) fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }

    /// The next eight bytes as a little-endian `u64`.
    pub(crate) fn u64(&mut self) -> u64 {
        u64::from(self.u32()) | u64::from(self.u32()) << 32
    }

    /// A coordinate: a tag byte picks raw f32 bits (non-finite ones become 0, since meshes are
    /// validated finite), a fine fixed-point grid (which lands vertices exactly on pixel centres
    /// and shared edges), a coarse grid, or magnitudes near 1e7 and 1e-7.
    pub(crate) fn coordinate(&mut self) -> f32 {
        match self.u8() % 6 {
            0 | 1 => {
                let raw = f32::from_bits(self.u32());
                if raw.is_finite() {
                    raw
                } else {
                    0.0
                }
            }
            2 => f32::from(i16::from_le_bytes([self.u8(), self.u8()])) / 4096.0,
            3 => f32::from(self.u8() as i8) / 64.0,
            4 => f32::from(self.u8() as i8) * 1e7,
            _ => f32::from(self.u8() as i8) * 1e-7,
        }
    }
}
