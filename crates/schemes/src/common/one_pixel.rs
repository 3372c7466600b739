//! The schemes' unit tests' scene: fragments of the one pixel of a 1 × 1 viewport, given by depth
//! key and primitive, so that a test spells out only what it is about (the keys and the order).

use fragsim_raster::{Fragment, Viewport};

/// A fragment of pixel 0.
pub(crate) fn fragment(depth_key: u32, prim: u32) -> Fragment {
    Fragment {
        pixel: 0,
        depth_key,
        prim,
    }
}

/// The 1 × 1 viewport that [`fragment`]s fall in.
pub(crate) fn one_pixel() -> Viewport {
    Viewport::new(1, 1).unwrap()
}
