//! How the measured schemes are set up and which of the campaign's items a run takes: the
//! sizes, executors, threads and submission order of every scheme run ([`SchemeSetup`]), and a
//! shard of a campaign split over machines ([`Shard`]).

use fragsim_capture::executors::Executor;
use fragsim_catalog::Sizing;
use fragsim_raster::View;

/// How schemes are sized and run.
#[derive(Debug, Clone)]
pub struct SchemeSetup {
    /// Slots, capacity and memory cap.
    pub sizing: Sizing,
    /// The executors each scheme runs on, in order (a sweep runs the first alone).
    pub executors: Vec<Executor>,
    /// Threads of the parallel executors (`None`: one per core).
    pub threads: Option<usize>,
    /// Submit the triangles in the order of this seed's permutation (primitive ids unchanged).
    pub shuffle: Option<u64>,
}

impl SchemeSetup {
    /// `view` with its triangles submitted in the `shuffle` order, where one is given.
    #[must_use]
    pub fn submission<'m>(&self, view: View<'m>) -> View<'m> {
        match self.shuffle {
            Some(seed) => view.shuffled(seed),
            None => view,
        }
    }

    /// The rayon pool of `threads`.
    ///
    /// # Errors
    /// The pool cannot be built.
    pub fn pool(&self) -> Result<rayon::ThreadPool, String> {
        rayon::ThreadPoolBuilder::new()
            .num_threads(self.threads.unwrap_or_else(rayon::current_num_threads))
            .build()
            .map_err(|e| e.to_string())
    }
}

/// `--shard I/N`: shard `I` of `N` (from 1) of a campaign split over machines, in
/// cargo-nextest's `--partition count:I/N` convention (`count:I/N` is accepted too): item `k`
/// (from 0) of the campaign's fixed order belongs to shard `k mod N + 1`, so the `N` shards are
/// disjoint, deterministic, and together exactly the unsharded run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard, from 1.
    pub index: u32,
    /// Shards in all.
    pub count: u32,
}

impl Shard {
    /// The whole campaign, unsharded.
    pub const WHOLE: Self = Self { index: 1, count: 1 };

    /// Parses `I/N` or `count:I/N`.
    ///
    /// # Errors
    /// Any other form, `N` = 0, or `I` outside `1..=N`.
    pub fn parse(text: &str) -> Result<Self, String> {
        let form = || format!("{text:?} is not I/N (shard I of N, from 1; nextest's count:I/N)");
        let bare = text.strip_prefix("count:").unwrap_or(text);
        let (index, count) = bare.split_once('/').ok_or_else(form)?;
        let number = |field: &str| field.trim().parse::<u32>().map_err(|_| form());
        let (index, count) = (number(index)?, number(count)?);
        if count == 0 || !(1..=count).contains(&index) {
            return Err(format!(
                "--shard {text}: the shard must be between 1 and the count, which must be at least 1"
            ));
        }
        Ok(Self { index, count })
    }

    /// Whether item `k` (from 0, in the campaign's order) is this shard's.
    #[must_use]
    pub fn takes(self, k: usize) -> bool {
        k % self.count as usize == (self.index - 1) as usize
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}
