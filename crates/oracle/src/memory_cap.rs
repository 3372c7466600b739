//! The memory cap over the oracle's own storage, checked before the oracle is built, and over a
//! named scene, checked from its name before it is made (`--memory-cap` of `render`, `bench`,
//! `sweep` and `compare`).
//!
//! The oracle keeps every fragment of the view (8 bytes each) plus three words a pixel (its
//! offsets, and the counts and cursors of its two passes). The fragments are not known before
//! rasterizing, and an adversarial mesh (thousands of coincident screen-filling triangles) makes
//! counting them as slow as building the oracle; so the check bounds them instead, in one pass
//! over the screen triangles that scans no pixel: a triangle holds at most
//! `min(pixel centres in its bounding box, A + P/2 + 1)` pixel centres, where `A` is its area
//! and `P` its perimeter in pixels (the bound on lattice points in a convex region,
//! Nosarzewska 1948). Guarantee: a view whose bound fits the cap is never refused here, and one
//! refused would need at most the bytes the message names (a bound, within a few fragments a
//! triangle of the exact count on large triangles; tiny ones are each counted once at most).
//! A view that rasterizes per sample holds `samples` lists a pixel: each sample index's
//! positions are a translate of the pixel centres, so the lattice bound holds for each, and the
//! box bound with one more row and column.
//!
//! A scene named in a header (`quads:1000000`, `soup:10000000:1`) could take gigabytes and
//! minutes to make before the view's bound can be taken, so [`check_named_scene`] bounds it from
//! its name first ([`Scene::procedural_size`]): its mesh, and the oracle's fragments at most its
//! layers (the most triangles that can cover one sample) in every list. A scene whose mesh alone
//! exceeds the cap is refused; one whose name bound exceeds it is refused too when its mesh takes
//! more than [`PRECISE_SHARE`] of the cap, since making it to bound its oracle from its
//! triangles would itself be a large allocation; a smaller one is made and bounded by
//! [`check`]. Nothing is allocated before the refusal.

use fragsim_raster::{Scene, SceneSize, ScreenTriangle, View};

/// Why the oracle, or a named scene, is refused before it is made: the bound on the bytes it
/// would need, how the bound is made, and the cap.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum MemoryCapError {
    /// The oracle of a view ([`check`]).
    #[error(
        "the oracle of this view would need up to {bytes} bytes (up to {fragments} fragments \
         of {BYTES_PER_FRAGMENT} bytes, bounded from the screen triangles' areas, plus \
         {BYTES_PER_PIXEL} bytes for each of {pixels} pixels), over the memory cap of {cap} \
         bytes (--memory-cap raises it)"
    )]
    Oracle {
        /// The bound on the oracle's bytes.
        bytes: u64,
        /// The bound on the view's fragments.
        fragments: u64,
        /// The view's pixels (lists).
        pixels: u64,
        /// The cap.
        cap: u64,
    },
    /// A named scene's mesh alone ([`check_named_scene`]).
    #[error(
        "scene {name}: its mesh ({} vertices, {} triangles) would need {bytes} bytes, over the \
         memory cap of {cap} bytes (--memory-cap raises it)",
        size.vertices,
        size.triangles
    )]
    SceneMesh {
        /// The scene's name.
        name: String,
        /// What its name says it holds.
        size: SceneSize,
        /// The mesh's bytes.
        bytes: u64,
        /// The cap.
        cap: u64,
    },
    /// A named scene's mesh and the bound on its oracle, from its name ([`check_named_scene`]).
    #[error(
        "scene {name}: its mesh ({} vertices, {} triangles) and its oracle (up to {} triangles \
         over each of {lists} lists: {fragments} fragments of {BYTES_PER_FRAGMENT} bytes, plus \
         {BYTES_PER_PIXEL} bytes a list) would need {bytes} bytes, over the memory cap of {cap} \
         bytes (--memory-cap raises it)",
        size.vertices,
        size.triangles,
        size.layers
    )]
    SceneAndOracle {
        /// The scene's name.
        name: String,
        /// What its name says it holds.
        size: SceneSize,
        /// The lists (pixels, or samples) of the view.
        lists: u64,
        /// The bound on the oracle's fragments.
        fragments: u64,
        /// The bytes of the mesh and the oracle together.
        bytes: u64,
        /// The cap.
        cap: u64,
    },
}

