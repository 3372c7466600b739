//! Strategies for depths in `[0, 1]`, for the depth-key order.

use proptest::prelude::*;
use proptest::sample::select;

/// The bit pattern of 1.0f32: the largest depth key.
const ONE_BITS: u32 = 0x3F80_0000;

/// A depth in `[0, 1]`: any f32 in the range with equal weight per bit pattern (so subnormals and
/// tiny depths are common), uniform in value, or a special value (`±0.0`, the smallest subnormal,
/// the smallest normal, 0.5, the largest float below 1, 1.0).
pub fn unit_depth() -> impl Strategy<Value = f32> {
    prop_oneof![
        2 => (0_u32..=ONE_BITS).prop_map(f32::from_bits),
        2 => 0.0_f32..=1.0,
        1 => select(vec![
            0.0_f32,
            -0.0,
            f32::from_bits(1),
            f32::MIN_POSITIVE,
            0.5,
            1.0 - f32::EPSILON / 2.0,
            1.0,
        ]),
    ]
}

/// Two depths in `[0, 1]`: independent (see [`unit_depth`]), or neighbours 1 to 4 ulps apart.
pub fn unit_depth_pair() -> impl Strategy<Value = (f32, f32)> {
    prop_oneof![
        (unit_depth(), unit_depth()),
        (0_u32..ONE_BITS, 1_u32..=4).prop_map(|(bits, ulps)| (
            f32::from_bits(bits),
            f32::from_bits((bits + ulps).min(ONE_BITS))
        )),
    ]
}
