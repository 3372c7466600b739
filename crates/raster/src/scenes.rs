//! Scenes: the embedded default mesh, meshes on disk and procedural scenes.

use std::f64::consts::PI;
use std::io::Read;
use std::path::Path;

use crate::camera::{Camera, OrbitCamera};
use crate::conventions::{Conventions, ConventionsError, DepthRange};
use crate::mesh::{is_ply, read_mesh_file, Mesh, MeshError, UpAxis};
use crate::pipeline::{CullMode, View};
use crate::rng::SplitMix64;
use crate::viewport::{Viewport, ViewportError};
use glam::{DMat4, DVec4};

/// The name of the embedded default scene.
pub const DEFAULT_SCENE_NAME: &str = "bunny";

/// The Stanford bunny (Turk & Levoy 1994; 35,947 vertices, 69,451 triangles), gzipped OBJ.
/// Credit: Stanford Computer Graphics Laboratory, free for research use.
const BUNNY_OBJ_GZ: &[u8] = include_bytes!("../assets/stanford-bunny.obj.gz");

/// Why a scene could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The mesh could not be loaded.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The scene name or its parameters are not understood.
    #[error("unknown scene {0:?}: expected bunny, bunny-spheres[:N[:SEED]], spheres[:N], soup[:COUNT[:SEED]] or quads[:N]")]
    Unknown(String),
    /// A parameter is out of range.
    #[error("scene {name}: {reason}")]
    BadParameter {
        /// The scene.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// The viewport is invalid.
    #[error(transparent)]
    Viewport(#[from] ViewportError),
    /// fragsim cannot rasterize the scene under the conventions asked for.
    #[error("scene {name}: {source}")]
    Conventions {
        /// The scene.
        name: String,
        /// Why the conventions are refused.
        source: ConventionsError,
    },
}

/// A named mesh: what the pipeline renders.
#[derive(Clone, Debug)]
pub struct Scene {
    /// A short description (file name or procedural parameters).
    pub name: String,
    /// The geometry.
    pub mesh: Mesh,
}

impl Scene {
    /// The embedded Stanford bunny.
    ///
    /// # Panics
    /// Never in a correct build: the embedded asset is checked by a unit test.
    #[must_use]
    pub fn default_scene() -> Self {
        let mut text = Vec::new();
        flate2::read::GzDecoder::new(BUNNY_OBJ_GZ)
            .read_to_end(&mut text)
            .expect("the embedded bunny is valid gzip");
        let mesh = Mesh::read_obj(&mut text.as_slice(), "embedded stanford-bunny.obj")
            .expect("embedded bunny parses");
        Self {
            name: DEFAULT_SCENE_NAME.into(),
            mesh,
        }
    }

    /// A mesh from a file, told by its content, not its name: gzipped or not, PLY (ASCII or
    /// binary: the first line is `ply`) or OBJ (anything else).
    ///
    /// # Errors
    /// See [`Mesh::load_obj`] and [`Mesh::load_ply`].
    pub fn from_file(path: &Path) -> Result<Self, SceneError> {
        let bytes = read_mesh_file(path)?;
        let name = path.display().to_string();
        let mesh = if is_ply(&bytes) {
            Mesh::read_ply(bytes.as_slice(), &name)?
        } else {
            Mesh::read_obj(&mut bytes.as_slice(), &name)?
        };
        Ok(Self {
            name: path.display().to_string(),
            mesh,
        })
    }

    /// A scene by name: `bunny` (embedded), `bunny-spheres[:N[:SEED]]` (the bunny with N random
    /// spheres, default 500), `spheres[:N]` (N nested closed spheres: depth
    /// complexity 2N at the centre), `soup[:COUNT[:SEED]]` (random triangles in a cube) or
    /// `quads[:N]` (N stacked parallel squares).
    ///
    /// # Errors
    /// An unknown name or a parameter out of range.
    pub fn procedural(spec: &str) -> Result<Self, SceneError> {
        let mesh = match Procedural::parse(spec)? {
            Procedural::Bunny => return Ok(Self::default_scene()),
            Procedural::BunnySpheres { count, seed } => {
                bunny_with_spheres(&Self::default_scene().mesh, count, seed)
            }
            Procedural::Spheres { count } => nested_spheres(count, SPHERE_SLICES, SPHERE_STACKS),
            Procedural::Soup { count, seed } => triangle_soup(count, seed),
            Procedural::Quads { count } => stacked_quads(count),
        };
        Ok(Self {
            name: spec.into(),
            mesh,
        })
    }

    /// What the scene `spec` names would hold, from its name alone: nothing is built, so a
    /// caller can bound a scene's memory before making it.
    ///
    /// # Errors
    /// As [`Scene::procedural`].
    pub fn procedural_size(spec: &str) -> Result<SceneSize, SceneError> {
        let (vertices, triangles) = match Procedural::parse(spec)? {
            Procedural::Bunny => (BUNNY_VERTICES, BUNNY_TRIANGLES),
            Procedural::BunnySpheres { count, .. } => {
                let (v, t) = sphere_size(BALL_SLICES, BALL_STACKS);
                let count = u64::from(count);
                (BUNNY_VERTICES + count * v, BUNNY_TRIANGLES + count * t)
            }
            Procedural::Spheres { count } => {
                let (v, t) = sphere_size(SPHERE_SLICES, SPHERE_STACKS);
                (u64::from(count) * v, u64::from(count) * t)
            }
            Procedural::Soup { count, .. } => (3 * u64::from(count), u64::from(count)),
            Procedural::Quads { count } => (4 * u64::from(count), 2 * u64::from(count)),
        };
        // A quad's two triangles share its diagonal, whose samples the fill rule gives to one of
        // them (clipped pieces tile the quad alike): a sample is in at most one of them.
        let layers = match Procedural::parse(spec)? {
            Procedural::Quads { count } => u64::from(count),
            _ => triangles,
        };
        Ok(SceneSize {
            vertices,
            triangles,
            layers,
        })
    }

    /// This scene through an orbit camera on a viewport, all faces kept.
    ///
    /// # Errors
    /// The scene has no triangles.
    pub fn view(&self, viewport: Viewport, orbit: &OrbitCamera) -> Result<View<'_>, SceneError> {
        self.view_under(
            viewport,
            &self.orbit_camera(viewport, orbit, DepthRange::ZeroToOne),
            Conventions::REFERENCE,
        )
    }

    /// The matrix `orbit` gives this scene on `viewport` for `depth_range` (the camera
    /// [`Scene::view`] uses, for [`DepthRange::ZeroToOne`]).
    #[must_use]
    pub fn orbit_camera(
        &self,
        viewport: Viewport,
        orbit: &OrbitCamera,
        depth_range: DepthRange,
    ) -> Camera {
        let aspect = f64::from(viewport.width) / f64::from(viewport.height);
        orbit.camera_for(self.mesh.bounds(), aspect, depth_range)
    }

    /// [`Scene::orbit_camera`] around the model stood on its `up` axis: the orbit of the model
    /// turned onto +y ([`UpAxis::turn`]), the turn folded into the matrix, so the mesh, its
    /// primitive ids and its file stay as they are. For [`UpAxis::Y`], exactly
    /// [`Scene::orbit_camera`].
    #[must_use]
    pub fn orbit_camera_up(
        &self,
        viewport: Viewport,
        orbit: &OrbitCamera,
        depth_range: DepthRange,
        up: UpAxis,
    ) -> Camera {
        if up == UpAxis::Y {
            return self.orbit_camera(viewport, orbit, depth_range);
        }
        let aspect = f64::from(viewport.width) / f64::from(viewport.height);
        let turned = orbit.camera_for(up.turn_bounds(self.mesh.bounds()), aspect, depth_range);
        let rows = up.rows();
        let turn = DMat4::from_cols(
            DVec4::new(rows[0][0], rows[1][0], rows[2][0], 0.0),
            DVec4::new(rows[0][1], rows[1][1], rows[2][1], 0.0),
            DVec4::new(rows[0][2], rows[1][2], rows[2][2], 0.0),
            DVec4::W,
        );
        Camera {
            view_projection: turned.view_projection * turn,
        }
    }

    /// This scene through any camera on a viewport under `conventions`, all faces kept.
    ///
    /// # Errors
    /// The scene has no triangles, or fragsim cannot rasterize under the conventions.
    pub fn view_under(
        &self,
        viewport: Viewport,
        camera: &Camera,
        conventions: Conventions,
    ) -> Result<View<'_>, SceneError> {
        let bad = |reason: String| SceneError::BadParameter {
            name: self.name.clone(),
            reason,
        };
        if self.mesh.triangles.is_empty() {
            return Err(bad("no triangles".into()));
        }
        View::with_conventions(&self.mesh, camera, viewport, CullMode::None, conventions).map_err(
            |source| SceneError::Conventions {
                name: self.name.clone(),
                source,
            },
        )
    }

    /// A warning when `view` (of this scene) rasterizes no fragment at all: every triangle lies
    /// outside it or covers no pixel centre (a far outlier such as a 1e38 coordinate shrinks the
    /// fitted camera's view of the rest below a pixel). Every output is then empty, which is
    /// better said than left to be noticed.
    #[must_use]
    pub fn empty_view_warning(&self, view: &View<'_>) -> Option<String> {
        // Stops at the first triangle that covers a pixel: one or a few for a visible scene.
        let empty = (0..view.triangle_count()).all(|prim| {
            let mut covered = false;
            view.rasterize(prim, &mut |_| covered = true);
            !covered
        });
        let viewport = view.viewport();
        empty.then(|| {
            format!(
                "scene {}: none of its {} triangles covers a pixel of the {}x{} view \
                 (outside it, or smaller than a pixel); every output is empty",
                self.name,
                view.triangle_count(),
                viewport.width,
                viewport.height
            )
        })
    }
}

