//! Prepares a mesh for `draw.c` with fragsim's own code (the `fragsim-raster` crate), so that
//! llvmpipe draws exactly the triangles fragsim scans.
//!
//! ```text
//! prep MESH WIDTH HEIGHT VIEW ELEVATION MODE OUT_SCENE OUT_COUNTS
//! ```
//!
//! - MODE `exact`: every vertex goes through fragsim's vertex stage (f64 transform by the orbit
//!   camera, projection, snapping to 1/256 pixel) and is written as the clip-space point
//!   `(X / (128 W) − 1, 1 − Y / (128 H), 0, 1)`, which a GL viewport of W × H maps back to the
//!   very same snapped window position (exact in f32 for power-of-two sides). The matrix written
//!   is the identity: llvmpipe's vertex shader still multiplies every vertex by a 4 × 4 uniform,
//!   as it would with a real camera, but the window positions it rasterizes are fragsim's.
//!   Every vertex position is checked against `View::screen_triangles`, triangle by triangle.
//! - MODE `mvp`: the model-space positions and fragsim's view-projection rounded to f32
//!   (llvmpipe transforms in f32: the same picture up to ties at pixel centres; for timing).
//!
//! OUT_COUNTS gets fragsim's depth complexity: `W × H` little-endian u32, `y · W + x`, y down,
//! from `View::rasterize` over every triangle (the fragments every capture scheme sees).
//!
//! OUT_SCENE layout (little-endian): `b"FSLPIPE1"`, u32 width, height, vertex count, triangle
//! count; 16 f32 column-major matrix; vertex count × 3 f32; triangle count × 3 u32.

use std::io::Write;
use std::path::Path;
use std::process::ExitCode;

use fragsim_raster::{OrbitCamera, Scene, Viewport, SUBPIXEL_BITS};
use glam::DVec4;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("prep: {e}");
            ExitCode::FAILURE
        }
    }
}

