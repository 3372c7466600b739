//! The headless GPU: a Vulkan adapter found without a surface, the device opened with the
//! features the scheme shaders use, and a one-paragraph report of what the adapter has.
//!
//! Guarantee: [`Gpu::open`] never panics for want of a GPU: no Vulkan driver, no adapter, or an
//! adapter without `PRIMITIVE_INDEX` is a [`GpuError`] naming the problem. 64-bit atomics and
//! timestamps are optional: a scheme that needs what the adapter lacks is refused when asked for
//! ([`Gpu::check`]). [`adapter_or_skip`] is the tests' way in: the GPU, or one line saying why
//! the test is skipped (or a failure where CI requires a GPU).
//!
//! For multisampling the report also gives the sample counts the colour target's format renders
//! at. Where the samples lie it cannot say: wgpu does not expose Vulkan's
//! `standardSampleLocations`, and reading it through wgpu's raw Vulkan handle takes `unsafe`
//! code, which the workspace forbids (`crate::sample_counts` says how the positions are checked
//! instead).

/// The format of every capture's colour target, which the shaders never write (write mask
/// empty): Vulkan draws need a render area, the schemes write storage buffers only. Multisampled
/// for the counting pass and per-sample captures, so the device reports its sample counts.
pub(crate) const TARGET_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;

/// Why no GPU could be used, or why a capture cannot run on this one. Callers branch on the
/// kind: tests skip where there is no GPU or the adapter lacks what a case needs, and the
/// conformance battery stops on those and on a refused request, but shrinks a case the device
/// failed ([`crate::conform`]). Each message names what is missing or wrong.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum GpuError {
    /// No Vulkan adapter, or none whose device opens.
    #[error("{0}")]
    NoGpu(String),
    /// The adapter lacks what the request needs: a feature, a sample count, a buffer within its
    /// limits, node numbers that fit.
    #[error("{0}")]
    Unsupported(String),
    /// The request is wrong whatever the adapter: an unknown scheme or plant, a plant that does not
    /// apply, a view the mode cannot draw.
    #[error("{0}")]
    Refused(String),
    /// The device failed a run: validation refused it, or waiting or reading back failed.
    #[error("{0}")]
    Device(String),
}

/// An open device and what its adapter is.
#[derive(Debug)]
pub struct Gpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter's name, driver and type.
    pub info: wgpu::AdapterInfo,
    /// The features this device was opened with (those of [`WANTED`] the adapter has).
    pub features: wgpu::Features,
    /// The sample counts a colour target of the draws' format renders at (wgpu's guaranteed 1
    /// and 4, and the adapter's own where it has `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES`).
    pub sample_counts: Vec<u32>,
}

/// Features the shaders use where the adapter has them, by name: 64-bit integers and their
/// atomics (MDTS on u64 words), timestamps (GPU timings), the adapter's own texture format
/// features (8 samples a pixel, past WebGPU's guaranteed 4) and `PRIMITIVE_INDEX`, which is
/// required (engine mode's primitive id; `common.wgsl` enables it).
pub const WANTED: [(&str, wgpu::Features); 6] = [
    ("SHADER_INT64", wgpu::Features::SHADER_INT64),
    (
        "SHADER_INT64_ATOMIC_MIN_MAX",
        wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX,
    ),
    (
        "SHADER_INT64_ATOMIC_ALL_OPS",
        wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS,
    ),
    ("TIMESTAMP_QUERY", wgpu::Features::TIMESTAMP_QUERY),
    (
        "TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES",
        wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES,
    ),
    ("PRIMITIVE_INDEX", wgpu::Features::PRIMITIVE_INDEX),
];

