//! What the wgpu backend's test files share: the adapter, or one line saying why a test is
//! skipped without one (and a failure instead under `CI=true` or `FRAGSIM_REQUIRE_GPU=1`).

use fragsim_wgpu::Gpu;

/// The machine's Vulkan adapter; `None` (after printing why) when there is none and no GPU is
/// required.
///
/// # Panics
/// Without an adapter under `CI=true` or `FRAGSIM_REQUIRE_GPU=1`.
pub fn gpu() -> Option<Gpu> {
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
            println!("skipped: {e} (set FRAGSIM_REQUIRE_GPU=1 to fail instead)");
            None
        }
    }
}