/// Bytes of the oracle a pixel needs beside its fragments: offset, count, cursor.
const BYTES_PER_PIXEL: u64 = 24;
/// Bytes of one stored fragment (depth key and primitive id).
const BYTES_PER_FRAGMENT: u64 = 8;
/// Units of a pixel in snapped coordinates.
const SUBPIXELS: f64 = 256.0;

/// The share of the memory cap (one part in this many) that a named scene's mesh may take for the
/// scene to be made before its oracle is bounded from its triangles.
pub const PRECISE_SHARE: u64 = 256;

/// At most how many fragments `view` rasterizes (in all its lists: a sample each, when it
/// rasterizes per sample).
#[must_use]
pub fn fragments_at_most(view: &View<'_>) -> u64 {
    let viewport = view.pixel_viewport();
    let samples = view
        .samples()
        .map_or(1, |pattern| u64::from(pattern.count()));
    let slack = i64::from(samples > 1);
    let mut total = 0_u64;
    for prim in 0..view.triangle_count() {
        view.screen_triangles(prim, &mut |tri| {
            let bound = triangle_bound(&tri, viewport.width, viewport.height, slack);
            total = total.saturating_add(bound.saturating_mul(samples));
        });
    }
    total
}

/// At most how many pixel centres of a `width × height` viewport triangle `tri` covers (with
/// `slack` more rows and columns in the box: the positions of one sample index of a pixel).
fn triangle_bound(tri: &ScreenTriangle, width: u32, height: u32, slack: i64) -> u64 {
    let xs = tri.xy.map(|p| p[0]);
    let ys = tri.xy.map(|p| p[1]);
    // Pixel centres `i + 0.5` within [lo, hi] (1/256 pixel units), clamped to the viewport.
    let centres = |lo: i64, hi: i64, side: u32| -> u64 {
        let first = (lo - 128).div_euclid(256) + i64::from((lo - 128).rem_euclid(256) != 0);
        let last = (hi - 128).div_euclid(256);
        let (first, last) = (first.max(0), last.min(i64::from(side) - 1));
        u64::try_from(last - first + 1 + slack).unwrap_or(0)
    };
    let lo = |v: [i64; 3]| v.into_iter().min().unwrap_or(0);
    let hi = |v: [i64; 3]| v.into_iter().max().unwrap_or(0);
    let boxed = centres(lo(xs), hi(xs), width) * centres(lo(ys), hi(ys), height);
    let p = tri
        .xy
        .map(|v| [v[0] as f64 / SUBPIXELS, v[1] as f64 / SUBPIXELS]);
    let area = ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
        - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]))
        .abs()
        / 2.0;
    let side = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let perimeter = side(p[0], p[1]) + side(p[1], p[2]) + side(p[2], p[0]);
    let lattice = (area + perimeter / 2.0 + 1.0).floor();
    // Past u64 the box bound is the smaller anyway.
    #[expect(
        clippy::cast_possible_truncation,
        reason = "the cast is taken only below 1.8e19, under u64::MAX"
    )]
    let lattice = if lattice < 1.8e19 {
        lattice as u64
    } else {
        u64::MAX
    };
    boxed.min(lattice)
}

/// Refuses `view` when the oracle's storage could exceed `cap` bytes, before any is allocated.
///
/// # Errors
/// The bound on the oracle's bytes, with how it is made, over the cap.
pub fn check(view: &View<'_>, cap: u64) -> Result<(), MemoryCapError> {
    let fragments = fragments_at_most(view);
    let pixels = view.viewport().pixels() as u64;
    let bytes = fragments
        .saturating_mul(BYTES_PER_FRAGMENT)
        .saturating_add(pixels.saturating_mul(BYTES_PER_PIXEL));
    if bytes > cap {
        return Err(MemoryCapError::Oracle {
            bytes,
            fragments,
            pixels,
            cap,
        });
    }
    Ok(())
}

