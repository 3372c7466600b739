//! One capture's GPU work ([`Run`]): the shader module, parameters, geometry and colour target its
//! passes share, each submission of draws and compute dispatches, its timestamps, and the
//! storages read back.

use std::time::Instant;

use fragsim_raster::View;

use super::{Geometry, Mode};
use crate::device::{Gpu, GpuError, TARGET_FORMAT};
use crate::plant::Plant;
use crate::shaders::{GpuScheme, Pass, Storage, COMMON, PIXEL_WORKGROUP};

/// Draws `geometry` over `view`'s viewport at `samples` a pixel through `scheme`'s passes and
/// reads its storages back.
pub(super) fn execute_geometry(
    gpu: &Gpu,
    view: &View<'_>,
    geometry: &Geometry,
    scheme: &GpuScheme,
    mode: Mode,
    plant: Option<Plant>,
    samples: u32,
) -> Result<RunResult, GpuError> {
    gpu.check(scheme.name(), scheme.needs())?;
    gpu.check_samples(samples)?;
    let viewport = view.viewport();
    let lists = viewport.pixels() as u64 * u64::from(samples);
    if let Some(pool) = scheme.pool(lists) {
        if pool >= u64::from(u32::MAX) {
            return Err(GpuError::Unsupported(format!(
                "{}: a pool of {pool} nodes does not fit 32-bit node numbers",
                scheme.name()
            )));
        }
    }
    let scope = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let run = Run::new(gpu, viewport, geometry, scheme, mode, plant, samples);
    let result = run.all();
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(GpuError::Device(format!(
            "{}: the device refused: {e}",
            scheme.name()
        )));
    }
    result
}

/// What a capture read back: the storages, their words, GPU and wall milliseconds.
pub(crate) type RunResult = (Vec<Storage>, Vec<Vec<u32>>, Option<f64>, f64);

/// What one submission read back ([`Run::phase`]).
struct PhaseOutput {
    /// The words of each range read, in order.
    words: Vec<Vec<u32>>,
    /// The GPU time of its passes, by timestamps.
    gpu_ms: Option<f64>,
    /// Submission to the end of the read-back.
    wall_ms: f64,
}

/// The objects every pass of one capture shares: the shader module, the parameters, the
/// geometry and the (never written) colour target of `samples` a pixel.
struct Run<'a> {
    gpu: &'a Gpu,
    scheme: &'a GpuScheme,
    mode: Mode,
    geometry: &'a Geometry,
    module: wgpu::ShaderModule,
    uniform: wgpu::Buffer,
    vertices: wgpu::Buffer,
    indices: Option<wgpu::Buffer>,
    target: wgpu::TextureView,
    constants: Vec<(&'static str, f64)>,
    samples: u32,
    /// The lists: pixels times samples.
    lists: u64,
}

