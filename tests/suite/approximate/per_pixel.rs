//! The approximate schemes per pixel, through `fragsim::shade::approximate`: MLAB and tail
//! blending exact then and only then (every prefix of at most `K` fragments bit-identical to the
//! exact colour, some order of more off, in twelve orders of six fragments), MLAB's one failure (a
//! fragment landing inside a merged node), WBOIT exact for one fragment only, and submission order
//! as recorded.

use fragsim::capture::primitive_order::PrimitiveOrder;
use fragsim::raster::Fragment;
use fragsim::shade::approximate::{in_submission_order, wboit_weight, Approximation};
use fragsim::shade::effects::{encode_srgb, shade_pixel, Effect, Entries, Geometry, Material};

fn flat(_: f32) -> f64 {
    0.0
}

fn facing(_: usize, _: u64) -> f64 {
    1.0
}

/// The exact transparency of `entries` (any order: sorted first, as the oracle's lists are).
fn exact(material: &Material, entries: &[u64]) -> [f32; 3] {
    let mut sorted = entries.to_vec();
    sorted.sort_unstable();
    let geometry = Geometry {
        distance: &flat,
        cosine: &facing,
    };
    shade_pixel(
        Effect::Transparency,
        material,
        Entries::KeyAndPrim,
        0,
        &sorted,
        geometry,
    )
    .expect("transparency resolves key-and-prim entries")
}

/// An entry at window depth `d` of primitive `prim`.
fn entry(d: f32, prim: u32) -> u64 {
    (u64::from(d.to_bits()) << 32) | u64::from(prim)
}

fn material() -> Material {
    Material {
        primitives: 6,
        ..Material::default()
    }
}

/// Every arrival order of six fragments of distinct colours (a sample of the 720: each
/// rotation, forwards and backwards), at depths far to near.
fn orders() -> Vec<Vec<u64>> {
    let base: Vec<u64> = (0..6).map(|i| entry(0.9 - 0.1 * i as f32, i)).collect();
    let mut all = Vec::new();
    for r in 0..6 {
        let mut order = base.clone();
        order.rotate_left(r);
        all.push(order.clone());
        order.reverse();
        all.push(order);
    }
    all
}

/// MLAB and tail blending with `K` nodes give the exact colour's bits for every prefix of
/// at most `K` fragments, in every order, and, for some order of more than `K`, a colour
/// that is not the exact one: exact then and only then.
#[test]
fn mlab_and_tail_blend_are_exact_up_to_k_fragments_and_only_then() {
    let m = material();
    for k in 1..=4_u32 {
        for approximation in [Approximation::Mlab { k }, Approximation::TailBlend { k }] {
            let mut differ = false;
            for order in orders() {
                for n in 0..=order.len() {
                    let prefix = &order[..n];
                    let got = approximation.shade_pixel(&m, prefix);
                    if n <= k as usize {
                        assert_eq!(got, exact(&m, prefix), "{approximation:?} {prefix:x?}");
                    } else {
                        differ |= got.map(encode_srgb) != exact(&m, prefix).map(encode_srgb);
                    }
                }
            }
            assert!(differ, "{approximation:?}: never off beyond K");
        }
    }
}

/// MLAB merges the two farthest: arriving in depth order (near to far or far to near), every
/// merge is of neighbours in depth and the result is the exact colour (to rounding). A
/// fragment arriving between two merged ones is what it gets wrong.
#[test]
fn mlab_is_exact_in_depth_order_and_off_when_a_fragment_lands_inside_a_merged_node() {
    let m = material();
    let mlab = Approximation::Mlab { k: 2 };
    let far_to_near = [entry(0.9, 0), entry(0.8, 1), entry(0.7, 2), entry(0.6, 3)];
    let near = |a: [f32; 3], b: [f32; 3]| (0..3).all(|ch| (a[ch] - b[ch]).abs() < 1e-5);
    let exact_colour = exact(&m, &far_to_near);
    let mut near_to_far = far_to_near;
    near_to_far.reverse();
    assert!(near(mlab.shade_pixel(&m, &near_to_far), exact_colour));
    assert!(near(mlab.shade_pixel(&m, &far_to_near), exact_colour));
    // 0.9 and 0.6 merge into one node at 0.6 when 0.1 arrives; 0.8 then lands behind the
    // merged node, so 0.9 is blended over it: out of place.
    let inside = [entry(0.9, 0), entry(0.6, 3), entry(0.1, 4), entry(0.8, 1)];
    assert_ne!(
        mlab.shade_pixel(&m, &inside).map(encode_srgb),
        exact(&m, &inside).map(encode_srgb)
    );
}

/// WBOIT is exact for one fragment (its average is the fragment's colour, its revealage
/// `1 − α`) and not for two of different colours; its weight falls with depth and is
/// clamped at 10⁻² α far away.
#[test]
fn wboit_is_exact_for_one_fragment_only_and_weights_near_fragments_more() {
    let m = material();
    let one = [entry(0.5, 2)];
    let got = Approximation::Wboit.shade_pixel(&m, &one);
    assert!((0..3).all(|ch| (got[ch] - exact(&m, &one)[ch]).abs() < 1e-6));
    let two = [entry(0.2, 0), entry(0.5, 3)];
    assert_ne!(
        Approximation::Wboit.shade_pixel(&m, &two).map(encode_srgb),
        exact(&m, &two).map(encode_srgb)
    );
    // Order independent up to rounding: the sums commute.
    let swapped = [two[1], two[0]];
    let (a, b) = (
        Approximation::Wboit.shade_pixel(&m, &two),
        Approximation::Wboit.shade_pixel(&m, &swapped),
    );
    assert!((0..3).all(|ch| (a[ch] - b[ch]).abs() < 1e-6));
    assert!(wboit_weight(0.5, 0.1) > wboit_weight(0.5, 0.5));
    assert_eq!(wboit_weight(0.5, 1.0), 0.5e-2);
    assert_eq!(
        Approximation::Wboit.shade_pixel(&m, &[]),
        m.background,
        "an empty pixel is the background"
    );
}

/// Submission order puts a pixel's entries in the recorded stream's order, whatever order
/// they are handed in.
#[test]
fn submission_order_is_the_recorded_streams() {
    let frag = |prim, depth_key| Fragment {
        pixel: 0,
        depth_key,
        prim,
    };
    let stream = [frag(7, 30), frag(2, 10), frag(5, 20)];
    let order = PrimitiveOrder::of_fragments(1, &stream);
    let sorted: Vec<u64> = {
        let mut v: Vec<u64> = stream.iter().map(|f| f.packed()).collect();
        v.sort_unstable();
        v
    };
    let arrivals = in_submission_order(&order, 0, &sorted);
    let expected: Vec<u64> = stream.iter().map(|f| f.packed()).collect();
    assert_eq!(arrivals, expected);
}
