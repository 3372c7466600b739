//! One capture on the GPU: a view's geometry drawn through a scheme's WGSL fragment shader, its
//! per-pixel buffers read back as a fragsim dump (`docs/dump-format.md`).
//!
//! Two ways in ([`Mode`]): **replay** draws fragsim's own screen triangles
//! (`View::screen_triangles`: transformed in f64, clipped and snapped to 1/256 pixel) as clip
//! coordinates with `w = 1` that a power-of-two viewport maps back to the same window positions
//! with no rounding, so the GPU scans exactly fragsim's triangles; **engine** draws the mesh with
//! the orbit camera's view-projection matrix rounded to f32 in the vertex shader, as an engine
//! does (Vulkan conventions: upper-left origin, depth in [0, 1], the f32 vertex stage). Depth is
//! the GPU's own interpolation in both modes (`@builtin(position).z`).
//!
//! Guarantee: the dump holds every word the shader left, bit for bit (nothing is repaired on
//! the way back); bad requests (a replay viewport that is not a power of two, a buffer past the
//! adapter's limits, a feature the adapter lacks) are errors naming the problem.

use std::collections::BTreeMap;
use std::time::Instant;

use fragsim_oracle::dump::{ArraySpec, Dtype, Dump, Header, Words, FORMAT, VERSION};
use fragsim_oracle::scene::{SceneAndCamera, ViewProjection};
use fragsim_raster::conventions::VertexPrecision;
use fragsim_raster::{Conventions, View};

use crate::device::{Gpu, GpuError};
use crate::shaders::{GpuScheme, Storage, COMMON};

/// How the geometry reaches the GPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// fragsim's snapped screen triangles (coverage identical to fragsim's by construction).
    Replay,
    /// The mesh and the view-projection matrix in f32 in the vertex shader.
    Engine,
}

impl Mode {
    /// The name used on the command line and in dumps.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Replay => "replay",
            Self::Engine => "engine",
        }
    }
}

/// A capture's dump and what it cost.
#[derive(Debug)]
pub struct Captured {
    /// The dump (header and arrays), ready to write or compare.
    pub dump: Dump,
    /// The render pass on the GPU, from its timestamps (when the adapter has them).
    pub gpu_ms: Option<f64>,
    /// Submit to the end of the read-back, on the host.
    pub wall_ms: f64,
    /// Triangles drawn (screen triangles in replay mode, mesh triangles in engine mode).
    pub triangles: u32,
}

/// The vertex and index data of one draw.
struct Geometry {
    vertices: Vec<u8>,
    stride: u64,
    indices: Option<Vec<u32>>,
    count: u32,
    view_projection: [f32; 16],
}

/// Replay vertices: clip `(X / (128 W) − 1, 1 − Y / (128 H), z, 1)` (20 bytes with the primitive
/// id). With `W` and `H` powers of two and `|X|, |Y| ≤ 2^23` both coordinates are exact in f32
/// and the viewport transform `(x + 1) W / 2` gives `X / 256` back exactly.
fn replay_geometry(view: &View<'_>) -> Result<Geometry, GpuError> {
    let viewport = view.viewport();
    if !viewport.width.is_power_of_two() || !viewport.height.is_power_of_two() {
        return Err(GpuError(format!(
            "replay mode needs power-of-two viewport sides (exact clip coordinates), not {}x{}",
            viewport.width, viewport.height
        )));
    }
    let (sx, sy) = (
        128.0 * f64::from(viewport.width),
        128.0 * f64::from(viewport.height),
    );
    let mut vertices = Vec::new();
    let mut count = 0u32;
    for prim in 0..view.triangle_count() {
        view.screen_triangles(prim, &mut |t| {
            for (xy, z) in t.xy.iter().zip(t.z) {
                let x = (xy[0] as f64 / sx - 1.0) as f32;
                let y = (1.0 - xy[1] as f64 / sy) as f32;
                for v in [x, y, z as f32, 1.0] {
                    vertices.extend_from_slice(&v.to_le_bytes());
                }
                vertices.extend_from_slice(&t.prim.to_le_bytes());
            }
            count += 1;
        });
    }
    Ok(Geometry {
        vertices,
        stride: 20,
        indices: None,
        count,
        view_projection: view.view_projection().as_mat4().to_cols_array(),
    })
}