/// Vertices of the embedded bunny that its faces use.
const BUNNY_VERTICES: u64 = 34_834;
/// Triangles of the embedded bunny.
const BUNNY_TRIANGLES: u64 = 69_451;
/// Slices and stacks of each sphere of `spheres:N`.
const SPHERE_SLICES: u32 = 48;
const SPHERE_STACKS: u32 = 24;
/// Slices and stacks of each sphere `bunny-spheres:N` adds.
const BALL_SLICES: u32 = 16;
const BALL_STACKS: u32 = 8;

/// Vertices and triangles of one sphere of [`nested_spheres`].
fn sphere_size(slices: u32, stacks: u32) -> (u64, u64) {
    let (slices, stacks) = (u64::from(slices), u64::from(stacks));
    (2 + (stacks - 1) * slices, slices * (2 + 2 * (stacks - 2)))
}

/// What a named scene holds, known from its name ([`Scene::procedural_size`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneSize {
    /// Vertices of its mesh.
    pub vertices: u64,
    /// Triangles of its mesh.
    pub triangles: u64,
    /// At most how many of its triangles cover one sample: a bound on any list's fragments.
    pub layers: u64,
}

impl SceneSize {
    /// Bytes of its mesh: the positions and the vertex indices.
    #[must_use]
    pub fn mesh_bytes(&self) -> u64 {
        let vertex = std::mem::size_of::<[f32; 3]>() as u64;
        let triangle = std::mem::size_of::<[u32; 3]>() as u64;
        self.vertices
            .saturating_mul(vertex)
            .saturating_add(self.triangles.saturating_mul(triangle))
    }
}