impl<'a> Run<'a> {
    fn new(
        gpu: &'a Gpu,
        viewport: fragsim_raster::Viewport,
        geometry: &'a Geometry,
        scheme: &'a GpuScheme,
        mode: Mode,
        plant: Option<Plant>,
        samples: u32,
    ) -> Self {
        use wgpu::util::DeviceExt;
        let device = &gpu.device;
        let per_sample = match scheme.per_sample_source() {
            Some(entries) if samples > 1 => entries,
            _ => "",
        };
        let source = format!("{COMMON}\n{}\n{per_sample}", scheme.source());
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(scheme.name()),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let lists = viewport.pixels() as u64 * u64::from(samples);
        let mut params = Vec::with_capacity(96);
        for v in geometry.view_projection {
            params.extend_from_slice(&v.to_le_bytes());
        }
        let replay = u32::from(mode == Mode::Replay);
        // `pool` fits: `capture_planted` refused larger pools.
        #[expect(
            clippy::cast_possible_truncation,
            reason = "capture_planted refused larger pools"
        )]
        let pool = scheme.pool(lists).unwrap_or(0) as u32;
        for v in [
            viewport.width,
            viewport.height,
            scheme.slots(),
            replay,
            pool,
            samples,
            0,
            0,
        ] {
            params.extend_from_slice(&v.to_le_bytes());
        }
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params"),
            contents: &params,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("vertices"),
            contents: &geometry.vertices,
            usage: wgpu::BufferUsages::VERTEX,
        });
        let indices = geometry.indices.as_ref().map(|indices| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("indices"),
                contents: &bytes_of(indices),
                usage: wgpu::BufferUsages::INDEX,
            })
        });
        let target = device
            .create_texture(&wgpu::TextureDescriptor {
                label: Some("target"),
                size: wgpu::Extent3d {
                    width: viewport.width,
                    height: viewport.height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format: TARGET_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            })
            .create_view(&wgpu::TextureViewDescriptor::default());
        Self {
            gpu,
            scheme,
            mode,
            geometry,
            module,
            uniform,
            vertices,
            indices,
            target,
            constants: vec![("plant", plant.map_or(0.0, Plant::constant))],
            samples,
            lists,
        }
    }

    /// The counting passes (if any), the size read back, the passes, every storage read back.
    fn all(&self) -> Result<RunResult, GpuError> {
        let lists = self.lists;
        let counting = self.scheme.counting_storages(lists);
        let mut buffers = Vec::new();
        for s in &counting {
            buffers.push((s.binding, self.buffer(s)?));
        }
        let (mut gpu_ms, mut wall_ms) = (None, 0.0);
        let mut total = 0;
        let passes = self.scheme.counting_passes(self.samples);
        if !passes.is_empty() {
            // The storage's size is the GPU's own count: offsets[lists], the prefix sum's total.
            let offsets = buffers
                .iter()
                .zip(&counting)
                .find(|(_, s)| s.name == "offsets")
                .map(|((_, b), _)| b)
                .ok_or_else(|| GpuError::Device("the counting passes bind no offsets".into()))?;
            let bound: Vec<(&Storage, &wgpu::Buffer)> = counting
                .iter()
                .zip(buffers.iter().map(|(_, b)| b))
                .collect();
            let counted = self.phase(&bound, &passes, &[(offsets, lists * 4, 4)])?;
            (gpu_ms, wall_ms) = (counted.gpu_ms, counted.wall_ms);
            total = u64::from(counted.words[0][0]);
        }
        let storages = self.scheme.storages(lists, total);
        for s in &storages {
            if !buffers.iter().any(|(b, _)| *b == s.binding) {
                buffers.push((s.binding, self.buffer(s)?));
            }
        }
        let bound: Vec<(&Storage, &wgpu::Buffer)> = storages
            .iter()
            .map(|s| {
                let buffer = buffers
                    .iter()
                    .find(|(b, _)| *b == s.binding)
                    .map(|(_, buffer)| buffer)
                    .expect("every storage's buffer was made above");
                (s, buffer)
            })
            .collect();
        let read: Vec<(&wgpu::Buffer, u64, u64)> =
            bound.iter().map(|&(s, b)| (b, 0, s.words() * 4)).collect();
        let PhaseOutput {
            words,
            gpu_ms: ms,
            wall_ms: wall,
        } = self.phase(&bound, &self.scheme.passes(self.samples), &read)?;
        wall_ms += wall;
        let gpu_ms = match (gpu_ms, ms) {
            (Some(a), Some(b)) => Some(a + b),
            (a, b) => a.or(b),
        };
        Ok((storages, words, gpu_ms, wall_ms))
    }

    /// A storage buffer at its initial words, refused past the adapter's limits. Never empty
    /// (an empty binding is invalid): at least two words.
    fn buffer(&self, s: &Storage) -> Result<wgpu::Buffer, GpuError> {
        use wgpu::util::DeviceExt;
        let bytes = s.words().max(2) * 4;
        let limits = self.gpu.device.limits();
        if bytes > limits.max_storage_buffer_binding_size || bytes > limits.max_buffer_size {
            return Err(GpuError::Unsupported(format!(
                "{}: buffer {:?} of {bytes} bytes is past adapter {}'s limit ({} bytes per storage binding)",
                self.scheme.name(),
                s.name,
                self.gpu.info.name,
                limits.max_storage_buffer_binding_size
            )));
        }
        Ok(self
            .gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(s.name),
                contents: &bytes_of(&vec![s.initial; (bytes / 4) as usize]),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            }))
    }

    /// One submission: `passes` over the `bound` storages, then the `read` ranges (buffer,
    /// byte offset, bytes) copied back, with the GPU time from the first pass's start to the
    /// last one's end where the adapter has timestamps, and the wall time from the submission
    /// to the end of the read-back.
    fn phase(
        &self,
        bound: &[(&Storage, &wgpu::Buffer)],
        passes: &[Pass],
        read: &[(&wgpu::Buffer, u64, u64)],
    ) -> Result<PhaseOutput, GpuError> {
        let device = &self.gpu.device;
        let name = self.scheme.name();
        // Writable storage is not for vertex shaders (no VERTEX_WRITABLE_STORAGE): the
        // parameters are the vertex stage's only binding.
        let buffer_entry = |binding, visibility, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let mut entries = vec![buffer_entry(
            0,
            wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
            wgpu::BufferBindingType::Uniform,
        )];
        let mut bind = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: self.uniform.as_entire_binding(),
        }];
        for &(s, buffer) in bound {
            entries.push(buffer_entry(
                s.binding,
                wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
                wgpu::BufferBindingType::Storage { read_only: false },
            ));
            bind.push(wgpu::BindGroupEntry {
                binding: s.binding,
                resource: buffer.as_entire_binding(),
            });
        }
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("bindings"),
            entries: &entries,
        });
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
        let timestamps = self.gpu.has(wgpu::Features::TIMESTAMP_QUERY).then(|| {
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
        for (i, &pass) in passes.iter().enumerate() {
            let begin = (i == 0).then_some(0);
            let end = (i + 1 == passes.len()).then_some(1);
            let stamps = timestamps.as_ref().map(|(set, _)| (set, begin, end));
            match pass {
                Pass::Draw(entry) => {
                    let pipeline = self.draw_pipeline(&pipeline_layout, entry);
                    self.draw(&mut encoder, &pipeline, &bind_group, stamps);
                }
                Pass::ComputeOnce(entry) | Pass::ComputePerPixel(entry) => {
                    let pipeline =
                        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                            label: Some(entry),
                            layout: Some(&pipeline_layout),
                            module: &self.module,
                            entry_point: Some(entry),
                            compilation_options: self.options(),
                            cache: None,
                        });
                    let mut cpass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some(entry),
                        timestamp_writes: stamps.map(|(set, b, e)| {
                            wgpu::ComputePassTimestampWrites {
                                query_set: set,
                                beginning_of_pass_write_index: b,
                                end_of_pass_write_index: e,
                            }
                        }),
                    });
                    cpass.set_pipeline(&pipeline);
                    cpass.set_bind_group(0, &bind_group, &[]);
                    let (x, y) = match pass {
                        Pass::ComputePerPixel(_) => per_pixel_groups(
                            self.lists,
                            device.limits().max_compute_workgroups_per_dimension,
                        ),
                        _ => (1, 1),
                    };
                    cpass.dispatch_workgroups(x, y, 1);
                }
            }
        }
        let mut sources: Vec<(&wgpu::Buffer, u64, u64)> = read.to_vec();
        if let Some((set, resolve)) = &timestamps {
            encoder.resolve_query_set(set, 0..2, resolve, 0);
            sources.push((resolve, 0, 16));
        }
        let staging: Vec<wgpu::Buffer> = sources
            .iter()
            .map(|&(source, offset, size)| {
                // A mapped buffer is never empty; the words past `size` are not read.
                let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("read-back"),
                    size: size.max(8),
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                encoder.copy_buffer_to_buffer(source, offset, &buffer, 0, size);
                buffer
            })
            .collect();
        let start = Instant::now();
        self.gpu.queue.submit([encoder.finish()]);
        for buffer in &staging {
            buffer.map_async(wgpu::MapMode::Read, .., |_| {});
        }
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Device(format!("{name}: waiting for the GPU: {e}")))?;
        let mut words = Vec::with_capacity(staging.len());
        for (buffer, &(_, _, size)) in staging.iter().zip(&sources) {
            let view = buffer
                .get_mapped_range(..)
                .map_err(|e| GpuError::Device(format!("{name}: read-back: {e}")))?;
            #[expect(
                clippy::cast_possible_truncation,
                reason = "a buffer's size is that of a mapped buffer, which fits the address space"
            )]
            words.push(
                view[..size as usize]
                    .chunks_exact(4)
                    .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                    .collect::<Vec<u32>>(),
            );
        }
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        let gpu_ms = timestamps.as_ref().map(|_| {
            let t = words.pop().unwrap_or_default();
            let ticks = |i: usize| u64::from(t[2 * i]) | (u64::from(t[2 * i + 1]) << 32);
            ticks(1).saturating_sub(ticks(0)) as f64
                * f64::from(self.gpu.queue.get_timestamp_period())
                / 1e6
        });
        Ok(PhaseOutput {
            words,
            gpu_ms,
            wall_ms,
        })
    }

    fn options(&self) -> wgpu::PipelineCompilationOptions<'_> {
        wgpu::PipelineCompilationOptions {
            constants: &self.constants,
            ..Default::default()
        }
    }

    fn draw_pipeline(&self, layout: &wgpu::PipelineLayout, entry: &str) -> wgpu::RenderPipeline {
        let replay_attributes = wgpu::vertex_attr_array![0 => Float32x4, 1 => Uint32];
        let engine_attributes = wgpu::vertex_attr_array![0 => Float32x3];
        let (vs, attributes): (&str, &[wgpu::VertexAttribute]) = match self.mode {
            Mode::Replay => ("vs_replay", &replay_attributes),
            Mode::Engine => ("vs_engine", &engine_attributes),
        };
        self.gpu
            .device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(entry),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module: &self.module,
                    entry_point: Some(vs),
                    compilation_options: self.options(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: self.geometry.stride,
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
                multisample: wgpu::MultisampleState {
                    count: self.samples,
                    ..Default::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module: &self.module,
                    entry_point: Some(entry),
                    compilation_options: self.options(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: TARGET_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::empty(),
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
    }

    fn draw(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::RenderPipeline,
        bind_group: &wgpu::BindGroup,
        stamps: Option<(&wgpu::QuerySet, Option<u32>, Option<u32>)>,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(self.scheme.name()),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &self.target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Discard,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: stamps.map(|(set, b, e)| wgpu::RenderPassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: b,
                end_of_pass_write_index: e,
            }),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        // No triangle (every one clipped away, or none given): the pass still runs, so its
        // timestamps and clear happen, but there is nothing to bind (wgpu refuses an empty
        // buffer slice).
        if self.geometry.count == 0 {
            return;
        }
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        match &self.indices {
            Some(indices) => {
                pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..3 * self.geometry.count, 0, 0..1);
            }
            None => pass.draw(0..3 * self.geometry.count, 0..1),
        }
    }
}