/// Engine vertices: the mesh's f32 positions and its triangles as an index buffer, so that
/// `primitive_index` is the mesh's primitive id.
fn engine_geometry(view: &View<'_>) -> Geometry {
    let mesh = view.mesh();
    let vertices = mesh
        .positions
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    Geometry {
        vertices,
        stride: 12,
        indices: Some(mesh.triangles.iter().flatten().copied().collect()),
        count: view.triangle_count(),
        view_projection: view.view_projection().as_mat4().to_cols_array(),
    }
}

fn bytes_of(words: &[u32]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// Runs `scheme` over `view` in `mode` and reads its buffers back as a dump naming `scene`.
///
/// # Errors
/// As the module says: a feature the adapter lacks, a replay viewport that is not a power of
/// two, a buffer past the adapter's limits, a shader the device refuses, a failed read-back.
pub fn capture(
    gpu: &Gpu,
    view: &View<'_>,
    scene: SceneAndCamera,
    scheme: &GpuScheme,
    mode: Mode,
) -> Result<Captured, GpuError> {
    gpu.check(scheme.name(), scheme.needs())?;
    let geometry = match mode {
        Mode::Replay => replay_geometry(view)?,
        Mode::Engine => engine_geometry(view),
    };
    let viewport = view.viewport();
    let pixels = viewport.pixels() as u64;
    let storages = scheme.storages(pixels);
    let limits = gpu.device.limits();
    for s in &storages {
        let bytes = s.words * 4;
        if bytes > limits.max_storage_buffer_binding_size || bytes > limits.max_buffer_size {
            return Err(GpuError(format!(
                "{}: buffer {:?} of {bytes} bytes is past adapter {}'s limit ({} bytes per storage binding)",
                scheme.name(),
                s.name,
                gpu.info.name,
                limits.max_storage_buffer_binding_size
            )));
        }
    }
    let device = &gpu.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let run = encode_and_run(gpu, viewport, &geometry, scheme, &storages, mode)?;
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(GpuError(format!(
            "{}: the device refused: {e}",
            scheme.name()
        )));
    }
    let (words, gpu_ms, wall_ms) = run;
    let dump = to_dump(
        gpu, view, scene, scheme, mode, &geometry, words, gpu_ms, wall_ms,
    )?;
    Ok(Captured {
        dump,
        gpu_ms,
        wall_ms,
        triangles: geometry.count,
    })
}

type RunResult = (Vec<Vec<u32>>, Option<f64>, f64);

