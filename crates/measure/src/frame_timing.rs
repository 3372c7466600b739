//! Timing frames: a scheme's frames on one executor, each split into vertex stage, geometry
//! passes and post pass, and rasterization alone. What `bench` and its multisampled rows measure
//! with, and `sweep` for its rasterization column.

use std::time::{Duration, Instant};

use fragsim_raster::{Camera, View};
use rayon::prelude::*;

use crate::Progress;

/// The median of `times` (sorted in place).
#[must_use]
pub fn median(times: &mut [Duration]) -> Duration {
    times.sort_unstable();
    times[times.len() / 2]
}

/// `d` in milliseconds.
#[must_use]
pub fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// The times of one scheme's frames on one executor ([`time_frames`]).
#[derive(Debug, Clone)]
pub struct FrameTimes {
    /// Every frame: vertex stage, geometry passes and post pass, fastest first.
    pub frames: Vec<Duration>,
    /// The vertex stage's median.
    pub vertex: Duration,
    /// The geometry passes' median.
    pub passes: Duration,
    /// The post pass's median.
    pub resolve: Duration,
}

impl FrameTimes {
    /// The median frame.
    #[must_use]
    pub fn median(&self) -> Duration {
        self.frames[self.frames.len() / 2]
    }
}

/// Times `frames` frames of one scheme (at least one): each is the vertex stage (the camera set
/// on `view`, on `vertex_pool`) and then `frame(view)`, which runs the geometry passes and the
/// post pass and returns what it made with the two times. One progress step a frame. Returns
/// the first frame's result and the times.
///
/// # Errors
/// The first error of `frame`.
pub fn time_frames<T>(
    view: &mut View<'_>,
    camera: &Camera,
    vertex_pool: &rayon::ThreadPool,
    frames: usize,
    progress: &dyn Progress,
    mut frame: impl FnMut(&View<'_>) -> Result<(T, Duration, Duration), String>,
) -> Result<(T, FrameTimes), String> {
    let mut totals = Vec::with_capacity(frames);
    let (mut vertex, mut passes, mut resolve) = (Vec::new(), Vec::new(), Vec::new());
    let mut first = None;
    for _ in 0..frames.max(1) {
        let start = Instant::now();
        vertex_pool.install(|| view.set_camera(camera));
        let vertex_time = start.elapsed();
        let (made, pass_time, resolve_time) = frame(view)?;
        totals.push(vertex_time + pass_time + resolve_time);
        vertex.push(vertex_time);
        passes.push(pass_time);
        resolve.push(resolve_time);
        first.get_or_insert(made);
        progress.step();
    }
    totals.sort_unstable();
    let times = FrameTimes {
        frames: totals,
        vertex: median(&mut vertex),
        passes: median(&mut passes),
        resolve: median(&mut resolve),
    };
    Ok((first.expect("at least one frame"), times))
}

/// Rasterizes every triangle on the current pool and discards the fragments; returns the time.
#[must_use]
pub fn time_raster_alone(view: &View<'_>) -> Duration {
    let start = Instant::now();
    let fragments: u64 = (0..view.triangle_count())
        .into_par_iter()
        .with_min_len(1024)
        .map(|prim| {
            let mut count = 0_u64;
            view.rasterize(prim, &mut |_| count += 1);
            count
        })
        .sum();
    std::hint::black_box(fragments);
    start.elapsed()
}