/// Refuses the named scene `name` over `lists` lists (pixels, or samples) when making it, or the
/// oracle on it, could exceed `cap` bytes, from its name alone, before anything is made (the
/// module's doc says when the name decides). A name that is no scene's passes: making it names
/// the fault.
///
/// # Errors
/// The scene's mesh, or the mesh and the oracle's bound, over the cap: the bytes, how they are
/// made, and the cap.
pub fn check_named_scene(name: &str, lists: u64, cap: u64) -> Result<(), MemoryCapError> {
    let Ok(size) = Scene::procedural_size(name) else {
        return Ok(());
    };
    let mesh = size.mesh_bytes();
    if mesh > cap {
        return Err(MemoryCapError::SceneMesh {
            name: name.into(),
            size,
            bytes: mesh,
            cap,
        });
    }
    let fragments = size.layers.saturating_mul(lists);
    let oracle = fragments
        .saturating_mul(BYTES_PER_FRAGMENT)
        .saturating_add(lists.saturating_mul(BYTES_PER_PIXEL));
    let total = mesh.saturating_add(oracle);
    if total > cap && mesh > cap / PRECISE_SHARE {
        return Err(MemoryCapError::SceneAndOracle {
            name: name.into(),
            size,
            lists,
            fragments,
            bytes: total,
            cap,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(xy: [[i64; 2]; 3]) -> ScreenTriangle {
        ScreenTriangle {
            prim: 0,
            xy,
            z: [0.5; 3],
        }
    }

    #[test]
    fn a_half_viewport_triangle_is_bounded_near_its_area() {
        // Corners of an 8 × 8 viewport: 32 pixels of area, 36 centres below the diagonal.
        let t = tri([[0, 0], [8 * 256, 0], [0, 8 * 256]]);
        let bound = triangle_bound(&t, 8, 8, 0);
        assert!((36..=64).contains(&bound), "{bound}");
    }

    #[test]
    fn a_triangle_between_centres_holds_none() {
        let t = tri([[10, 10], [100, 10], [10, 100]]);
        assert_eq!(triangle_bound(&t, 8, 8, 0), 0);
    }

    #[test]
    fn huge_named_scenes_are_refused_from_their_name_and_small_ones_pass() {
        let cap = 4 << 30;
        let quads = check_named_scene("quads:1000000", 64 * 64, cap)
            .unwrap_err()
            .to_string();
        assert!(
            quads.contains("scene quads:1000000") && quads.contains("memory cap"),
            "{quads}"
        );
        let soup = check_named_scene("soup:10000000:1", 16 * 16, cap).unwrap_err();
        assert!(
            matches!(soup, MemoryCapError::SceneAndOracle { .. }),
            "{soup:?}"
        );
        assert!(soup.to_string().contains("10000000 triangles"), "{soup}");
        // A mesh past the cap on its own, whatever the viewport.
        assert!(matches!(
            check_named_scene("soup:10000000:1", 1, 64 << 20),
            Err(MemoryCapError::SceneMesh { .. })
        ));
        // The controls: the default soup at 1024 x 1024, whose name bound exceeds the cap but
        // whose mesh is small, is left to the bound from its triangles; 1000 quads fit.
        check_named_scene("soup:2000", 1024 * 1024, cap).unwrap();
        check_named_scene("quads:1000", 64 * 64, cap).unwrap();
        check_named_scene("no-such-scene", 1, 0).unwrap();
    }

    #[test]
    fn a_triangle_off_the_viewport_holds_none() {
        let t = tri([[-4096, -4096], [-2048, -4096], [-4096, -2048]]);
        assert_eq!(triangle_bound(&t, 8, 8, 0), 0);
    }
}