/// A scene name parsed, its parameters checked.
enum Procedural {
    Bunny,
    BunnySpheres { count: u32, seed: u64 },
    Spheres { count: u32 },
    Soup { count: u32, seed: u64 },
    Quads { count: u32 },
}

impl Procedural {
    #[expect(
        clippy::cast_possible_truncation,
        reason = "each count is at most its parameter's bound (the third argument of `param`), at most 10 million"
    )]
    fn parse(spec: &str) -> Result<Self, SceneError> {
        let mut parts = spec.split(':');
        let kind = parts.next().unwrap_or_default();
        let params: Vec<&str> = parts.collect();
        let param = |i: usize, default: u64, max: u64| -> Result<u64, SceneError> {
            let value = match params.get(i) {
                None => default,
                Some(text) => text.parse::<u64>().map_err(|_| SceneError::BadParameter {
                    name: spec.into(),
                    reason: format!(
                        "parameter {} is not a non-negative integer: {text:?}",
                        i + 1
                    ),
                })?,
            };
            if value == 0 && i == 0 || value > max {
                return Err(SceneError::BadParameter {
                    name: spec.into(),
                    reason: format!(
                        "parameter {} must be between 1 and {max}, got {value}",
                        i + 1
                    ),
                });
            }
            Ok(value)
        };
        Ok(match kind {
            "bunny" if params.is_empty() => Self::Bunny,
            "bunny-spheres" => Self::BunnySpheres {
                count: param(0, 500, 100_000)? as u32,
                seed: param(1, 1, u64::MAX)?,
            },
            "spheres" => Self::Spheres {
                count: param(0, 4, 256)? as u32,
            },
            "soup" => Self::Soup {
                count: param(0, 2000, 10_000_000)? as u32,
                seed: param(1, 1, u64::MAX)?,
            },
            "quads" => Self::Quads {
                count: param(0, 8, 1_000_000)? as u32,
            },
            _ => return Err(SceneError::Unknown(spec.into())),
        })
    }
}

