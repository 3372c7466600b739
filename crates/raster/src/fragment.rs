//! Fragments and the order-preserving depth key.

/// The key of an empty slot in an ascending depth array: larger than every depth key, since the
/// largest key a fragment can carry is that of depth 1.0 (`0x3F80_0000`).
///
/// Unlike FreePipe's Table 1, which tests against `0x7FFFFFFF` after initialising to
/// `0xFFFFFFFF`, fragsim uses one sentinel for both (see `docs/proof.md`).
pub const EMPTY_KEY: u32 = u32::MAX;

/// One fragment: the pixel it covers, its depth key and the triangle it came from.
///
/// The canonical order of a pixel's fragments is `(depth_key, prim)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Fragment {
    /// Row-major pixel index `y * width + x`.
    pub pixel: u32,
    /// Depth key: the bit pattern of the f32 depth in `[0, 1]` (see [`depth_key`]).
    pub depth_key: u32,
    /// Primitive id: the index of the triangle in the mesh (clipped pieces keep it).
    pub prim: u32,
}

impl Fragment {
    /// The fragment's identity packed into one 64-bit word whose integer order is the canonical
    /// order: depth key in the high half, primitive id in the low half.
    #[must_use]
    #[inline]
    pub fn packed(self) -> u64 {
        (u64::from(self.depth_key) << 32) | u64::from(self.prim)
    }

    /// The depth as a float.
    #[must_use]
    pub fn depth(self) -> f32 {
        depth_from_key(self.depth_key)
    }
}

/// The depth key of a depth in `[0, 1]`: its IEEE-754 bit pattern, with `-0.0` mapped to `+0.0`.
///
/// For non-negative floats the bit pattern read as an unsigned integer orders exactly as the
/// floats do, which is why an integer `atomicMin` sorts depths. Returns `None` for depths outside
/// `[0, 1]` and for NaN: the pipeline drops those fragments (they lie outside the view volume).
#[must_use]
#[inline]
pub fn depth_key(depth: f32) -> Option<u32> {
    if (0.0..=1.0).contains(&depth) {
        // `-0.0` passes the range test; adding `0.0` turns it into `+0.0`.
        Some((depth + 0.0).to_bits())
    } else {
        None
    }
}

/// The depth whose key this is.
#[must_use]
pub fn depth_from_key(key: u32) -> f32 {
    f32::from_bits(key)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_order_is_float_order_at_the_ends() {
        let depths = [
            0.0_f32,
            f32::from_bits(1),
            1e-30,
            0.5,
            1.0 - f32::EPSILON / 2.0,
            1.0,
        ];
        for pair in depths.windows(2) {
            assert!(depth_key(pair[0]).unwrap() < depth_key(pair[1]).unwrap());
        }
        assert_eq!(depth_key(-0.0), Some(0));
        assert_eq!(depth_key(f32::NAN), None);
        assert_eq!(depth_key(1.000_000_1), None);
        assert_eq!(depth_key(-1e-30), None);
        assert!(depth_key(1.0).unwrap() < EMPTY_KEY);
    }
}
