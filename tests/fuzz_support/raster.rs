//! The `rasterize` target: arbitrary small meshes through an identity or arbitrary camera on a
//! viewport of at most 64 × 64 pixels. No panic; every fragment inside the viewport, of the right
//! primitive, with a depth key of at most `0x3F80_0000` (depth 1.0). With the identity camera and
//! a triangle that needs no clipping, coverage equals [`reference_coverage`] pixel for pixel and
//! every depth lies between the vertices' depths.

use fragsim::raster::{CullMode, Fragment, Mesh, View, Viewport, GUARD_BAND_PIXELS, SUBPIXEL_BITS};

use super::camera::{camera_from_columns, identity_camera};
use super::input::Input;

/// The key of depth 1.0, the largest a fragment may carry.
pub(crate) const MAX_KEY: u32 = 0x3F80_0000;

/// Rasterizes `prim` of `view` and checks the invariants every fragment must meet.
pub(crate) fn check_fragments(view: &View<'_>, prim: u32) -> Vec<Fragment> {
    let pixels = view.viewport().pixels();
    let mut fragments = Vec::new();
    view.rasterize(prim, &mut |f| fragments.push(f));
    for f in &fragments {
        assert!((f.pixel as usize) < pixels, "{f:?} outside {pixels} pixels");
        assert!(f.depth_key <= MAX_KEY, "{f:?}: key above depth 1.0");
        assert!(
            (0.0..=1.0).contains(&f.depth()),
            "{f:?}: depth outside [0, 1]"
        );
        assert_eq!(f.prim, prim, "{f:?} carries the wrong primitive id");
    }
    fragments
}

/// A depth for the identity camera: mostly an exact grid over `[0, 1]` (0 and 1 included), else
/// raw f32 bits, which may lie outside `[0, 1]` (such triangles are checked for invariants only).
fn depth(input: &mut Input<'_>) -> f32 {
    match input.u8() {
        b @ 0..=250 => f32::from(b) / 250.0,
        _ => {
            let raw = f32::from_bits(input.u32());
            if raw.is_finite() {
                raw
            } else {
                0.0
            }
        }
    }
}

/// Decodes a viewport, a cull mode, a camera and a mesh from `data`, rasterizes every triangle
/// and checks it.
pub(crate) fn check(data: &[u8]) {
    let mut input = Input::new(data);
    let width = 1 + u32::from(input.u8() % 64);
    let height = 1 + u32::from(input.u8() % 64);
    let viewport = Viewport::new(width, height).expect("sides in 1..=64");
    let flags = input.u8();
    let cull = [CullMode::None, CullMode::Back, CullMode::Front][usize::from(flags % 3)];
    let identity = flags & 0x10 == 0;
    let camera = if identity {
        identity_camera()
    } else {
        let mut columns = [[0.0; 4]; 4];
        for value in columns.iter_mut().flatten() {
            *value = f64::from(input.coordinate());
        }
        camera_from_columns(columns)
    };
    let vertices = 3 + usize::from(input.u8() % 14);
    let vertex_count = u32::try_from(vertices).expect("3 to 16 vertices");
    let triangles = 1 + usize::from(input.u8() % 8);
    let positions: Vec<[f32; 3]> = (0..vertices)
        .map(|_| {
            let (x, y) = (input.coordinate(), input.coordinate());
            let z = if identity {
                depth(&mut input)
            } else {
                input.coordinate()
            };
            [x, y, z]
        })
        .collect();
    let triangles: Vec<[u32; 3]> = (0..triangles)
        .map(|_| [(); 3].map(|()| u32::from(input.u8()) % vertex_count))
        .collect();
    let mesh = Mesh {
        positions,
        triangles,
    };
    mesh.validate("fuzz")
        .expect("decoded meshes are finite and in range");
    let view = View::new(&mesh, &camera, viewport, cull);
    for prim in 0..view.triangle_count() {
        let fragments = check_fragments(&view, prim);
        if !identity {
            continue;
        }
        let corners = mesh.triangles[prim as usize].map(|i| mesh.positions[i as usize]);
        let Some(expected) = reference_coverage(corners, viewport, cull) else {
            continue;
        };
        let mut got: Vec<u32> = fragments.iter().map(|f| f.pixel).collect();
        got.sort_unstable();
        assert_eq!(
            got, expected,
            "coverage of {corners:?} on {viewport:?}, {cull:?}"
        );
        let (lo, hi) = corners
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), c| {
                (lo.min(c[2]), hi.max(c[2]))
            });
        for f in &fragments {
            assert!(
                (lo..=hi).contains(&f.depth()),
                "{f:?}: depth {} outside the vertices' [{lo}, {hi}]",
                f.depth()
            );
        }
    }
}