impl Gpu {
    /// Finds a Vulkan adapter (no surface) and opens it with the adapter's own limits, so that
    /// large per-pixel buffers fit where the hardware allows.
    ///
    /// # Errors
    /// No Vulkan adapter (the message says what to install), no `PRIMITIVE_INDEX`, or a device
    /// that would not open.
    pub fn open() -> Result<Self, GpuError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        desc.backends = wgpu::Backends::VULKAN;
        let instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            apply_limit_buckets: false,
        }))
        .map_err(|e| {
            GpuError::NoGpu(format!(
                "no Vulkan adapter ({e}); install a driver, e.g. `apt-get install -y mesa-vulkan-drivers libvulkan1` for lavapipe"
            ))
        })?;
        let info = adapter.get_info();
        let wanted = WANTED
            .iter()
            .fold(wgpu::Features::empty(), |all, &(_, f)| all | f);
        let features = adapter.features() & wanted;
        if !features.contains(wgpu::Features::PRIMITIVE_INDEX) {
            return Err(GpuError::Unsupported(format!(
                "adapter {} has no PRIMITIVE_INDEX (the shaders' primitive id)",
                info.name
            )));
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("fragsim-wgpu"),
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| {
            GpuError::NoGpu(format!("adapter {}: cannot open a device: {e}", info.name))
        })?;
        let sample_counts =
            if features.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES) {
                adapter
                    .get_texture_format_features(TARGET_FORMAT)
                    .flags
                    .supported_sample_counts()
            } else {
                vec![1, 4]
            };
        Ok(Self {
            device,
            queue,
            info,
            features,
            sample_counts,
        })
    }

    /// Refuses a draw at `samples` a pixel that the colour target's format cannot render at.
    ///
    /// # Errors
    /// The counts the adapter has, with its name.
    pub fn check_samples(&self, samples: u32) -> Result<(), GpuError> {
        if self.sample_counts.contains(&samples) {
            Ok(())
        } else {
            Err(GpuError::Unsupported(format!(
                "adapter {} renders {TARGET_FORMAT:?} targets at {:?} samples a pixel, not {samples}",
                self.info.name, self.sample_counts
            )))
        }
    }

    /// Whether the device has `feature`.
    #[must_use]
    pub fn has(&self, feature: wgpu::Features) -> bool {
        self.features.contains(feature)
    }

    /// Refuses a shader that needs `needed` on a device without it.
    ///
    /// # Errors
    /// The features missing, by name, with the adapter's name.
    pub fn check(&self, what: &str, needed: wgpu::Features) -> Result<(), GpuError> {
        let missing: Vec<&str> = WANTED
            .iter()
            .filter(|&&(_, f)| needed.contains(f) && !self.has(f))
            .map(|&(name, _)| name)
            .collect();
        if missing.is_empty() {
            Ok(())
        } else {
            Err(GpuError::Unsupported(format!(
                "{what} needs {}, which adapter {} does not have",
                missing.join(" and "),
                self.info.name
            )))
        }
    }

    /// One line: the adapter, its driver and each wanted feature, present or not.
    #[must_use]
    pub fn report(&self) -> String {
        let flags: Vec<String> = WANTED
            .iter()
            .map(|&(name, f)| format!("{name}: {}", if self.has(f) { "yes" } else { "no" }))
            .collect();
        format!(
            "adapter {} ({:?}, driver {} {}); {}; target sample counts {:?}",
            self.info.name,
            self.info.device_type,
            self.info.driver,
            self.info.driver_info,
            flags.join(", "),
            self.sample_counts
        )
    }
}

/// Writes `skipped: WHY` to the process's standard error directly, not through `eprintln!`,
/// which the test harness captures and shows only for failing tests: a skipped test must say
/// so in every `cargo test` log.
pub fn say_skipped(why: &str) {
    use std::io::Write;
    // A closed stderr leaves nothing to tell.
    let _ = writeln!(std::io::stderr(), "skipped: {why}");
}

/// The GPU for a test, or `None` after one line saying the test is skipped and why. Sets
/// `XDG_RUNTIME_DIR` to the temporary directory when unset (Mesa warns without it) and prints
/// the adapter's [`Gpu::report`] when there is one, so a test log names it.
///
/// # Panics
/// With no usable adapter where a GPU is required: `CI=true` (set by CI) or
/// `FRAGSIM_REQUIRE_GPU=1`, so that CI fails rather than skips.
#[must_use]
#[expect(
    clippy::print_stdout,
    reason = "a test helper: the test log names the adapter (see the doc comment)"
)]
pub fn adapter_or_skip() -> Option<Gpu> {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    match Gpu::open() {
        Ok(gpu) => {
            println!("{}", gpu.report());
            Some(gpu)
        }
        Err(e) => {
            let required = std::env::var("CI").is_ok_and(|v| v == "true")
                || std::env::var("FRAGSIM_REQUIRE_GPU").is_ok_and(|v| v == "1");
            assert!(
                !required,
                "a GPU is required (CI=true or FRAGSIM_REQUIRE_GPU=1): {e}"
            );
            say_skipped(&format!("{e} (set FRAGSIM_REQUIRE_GPU=1 to fail instead)"));
            None
        }
    }
}
