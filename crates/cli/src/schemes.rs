//! The registry of schemes the command line can run: one name, one constructor.

use clap::ValueEnum;
use fragsim_capture::abuffer::{ABuffer, PostSort};
use fragsim_capture::executor::{ParallelExecutor, Run, SerialExecutor};
use fragsim_capture::mdts::{Direction, Mdts};
use fragsim_capture::{CaptureError, Scheme};
use fragsim_raster::View;

use crate::args::Count;

/// The schemes the command line can run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SchemeName {
    /// MDTS, 64-bit words (depth key and primitive id), ascending.
    Mdts,
    /// MDTS, 32-bit depth keys as in FreePipe's Table 1.
    Mdts32,
    /// MDTS with `atomicMax`, descending.
    MdtsDesc,
    /// A-buffer, storage sized exactly by a counting pass, insertion-sorted.
    Abuffer,
    /// A-buffer as above, bitonic-sorted.
    AbufferBitonic,
    /// A-buffer with a fixed capacity per pixel (`--capacity`, or the maximum depth complexity).
    AbufferFixed,
    /// Every scheme above.
    All,
}

impl SchemeName {
    /// Every concrete scheme, in the order tables list them.
    pub const EVERY: [SchemeName; 6] = [
        SchemeName::Mdts,
        SchemeName::Mdts32,
        SchemeName::MdtsDesc,
        SchemeName::Abuffer,
        SchemeName::AbufferBitonic,
        SchemeName::AbufferFixed,
    ];

    /// `names` with `all` expanded and duplicates removed, in the order given.
    #[must_use]
    pub fn expand(names: &[SchemeName]) -> Vec<SchemeName> {
        if names.contains(&SchemeName::All) {
            return Self::EVERY.to_vec();
        }
        let mut unique = Vec::new();
        for &n in names {
            if !unique.contains(&n) {
                unique.push(n);
            }
        }
        unique
    }
}

/// What sizing a scheme may need from the scene and the user.
#[derive(Debug, Clone, Copy)]
pub struct Sizing<'a> {
    /// `--k`.
    pub k: Count,
    /// `--capacity`.
    pub capacity: Count,
    /// The scene's per-pixel depth complexity (from the oracle's counting pass).
    pub depth_complexity: &'a [u32],
    /// Its maximum.
    pub max_depth_complexity: u32,
    /// `--memory-cap`.
    pub memory_cap: u64,
}

/// A finished run of a named scheme.
#[derive(Debug, Clone)]
pub struct NamedRun {
    /// The run.
    pub run: Run,
    /// The scheme's own name (`Scheme::name`).
    pub name: String,
    /// Slots per pixel, where the scheme has a fixed number.
    pub slots: Option<u32>,
}

/// Executors that keep their storage between frames of the same scheme.
#[derive(Debug, Default)]
pub struct Executors {
    serial: SerialExecutor,
    parallel: ParallelExecutor,
}

impl Executors {
    /// Builds scheme `name` sized by `sizing` and runs one frame of it on `executor`
    /// (`serial` or `parallel`, on the current rayon pool).
    ///
    /// # Errors
    /// A parameter the scheme rejects, or storage beyond the memory cap.
    pub fn run(
        &mut self,
        name: SchemeName,
        executor: &str,
        view: &View<'_>,
        sizing: &Sizing<'_>,
    ) -> Result<NamedRun, String> {
        let mut go = |scheme: &dyn ErasedScheme, slots: Option<u32>| NamedRun {
            run: scheme.run(self, executor, view),
            name: scheme.name(),
            slots,
        };
        let viewport = view.viewport();
        let cap = sizing.memory_cap;
        let k = sizing.k.resolve(sizing.max_depth_complexity);
        let err = |e: CaptureError| e.to_string();
        let exact_or_fixed =
            |sort: PostSort, capacity: Count| -> Result<(ABuffer, Option<u32>), String> {
                Ok(match capacity {
                    Count::Auto => (
                        ABuffer::exact(sizing.depth_complexity, sort, cap).map_err(err)?,
                        None,
                    ),
                    Count::Fixed(c) => (
                        ABuffer::fixed(viewport, c, sort, cap).map_err(err)?,
                        Some(c),
                    ),
                })
            };
        Ok(match name {
            SchemeName::Mdts => go(
                &Mdts::<u64>::new(viewport, k, Direction::Ascending, cap).map_err(err)?,
                Some(k),
            ),
            SchemeName::Mdts32 => go(
                &Mdts::<u32>::new(viewport, k, Direction::Ascending, cap).map_err(err)?,
                Some(k),
            ),
            SchemeName::MdtsDesc => go(
                &Mdts::<u64>::new(viewport, k, Direction::Descending, cap).map_err(err)?,
                Some(k),
            ),
            SchemeName::Abuffer => {
                let (scheme, slots) = exact_or_fixed(PostSort::Insertion, sizing.capacity)?;
                go(&scheme, slots)
            }
            SchemeName::AbufferBitonic => {
                let (scheme, slots) = exact_or_fixed(PostSort::Bitonic, sizing.capacity)?;
                go(&scheme, slots)
            }
            SchemeName::AbufferFixed => {
                let capacity = Count::Fixed(sizing.capacity.resolve(sizing.max_depth_complexity));
                let (scheme, slots) = exact_or_fixed(PostSort::Insertion, capacity)?;
                go(&scheme, slots)
            }
            SchemeName::All => return Err("`all` names a list of schemes, not one".into()),
        })
    }
}

/// A scheme behind a vtable, so the registry needs one call site per executor rather than one
/// per (scheme, executor) pair. The per-step code stays statically dispatched inside `run`.
trait ErasedScheme {
    fn name(&self) -> String;
    fn run(&self, executors: &mut Executors, executor: &str, view: &View<'_>) -> Run;
}

impl<S: Scheme> ErasedScheme for S {
    fn name(&self) -> String {
        Scheme::name(self)
    }

    fn run(&self, executors: &mut Executors, executor: &str, view: &View<'_>) -> Run {
        if executor == "serial" {
            executors.serial.run(view, self)
        } else {
            executors.parallel.run(view, self)
        }
    }
}