fn bytes_of(words: &[u32]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// Workgroups (x, y) of a per-pixel compute pass: `x` at most the adapter's limit per
/// dimension, `y` rows of them (the shader's pixel is `id.y · x · 64 + id.x`).
#[expect(
    clippy::cast_possible_truncation,
    reason = "x is at most max_per_dimension, a u32, and groups / x at most the groups of at most 16384² pixels"
)]
fn per_pixel_groups(pixels: u64, max_per_dimension: u32) -> (u32, u32) {
    let groups = pixels.div_ceil(u64::from(PIXEL_WORKGROUP)).max(1);
    let x = groups.min(u64::from(max_per_dimension.max(1)));
    (x as u32, groups.div_ceil(x) as u32)
}

#[cfg(test)]
mod tests {
    use super::per_pixel_groups;

    #[test]
    fn per_pixel_dispatches_cover_every_pixel_within_the_limit() {
        assert_eq!(per_pixel_groups(0, 65535), (1, 1));
        assert_eq!(per_pixel_groups(64, 65535), (1, 1));
        assert_eq!(per_pixel_groups(65, 65535), (2, 1));
        // 2048² pixels: 65536 workgroups of 64, past one dimension's 65535.
        let (x, y) = per_pixel_groups(2048 * 2048, 65535);
        assert_eq!((x, y), (65535, 2));
        assert!(u64::from(x) * u64::from(y) * 64 >= 2048 * 2048);
    }
}
