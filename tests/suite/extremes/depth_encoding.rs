//! Depth encoding: the keys of the ends of the depth range, subnormals, values just outside it,
//! infinities and NaN, and fragments interpolated or clipped at depths 0 and 1.

use fragsim::memory::SerialMemory;
use fragsim::raster::{depth_from_key, depth_key, CullMode, Mesh, MeshError, View};
use proptest::prelude::*;

use super::{all_fragments, identity_view, mdts32_run, perspective, soup, viewport, MAX_KEY};

#[test]
fn depth_zero_has_key_zero() {
    assert_eq!(depth_key(0.0), Some(0));
}

#[test]
fn negative_zero_has_the_key_of_positive_zero_not_0x80000000() {
    assert_eq!(depth_key(-0.0), Some(0));
    // Unmapped, its bit pattern would sort after every depth up to 1.0: the library's MDTS,
    // handed the raw bits, keeps the nearest depth there is behind depth 1.0.
    let raw = (-0.0_f32).to_bits();
    assert_eq!(
        mdts32_run::<SerialMemory>(&[raw, MAX_KEY]).0,
        [MAX_KEY, raw]
    );
    assert_eq!(mdts32_run::<SerialMemory>(&[0, MAX_KEY]).0, [0, MAX_KEY]);
}

#[test]
fn the_smallest_subnormal_depth_has_key_one() {
    let smallest = f32::from_bits(1);
    assert!(smallest > 0.0 && !smallest.is_normal());
    assert_eq!(depth_key(smallest), Some(1));
}

#[test]
fn the_largest_depth_below_one_has_key_0x3f7fffff() {
    let below_one = 1.0 - f32::EPSILON / 2.0;
    assert_eq!(below_one.to_bits(), 0x3F7F_FFFF);
    assert_eq!(depth_key(below_one), Some(0x3F7F_FFFF));
    assert!(depth_key(below_one) < depth_key(1.0));
}

#[test]
fn depth_one_has_the_largest_key_0x3f800000() {
    assert_eq!(depth_key(1.0), Some(MAX_KEY));
    assert_eq!(depth_from_key(MAX_KEY), 1.0);
}

#[test]
fn depths_just_outside_the_unit_interval_have_no_key() {
    let above_one = f32::from_bits(0x3F80_0001);
    assert!(above_one > 1.0);
    for depth in [above_one, -f32::from_bits(1), -1e-30, 1.5, -1.0] {
        assert_eq!(depth_key(depth), None, "{depth:e}");
    }
}

#[test]
fn infinities_and_nan_have_no_key() {
    for depth in [f32::INFINITY, f32::NEG_INFINITY, f32::NAN, -f32::NAN] {
        assert_eq!(depth_key(depth), None, "{depth}");
    }
}

#[test]
fn non_finite_vertices_are_stopped_by_mesh_validation_and_by_the_pipeline() {
    // At load: every OBJ mesh is validated finite.
    for text in ["v inf 0 0\n", "v nan 0 0\n", "v 0 -inf 0\n", "v 0 0 1e39\n"] {
        let obj = format!("{text}v 1 0 0\nv 1 1 0\nf 1 2 3\n");
        let err = Mesh::read_obj(&mut obj.as_bytes(), "hostile.obj").unwrap_err();
        assert!(
            matches!(err, MeshError::NonFinite { .. }),
            "{text:?}: {err}"
        );
    }
    // A hand-built mesh that skips validation: the pipeline emits nothing and does not panic
    // (a NaN or infinite w fails the `w > 0` test before any fixed-point arithmetic).
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mesh = soup(&[[[bad, -1.0, 0.5], [3.0, -1.0, 0.5], [-1.0, 3.0, 0.5]]]);
        assert!(mesh.validate("hand-built").is_err());
        let view = identity_view(&mesh, 8, 8);
        assert!(all_fragments(&view).is_empty(), "{bad}");
        let perspective_view = View::new(
            &mesh,
            &perspective(0.1, 10.0),
            viewport(8, 8),
            CullMode::None,
        );
        assert!(all_fragments(&perspective_view).is_empty(), "{bad}");
    }
}

#[test]
fn fragments_interpolated_just_beyond_depth_one_are_dropped_one_by_one() {
    // Depth 1.0 at one corner, one ulp above 1.0 at the others: pixels near the first corner
    // round to exactly 1.0 and are kept; the rest are beyond the far plane and dropped.
    let above_one = f32::from_bits(0x3F80_0001);
    let mesh = soup(&[[
        [-1.0, 1.0, 1.0],
        [3.0, 1.0, above_one],
        [-1.0, -3.0, above_one],
    ]]);
    let view = identity_view(&mesh, 16, 16);
    let kept = all_fragments(&view);
    assert!(
        !kept.is_empty() && kept.len() < 256,
        "kept {} of 256",
        kept.len()
    );
    assert!(kept.iter().all(|f| f.depth_key == MAX_KEY));
    // The same triangle at depth 0.5 covers all 256 pixels.
    let flat = soup(&[[[-1.0, 1.0, 0.5], [3.0, 1.0, 0.5], [-1.0, -3.0, 0.5]]]);
    assert_eq!(all_fragments(&identity_view(&flat, 16, 16)).len(), 256);
}

#[test]
fn a_triangle_touching_depth_zero_from_below_is_clipped_away() {
    let below_zero = -f32::from_bits(1);
    let mesh = soup(&[[
        [-1.0, 1.0, 0.0],
        [3.0, 1.0, below_zero],
        [-1.0, -3.0, below_zero],
    ]]);
    assert!(all_fragments(&identity_view(&mesh, 16, 16)).is_empty());
}

proptest! {
    #[test]
    fn depth_key_order_equals_depth_order_on_the_unit_interval(
        a in prop_oneof![0_u32..=MAX_KEY, Just(0x8000_0000_u32)],
        b in prop_oneof![0_u32..=MAX_KEY, Just(0x8000_0000_u32)],
    ) {
        // Including -0.0, which equals +0.0 as a float and as a key.
        let (x, y) = (f32::from_bits(a), f32::from_bits(b));
        let (kx, ky) = (depth_key(x).unwrap(), depth_key(y).unwrap());
        prop_assert_eq!(x.partial_cmp(&y), Some(kx.cmp(&ky)));
        // And the library's 32-bit MDTS, which compares keys as integers, keeps them in depth
        // order: the nearer first (f32 order computed here, not by the library).
        let (near, far) = if x <= y { (kx, ky) } else { (ky, kx) };
        prop_assert_eq!(mdts32_run::<SerialMemory>(&[kx, ky]).0, vec![near, far]);
    }
}