fn arg<T: std::str::FromStr>(args: &[String], i: usize, name: &str) -> Result<T, String> {
    args.get(i)
        .ok_or_else(|| format!("missing {name}"))?
        .parse()
        .map_err(|_| format!("bad {name}: {:?}", args[i]))
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 9 {
        return Err(
            "usage: prep MESH WIDTH HEIGHT VIEW ELEVATION exact|mvp OUT_SCENE OUT_COUNTS".into(),
        );
    }
    let mesh_path = Path::new(&args[1]);
    let width: u32 = arg(&args, 2, "WIDTH")?;
    let height: u32 = arg(&args, 3, "HEIGHT")?;
    let view_degrees: f64 = arg(&args, 4, "VIEW")?;
    let elevation: f64 = arg(&args, 5, "ELEVATION")?;
    let exact = match args[6].as_str() {
        "exact" => true,
        "mvp" => false,
        other => return Err(format!("MODE must be exact or mvp, got {other:?}")),
    };
    if exact && !(width.is_power_of_two() && height.is_power_of_two()) {
        return Err("exact mode needs power-of-two sides (f32-exact clip coordinates)".into());
    }

    let scene = Scene::from_file(mesh_path).map_err(|e| e.to_string())?;
    let viewport = Viewport::new(width, height)?;
    // Exactly what `fragsim bench/render --view V --elevation E` builds (`SceneSpec::orbit`,
    // crates/raster/src/scene_spec.rs).
    let orbit = OrbitCamera {
        angle_degrees: view_degrees,
        elevation_degrees: elevation,
        ..OrbitCamera::default()
    };
    let view = scene.view(viewport, &orbit).map_err(|e| e.to_string())?;
    let mesh = &scene.mesh;
    let aspect = f64::from(width) / f64::from(height);
    let camera = orbit.camera(mesh.bounds(), aspect);
    let vp = camera.view_projection;

    // fragsim's vertex stage, vertex by vertex (pipeline.rs `transform` and `snap`).
    let one = f64::from(1u32 << SUBPIXEL_BITS);
    let (w, h) = (f64::from(width), f64::from(height));
    let snapped: Vec<[i64; 2]> = mesh
        .positions
        .iter()
        .map(|p| {
            let c = vp * DVec4::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]), 1.0);
            let x = (c.x / c.w * 0.5 + 0.5) * w;
            let y = (0.5 - c.y / c.w * 0.5) * h;
            [(x * one).round() as i64, (y * one).round() as i64]
        })
        .collect();

    // Check them against fragsim's own screen triangles, and count fragments per pixel.
    let mut counts = vec![0u32; viewport.pixels()];
    let mut screen_triangles = 0u64;
    let mut mismatches = 0u64;
    for (prim, tri) in mesh.triangles.iter().enumerate() {
        let prim = prim as u32;
        let mut pieces = Vec::new();
        view.screen_triangles(prim, &mut |t| pieces.push(t));
        screen_triangles += pieces.len() as u64;
        let [a, b, c] = tri.map(|i| snapped[i as usize]);
        match pieces.as_slice() {
            [] => {}
            [t] => {
                if !(t.xy == [a, b, c] || t.xy == [a, c, b]) {
                    mismatches += 1;
                }
            }
            _ => {
                return Err(format!(
                    "triangle {prim} is clipped into {} pieces: exact mode cannot draw it \
                     as an indexed mesh",
                    pieces.len()
                ))
            }
        }
        view.rasterize(prim, &mut |f| counts[f.pixel as usize] += 1);
    }
    if mismatches > 0 {
        return Err(format!(
            "{mismatches} triangles differ from fragsim's screen triangles"
        ));
    }
    let fragments: u64 = counts.iter().map(|&c| u64::from(c)).sum();

    let mut out = Vec::new();
    out.extend_from_slice(b"FSLPIPE1");
    for v in [
        width,
        height,
        mesh.positions.len() as u32,
        mesh.triangles.len() as u32,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    let matrix: [f32; 16] = if exact {
        glam::Mat4::IDENTITY.to_cols_array()
    } else {
        vp.as_mat4().to_cols_array()
    };
    for m in matrix {
        out.extend_from_slice(&m.to_le_bytes());
    }
    let mut max_err = 0f64;
    for (p, s) in mesh.positions.iter().zip(&snapped) {
        let xyz: [f32; 3] = if exact {
            let x = s[0] as f64 / (128.0 * w) - 1.0;
            let y = 1.0 - s[1] as f64 / (128.0 * h);
            // Lossless: |X|, |Y| < 2^24 inside the viewport's neighbourhood.
            max_err = max_err
                .max((f64::from(x as f32) - x).abs())
                .max((f64::from(y as f32) - y).abs());
            [x as f32, y as f32, 0.0]
        } else {
            *p
        };
        for v in xyz {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    if max_err != 0.0 {
        return Err(format!(
            "clip coordinates not exact in f32 (error {max_err:e})"
        ));
    }
    for tri in &mesh.triangles {
        for i in tri {
            out.extend_from_slice(&i.to_le_bytes());
        }
    }
    write(&args[7], &out)?;
    let counts_bytes: Vec<u8> = counts.iter().flat_map(|c| c.to_le_bytes()).collect();
    write(&args[8], &counts_bytes)?;
    println!(
        "{{\"mesh\": {:?}, \"vertices\": {}, \"triangles\": {}, \"screen_triangles\": {}, \
         \"width\": {width}, \"height\": {height}, \"view\": {view_degrees}, \
         \"elevation\": {elevation}, \"mode\": {:?}, \"fragments\": {fragments}, \
         \"covered_pixels\": {}, \"max_depth_complexity\": {}}}",
        args[1],
        mesh.positions.len(),
        mesh.triangles.len(),
        screen_triangles,
        args[6],
        counts.iter().filter(|&&c| c > 0).count(),
        counts.iter().max().copied().unwrap_or(0),
    );
    Ok(())
}

fn write(path: &str, bytes: &[u8]) -> Result<(), String> {
    std::fs::File::create(path)
        .and_then(|mut f| f.write_all(bytes))
        .map_err(|e| format!("{path}: {e}"))
}