/// `count` closed UV spheres centred at the origin with radii `1/count, 2/count, …, 1`.
#[must_use]
#[expect(
    clippy::cast_possible_truncation,
    reason = "at most 256 spheres (Scene::Spheres) of (stacks - 1) × slices + 2 vertices each fit u32; positions are f32, as the mesh stores them"
)]
pub(crate) fn nested_spheres(count: u32, slices: u32, stacks: u32) -> Mesh {
    let mut mesh = Mesh::default();
    for s in 1..=count {
        let radius = f64::from(s) / f64::from(count);
        let base = mesh.positions.len() as u32;
        // Poles are single vertices so the sphere is closed (watertight).
        mesh.positions.push([0.0, radius as f32, 0.0]);
        for i in 1..stacks {
            let theta = PI * f64::from(i) / f64::from(stacks);
            for j in 0..slices {
                let phi = 2.0 * PI * f64::from(j) / f64::from(slices);
                let p = [
                    radius * theta.sin() * phi.cos(),
                    radius * theta.cos(),
                    radius * theta.sin() * phi.sin(),
                ];
                mesh.positions.push(p.map(|c| c as f32));
            }
        }
        mesh.positions.push([0.0, -radius as f32, 0.0]);
        let ring = |i: u32, j: u32| base + 1 + (i - 1) * slices + (j % slices);
        let south = base + 1 + (stacks - 1) * slices;
        for j in 0..slices {
            mesh.triangles.push([base, ring(1, j + 1), ring(1, j)]);
            for i in 1..stacks - 1 {
                mesh.triangles
                    .push([ring(i, j), ring(i, j + 1), ring(i + 1, j + 1)]);
                mesh.triangles
                    .push([ring(i, j), ring(i + 1, j + 1), ring(i + 1, j)]);
            }
            mesh.triangles
                .push([ring(stacks - 1, j), ring(stacks - 1, j + 1), south]);
        }
    }
    mesh
}