/// The pixels (row-major indices, ascending) that triangle `corners` covers under the identity
/// camera, by brute force over every pixel centre of the viewport, or `None` when the triangle
/// would be clipped (a depth outside `[0, 1]`, or a vertex outside the guard band) and the
/// brute-force test does not apply.
///
/// Written from `docs/semantics.md` alone: snapping (rule 3) as specified, then an exact i128
/// point-in-triangle test whose shared-edge rule is stated geometrically — a centre on an edge is
/// covered when the edge is a top edge (horizontal, the triangle below it) or a left edge (the
/// triangle to its right) — so it does not depend on the pipeline's reorientation or bias trick.
pub(crate) fn reference_coverage(
    corners: [[f32; 3]; 3],
    viewport: Viewport,
    cull: CullMode,
) -> Option<Vec<u32>> {
    let (width, height) = (f64::from(viewport.width), f64::from(viewport.height));
    let guard = [
        1.0 + 2.0 * GUARD_BAND_PIXELS / width,
        1.0 + 2.0 * GUARD_BAND_PIXELS / height,
    ];
    let unclipped = corners.iter().all(|&[x, y, z]| {
        (0.0..=1.0).contains(&z) && f64::from(x).abs() <= guard[0] && f64::from(y).abs() <= guard[1]
    });
    if !unclipped {
        return None;
    }
    let one = f64::from(1_u32 << SUBPIXEL_BITS);
    // With w = 1, x / w = x exactly; rounding is half away from zero, as `f64::round`.
    #[expect(
        clippy::cast_possible_truncation,
        reason = "an unclipped corner lies within the guard band (16384 pixels past the \
                  viewport), so its subpixel coordinates are far inside i64"
    )]
    let snap = |[x, y, _]: [f32; 3]| -> [i128; 2] {
        let wx = (f64::from(x) * 0.5 + 0.5) * width;
        let wy = (0.5 - f64::from(y) * 0.5) * height;
        [
            i128::from((wx * one).round() as i64),
            i128::from((wy * one).round() as i64),
        ]
    };
    let [a, b, c] = corners.map(snap);
    let cross = |p: [i128; 2], q: [i128; 2], r: [i128; 2]| {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    };
    let area = cross(a, b, c);
    if area == 0 {
        return Some(Vec::new());
    }
    // In the y-down window a negative area is counter-clockwise as seen: a front face.
    let front = area < 0;
    if matches!(
        (cull, front),
        (CullMode::Back, false) | (CullMode::Front, true)
    ) {
        return Some(Vec::new());
    }
    // Each edge with the vertex opposite it.
    let edges = [(a, b, c), (b, c, a), (c, a, b)];
    let owns_boundary = |p: [i128; 2], q: [i128; 2], r: [i128; 2]| {
        let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
        if dy == 0 {
            r[1] > p[1]
        } else {
            let h = (r[0] - p[0]) * dy - (r[1] - p[1]) * dx;
            (h > 0) == (dy > 0)
        }
    };
    let full = i128::from(1_u32 << SUBPIXEL_BITS);
    let mut covered = Vec::new();
    for j in 0..viewport.height {
        for i in 0..viewport.width {
            let centre = [
                i128::from(i) * full + full / 2,
                i128::from(j) * full + full / 2,
            ];
            let inside = edges.iter().all(|&(p, q, r)| {
                let side = cross(p, q, centre);
                let interior = cross(p, q, r);
                side.signum() == interior.signum() || side == 0 && owns_boundary(p, q, r)
            });
            if inside {
                covered.push(j * viewport.width + i);
            }
        }
    }
    Some(covered)
}