fn encode_and_run(
    gpu: &Gpu,
    viewport: fragsim_raster::Viewport,
    geometry: &Geometry,
    scheme: &GpuScheme,
    storages: &[Storage],
    mode: Mode,
) -> Result<RunResult, GpuError> {
    use wgpu::util::DeviceExt;
    let device = &gpu.device;
    let source = format!("{COMMON}\n{}", scheme.source());
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(scheme.name()),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });

    let mut params = Vec::with_capacity(80);
    for v in geometry.view_projection {
        params.extend_from_slice(&v.to_le_bytes());
    }
    let replay = u32::from(mode == Mode::Replay);
    for v in [viewport.width, viewport.height, scheme.slots(), replay] {
        params.extend_from_slice(&v.to_le_bytes());
    }
    let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("params"),
        contents: &params,
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let buffers: Vec<wgpu::Buffer> = storages
        .iter()
        .map(|s| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(s.name),
                contents: &bytes_of(&vec![s.initial; s.words as usize]),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            })
        })
        .collect();

    let mut entries = vec![wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }];
    for s in storages {
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: s.binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        });
    }
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("bindings"),
        entries: &entries,
    });
    let mut bind = vec![wgpu::BindGroupEntry {
        binding: 0,
        resource: uniform.as_entire_binding(),
    }];
    for (s, b) in storages.iter().zip(&buffers) {
        bind.push(wgpu::BindGroupEntry {
            binding: s.binding,
            resource: b.as_entire_binding(),
        });
    }
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("bindings"),
        layout: &layout,
        entries: &bind,
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("layout"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let replay_attributes = wgpu::vertex_attr_array![0 => Float32x4, 1 => Uint32];
    let engine_attributes = wgpu::vertex_attr_array![0 => Float32x3];
    let (vs, attributes): (&str, &[wgpu::VertexAttribute]) = match mode {
        Mode::Replay => ("vs_replay", &replay_attributes),
        Mode::Engine => ("vs_engine", &engine_attributes),
    };
    // A colour target the shader never writes (write mask empty): Vulkan draws need a render
    // area, the schemes write storage buffers only.
    let target_format = wgpu::TextureFormat::R8Unorm;
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(scheme.name()),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(vs),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: geometry.stride,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes,
            })],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(scheme.entry_point()),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: target_format,
                blend: None,
                write_mask: wgpu::ColorWrites::empty(),
            })],
        }),
        multiview_mask: None,
        cache: None,
    });
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("target"),
        size: wgpu::Extent3d {
            width: viewport.width,
            height: viewport.height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: target_format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let target_view = target.create_view(&wgpu::TextureViewDescriptor::default());
    let vertex_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("vertices"),
        contents: &geometry.vertices,
        usage: wgpu::BufferUsages::VERTEX,
    });
    let index_buffer = geometry.indices.as_ref().map(|indices| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("indices"),
            contents: &bytes_of(indices),
            usage: wgpu::BufferUsages::INDEX,
        })
    });

    let timestamps = gpu.has(wgpu::Features::TIMESTAMP_QUERY).then(|| {
        let set = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2,
        });
        let resolve = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamps"),
            size: 16,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        (set, resolve)
    });

    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(scheme.name()),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &target_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Discard,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: timestamps
                .as_ref()
                .map(|(set, _)| wgpu::RenderPassTimestampWrites {
                    query_set: set,
                    beginning_of_pass_write_index: Some(0),
                    end_of_pass_write_index: Some(1),
                }),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.set_vertex_buffer(0, vertex_buffer.slice(..));
        match &index_buffer {
            Some(indices) => {
                pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..3 * geometry.count, 0, 0..1);
            }
            None => pass.draw(0..3 * geometry.count, 0..1),
        }
    }
    let mut sources: Vec<(&wgpu::Buffer, u64)> = buffers
        .iter()
        .zip(storages)
        .map(|(b, s)| (b, s.words * 4))
        .collect();
    if let Some((set, resolve)) = &timestamps {
        encoder.resolve_query_set(set, 0..2, resolve, 0);
        sources.push((resolve, 16));
    }
    let staging: Vec<wgpu::Buffer> = sources
        .iter()
        .map(|&(source, size)| {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("read-back"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            encoder.copy_buffer_to_buffer(source, 0, &buffer, 0, size);
            buffer
        })
        .collect();
    let start = Instant::now();
    gpu.queue.submit([encoder.finish()]);
    let mut words = Vec::with_capacity(staging.len());
    for buffer in &staging {
        buffer.map_async(wgpu::MapMode::Read, .., |_| {});
    }
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| GpuError(format!("{}: waiting for the GPU: {e}", scheme.name())))?;
    for buffer in &staging {
        let view = buffer
            .get_mapped_range(..)
            .map_err(|e| GpuError(format!("{}: read-back: {e}", scheme.name())))?;
        words.push(
            view.chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect::<Vec<u32>>(),
        );
    }
    let wall_ms = start.elapsed().as_secs_f64() * 1e3;
    let gpu_ms = timestamps.as_ref().map(|_| {
        let t = words.pop().unwrap_or_default();
        let ticks = |i: usize| u64::from(t[2 * i]) | (u64::from(t[2 * i + 1]) << 32);
        ticks(1).saturating_sub(ticks(0)) as f64 * f64::from(gpu.queue.get_timestamp_period()) / 1e6
    });
    Ok((words, gpu_ms, wall_ms))
}