/// The bucket depth peeling paper's "bunny with 500 spheres" (HPG 2009, Table 2): `mesh` (the
/// bunny) and `count` closed UV spheres (16 slices, 8 stacks: 224 triangles each) with centres
/// uniform in the mesh's bounding box and radii uniform in 2–6 % of its diagonal, from `seed`.
/// The paper gives neither the spheres' sizes nor their placement; these make a scene of high
/// depth complexity around and through the bunny.
#[must_use]
#[expect(
    clippy::cast_possible_truncation,
    reason = "at most 100,000 spheres (Scene::BunnySpheres) of a few hundred vertices each beside the bunny's fit u32; positions are f32, as the mesh stores them"
)]
pub(crate) fn bunny_with_spheres(bunny: &Mesh, count: u32, seed: u64) -> Mesh {
    let (lo, hi) = bunny.bounds();
    let diagonal = (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt();
    let unit = nested_spheres(1, BALL_SLICES, BALL_STACKS);
    let mut rng = SplitMix64::new(seed);
    let mut mesh = bunny.clone();
    for _ in 0..count {
        let centre: [f64; 3] = std::array::from_fn(|i| lo[i] + (hi[i] - lo[i]) * rng.next_f64());
        let radius = diagonal * (0.02 + 0.04 * rng.next_f64());
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(
            unit.positions
                .iter()
                .map(|p| std::array::from_fn(|i| (centre[i] + radius * f64::from(p[i])) as f32)),
        );
        mesh.triangles
            .extend(unit.triangles.iter().map(|t| t.map(|i| base + i)));
    }
    mesh
}

/// `count` triangles with vertices uniform in the unit cube, from `seed`.
#[must_use]
#[expect(
    clippy::cast_possible_truncation,
    reason = "positions are f32, as the mesh stores them"
)]
pub(crate) fn triangle_soup(count: u32, seed: u64) -> Mesh {
    let mut rng = SplitMix64::new(seed);
    let mut mesh = Mesh::default();
    for t in 0..count {
        for _ in 0..3 {
            mesh.positions
                .push([rng.next_f64(), rng.next_f64(), rng.next_f64()].map(|c| c as f32));
        }
        mesh.triangles.push([3 * t, 3 * t + 1, 3 * t + 2]);
    }
    mesh
}

/// `count` unit squares parallel to the xy plane, stacked along z in `[0, 1]`.
#[must_use]
pub(crate) fn stacked_quads(count: u32) -> Mesh {
    let mut mesh = Mesh::default();
    for q in 0..count {
        let z = if count == 1 {
            0.0
        } else {
            q as f32 / (count - 1) as f32
        };
        let base = 4 * q;
        mesh.positions.extend([
            [-1.0, -1.0, z],
            [1.0, -1.0, z],
            [1.0, 1.0, z],
            [-1.0, 1.0, z],
        ]);
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.triangles.push([base, base + 2, base + 3]);
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_bunny_is_the_full_stanford_bunny() {
        let scene = Scene::default_scene();
        assert_eq!(scene.mesh.triangles.len(), 69_451);
        // The file lists 35,947 vertices; tobj keeps the 34,834 that faces use.
        assert_eq!(scene.mesh.positions.len(), 34_834);
    }

    #[test]
    fn names_parse_and_bad_ones_fail() {
        assert_eq!(
            Scene::procedural("spheres:3").unwrap().mesh.triangles.len(),
            3 * 48 * 2 * 23
        );
        assert_eq!(
            Scene::procedural("quads:5").unwrap().mesh.triangles.len(),
            10
        );
        assert_eq!(
            Scene::procedural("soup:7:9").unwrap().mesh.triangles.len(),
            7
        );
        let spheres = Scene::procedural("bunny-spheres:3:2").unwrap();
        assert_eq!(spheres.mesh.triangles.len(), 69_451 + 3 * 224);
        assert_ne!(
            spheres.mesh,
            Scene::procedural("bunny-spheres:3:5").unwrap().mesh
        );
        for name in [
            "bunny",
            "bunny-spheres:3:2",
            "spheres:3",
            "quads:5",
            "soup:7:9",
        ] {
            let mesh = Scene::procedural(name).unwrap().mesh;
            let size = Scene::procedural_size(name).unwrap();
            assert_eq!(
                (size.vertices, size.triangles),
                (mesh.positions.len() as u64, mesh.triangles.len() as u64),
                "{name}"
            );
        }
        assert_eq!(
            Scene::procedural_size("quads:1000000").unwrap().layers,
            1_000_000
        );
        assert!(Scene::procedural_size("soup:10000001").is_err());
        assert!(Scene::procedural("spheres:0").is_err());
        assert!(Scene::procedural("cubes").is_err());
        assert!(Scene::procedural("soup:x").is_err());
    }
}