/// The u64 words of an array read back as (low, high) u32 pairs.
fn pairs_to_u64(words: &[u32]) -> Vec<u64> {
    words
        .chunks_exact(2)
        .map(|p| u64::from(p[0]) | (u64::from(p[1]) << 32))
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn to_dump(
    gpu: &Gpu,
    view: &View<'_>,
    scene: SceneAndCamera,
    scheme: &GpuScheme,
    mode: Mode,
    geometry: &Geometry,
    words: Vec<Vec<u32>>,
    gpu_ms: Option<f64>,
    wall_ms: f64,
) -> Result<Dump, GpuError> {
    let viewport = view.viewport();
    let pixels = viewport.pixels() as u64;
    let slots = u64::from(scheme.slots());
    let mut arrays = BTreeMap::new();
    let mut specs = BTreeMap::new();
    for (storage, words) in scheme.storages(pixels).iter().zip(words) {
        let (dtype, shape, data) = match storage.dump_dtype {
            Dtype::U32 if storage.per_pixel_slots => {
                (Dtype::U32, vec![pixels, slots], Words::U32(words))
            }
            Dtype::U32 => (Dtype::U32, vec![pixels], Words::U32(words)),
            Dtype::U64 => (
                Dtype::U64,
                vec![pixels, slots],
                Words::U64(pairs_to_u64(&words)),
            ),
        };
        let ext = if dtype == Dtype::U32 { "u32" } else { "u64" };
        specs.insert(
            storage.dump_name.to_string(),
            ArraySpec {
                file: format!("{}.{ext}", storage.dump_name),
                dtype,
                shape,
            },
        );
        arrays.insert(storage.dump_name.to_string(), data);
    }
    // Engine mode draws the mesh with the orbit camera's matrix in f32 and Vulkan's conventions
    // (upper-left origin, depth in [0, 1]): the dump names both, so that compare rebuilds the
    // oracle the engine's way. Replay mode draws fragsim's own snapped triangles: reference.
    let mut scene = scene;
    if mode == Mode::Engine {
        // Row-major, as a reader writes a matrix down (glam's arrays are column-major).
        let m = geometry.view_projection;
        scene.view_projection = Some(ViewProjection {
            row_major: std::array::from_fn(|i| f64::from(m[(i % 4) * 4 + i / 4])),
            precision: VertexPrecision::F32,
        });
        scene.conventions = Conventions {
            vertex_precision: VertexPrecision::F32,
            ..Conventions::REFERENCE
        };
    }
    let header = Header {
        format: FORMAT.into(),
        version: VERSION,
        producer: format!(
            "fragsim-wgpu {} ({} mode, {})",
            env!("CARGO_PKG_VERSION"),
            mode.name(),
            scheme.name()
        ),
        scene,
        width: viewport.width,
        height: viewport.height,
        scheme: scheme.layout().into(),
        k: scheme.k(),
        capacity: scheme.capacity(),
        sorted: false,
        filled: scheme.capacity().is_some(),
        word: scheme.word().into(),
        pool: None,
        layers: None,
        layout: None,
        arrays: specs,
        extra: serde_json::json!({
            "device": gpu.info.name,
            "driver": format!("{} {}", gpu.info.driver, gpu.info.driver_info),
            "mode": mode.name(),
            "shader": scheme.name(),
            "triangles_drawn": geometry.count,
            "timings": {"gpu_ms": gpu_ms, "wall_ms": wall_ms},
        }),
    };
    Ok(Dump { header, arrays })
}
