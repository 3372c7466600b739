//! The k-buffer family's per-pixel slots: `K` `u64` slots a pixel and the read–insert–write of
//! one fragment on them, on either machine ([`WriteBack`]). The k-buffer ([`super::KBuffer`]) and
//! the multi-pass k-buffer run it as it is; the interlocked, ordered-interlock and spinlocked
//! k-buffers run its insertion inside their critical sections. The module docs of the schemes say
//! what each step is on which machine.

use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::Fragment;

use fragsim_capture::Guarantee;
use fragsim_capture::Identity;
use fragsim_capture::{CaptureError, Descriptor, Promise};

/// The value of an empty slot: larger than every packed fragment.
pub const EMPTY: u64 = u64::MAX;

/// How a fragment's read and write-back reach the pixel's `K` slots: the machine modelled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WriteBack {
    /// Render targets, as on the papers' GPUs: the read of the `K` slots is one step, the
    /// write-back one step, and write-backs to a pixel commit in order. Only the read
    /// can be stale, so the only failure is a lost fragment.
    #[default]
    RenderTarget,
    /// `K` loads, then `K` stores, one step each, as CUDA code does: write-backs can tear, so the
    /// slots can also hold duplicates and be out of order.
    SeparateStores,
}

impl WriteBack {
    /// The suffix of a scheme's name on this machine: none for render targets (the default).
    #[must_use]
    pub fn suffix(self) -> &'static str {
        match self {
            Self::RenderTarget => "",
            Self::SeparateStores => "-stores",
        }
    }
}

/// Where a fragment's read–insert–write is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Slot `i` is loaded next (with render targets, `Read(0)`: all `K` slots in one step).
    Read(u32),
    /// Slot `i` is stored next (with render targets, `Write(0)`: all `K` slots in one step).
    Write(u32),
}

/// A fragment's read–insert–write.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Insert {
    /// First word of the pixel's `K` slots.
    pub base: usize,
    /// The fragment, packed `depth_key << 32 | prim`.
    pub value: u64,
    /// The next memory operation.
    pub phase: Phase,
    /// While reading, the slots read so far; from the first write on, the `K` words to write.
    pub local: Vec<u64>,
    /// Whether the insertion pushed a value off the end.
    pub evicted: bool,
    /// Render targets: the fragment's place in the pixel's commit order, taken with its read.
    pub ticket: u32,
}

/// How a step of [`Slots::step`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Outcome {
    /// More steps follow.
    Continue,
    /// The write-back is done; nothing fell off.
    Stored,
    /// The write-back is done; the value that was `K`-th fell off.
    Evicted,
    /// The fragment was farther than all `K` values read: it writes nothing.
    FellOff,
    /// Render targets only: the write-back of a fragment that read later had already committed,
    /// so in commit order this one came first and was overwritten; nothing was written.
    Overtaken,
}

/// `K` slots per pixel and the read–insert–write on them, shared by the single-pass k-buffer and
/// the multi-pass one ([`super::multipass`]), which peels with it.
///
/// The slots of pixel `p` are `u64` words `p K .. (p + 1) K`; with render targets, `u32` words
/// `3 p` (the lock), `3 p + 1` (the next ticket) and `3 p + 2` (the last committed ticket + 1) are
/// the pixel's too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Slots {
    /// Slots per pixel.
    pub k: u32,
    /// The machine.
    pub write_back: WriteBack,
}

impl Slots {
    /// Fails on `k == 0`, naming `scheme`.
    pub(crate) fn new(scheme: &str, k: u32, write_back: WriteBack) -> Result<Self, CaptureError> {
        if k == 0 {
            return Err(CaptureError::BadParameter(format!(
                "{scheme} needs K ≥ 1 slots per pixel, got K = 0"
            )));
        }
        Ok(Self { k, write_back })
    }

    /// The descriptor of a scheme keeping these slots for `pixels` pixels, its `u32` words
    /// (locks, tickets) `words32`: whole fragments in `u64` slots, all empty at first, the `K`
    /// nearest promised, and every fragment that falls off a walk's end counted as dropped.
    pub(crate) fn descriptor(
        self,
        name: String,
        pixels: usize,
        words32: usize,
        guarantee: Guarantee,
    ) -> Descriptor {
        Descriptor {
            name,
            layout: Layout {
                words32,
                init32: 0,
                words64: self.words(pixels),
                init64: EMPTY,
                table_bytes: 0,
            },
            identity: Identity::KeyAndPrim,
            guarantee,
            promise: Promise::Nearest(self.k),
            pixels,
            counts_every_drop: true,
        }
    }

    /// `u64` words of `pixels` pixels' slots.
    pub(crate) fn words(self, pixels: usize) -> usize {
        pixels * self.k as usize
    }

    /// `u32` words of `pixels` pixels' render-target bookkeeping (none for separate stores):
    /// the lock, the next ticket, the last committed ticket + 1.
    pub(crate) fn sync_words(self, pixels: usize) -> usize {
        match self.write_back {
            WriteBack::RenderTarget => 3 * pixels,
            WriteBack::SeparateStores => 0,
        }
    }

    /// A fragment's walk before its first read.
    pub(crate) fn begin(self, fragment: Fragment) -> Insert {
        Insert {
            base: fragment.pixel as usize * self.k as usize,
            value: fragment.packed(),
            phase: Phase::Read(0),
            local: Vec::with_capacity(self.k as usize + 1),
            evicted: false,
            ticket: 0,
        }
    }

    /// One step of the walk: one load or one store with separate stores; the whole read or the
    /// whole write-back with render targets.
    pub(crate) fn step<M: Memory>(self, insert: &mut Insert, memory: &M) -> Outcome {
        match self.write_back {
            WriteBack::SeparateStores => self.step_separate(insert, memory),
            WriteBack::RenderTarget => self.step_render_target(insert, memory),
        }
    }

    fn step_separate<M: Memory>(self, insert: &mut Insert, memory: &M) -> Outcome {
        let k = self.k;
        match insert.phase {
            Phase::Read(i) => {
                insert
                    .local
                    .push(WordMemory::<u64>::load(memory, insert.base + i as usize));
                if i + 1 < k {
                    insert.phase = Phase::Read(i + 1);
                    return Outcome::Continue;
                }
                self.insert_in_registers(insert)
            }
            Phase::Write(i) => {
                WordMemory::<u64>::store(
                    memory,
                    insert.base + i as usize,
                    insert.local[i as usize],
                );
                if i + 1 < k {
                    insert.phase = Phase::Write(i + 1);
                    Outcome::Continue
                } else if insert.evicted {
                    Outcome::Evicted
                } else {
                    Outcome::Stored
                }
            }
        }
    }

    fn step_render_target<M: Memory>(self, insert: &mut Insert, memory: &M) -> Outcome {
        let k = self.k as usize;
        let pixel = insert.base / k;
        let (lock, next_ticket, last_writer) = (3 * pixel, 3 * pixel + 1, 3 * pixel + 2);
        match insert.phase {
            Phase::Read(_) => {
                memory.lock(lock);
                insert.ticket = WordMemory::<u32>::load(memory, next_ticket);
                WordMemory::<u32>::store(memory, next_ticket, insert.ticket.wrapping_add(1));
                insert.local.extend(
                    (insert.base..insert.base + k).map(|w| WordMemory::<u64>::load(memory, w)),
                );
                memory.unlock(lock);
                self.insert_in_registers(insert)
            }
            Phase::Write(_) => {
                // `ticket + 1`, so that 0 means "no write-back yet".
                let mine = insert.ticket.saturating_add(1);
                memory.lock(lock);
                let commits = mine > WordMemory::<u32>::load(memory, last_writer);
                if commits {
                    for (i, &v) in insert.local.iter().enumerate() {
                        WordMemory::<u64>::store(memory, insert.base + i, v);
                    }
                    WordMemory::<u32>::store(memory, last_writer, mine);
                }
                memory.unlock(lock);
                if !commits {
                    Outcome::Overtaken
                } else if insert.evicted {
                    Outcome::Evicted
                } else {
                    Outcome::Stored
                }
            }
        }
    }

    /// The insertion, in registers, after the last read: no memory operation. Under a hazard the
    /// values read may hold gaps, duplicates or be out of order (separate stores only); they are
    /// sorted as they are, as a shader sorting its `K + 1` registers would.
    pub(crate) fn insert_in_registers(self, insert: &mut Insert) -> Outcome {
        let k = self.k as usize;
        insert.local.retain(|&v| v != EMPTY);
        let full = insert.local.len() == k;
        if full && insert.local.iter().all(|&v| v < insert.value) {
            return Outcome::FellOff;
        }
        insert.local.push(insert.value);
        insert.local.sort_unstable();
        insert.evicted = insert.local.len() > k;
        insert.local.resize(k, EMPTY);
        insert.phase = Phase::Write(0);
        Outcome::Continue
    }

    /// Empties `pixel`'s slots and forgets its last writer (between geometry passes).
    pub(crate) fn clear<M: Memory>(self, memory: &M, pixel: usize) {
        let base = pixel * self.k as usize;
        for w in base..base + self.k as usize {
            WordMemory::<u64>::store(memory, w, EMPTY);
        }
        if self.write_back == WriteBack::RenderTarget {
            WordMemory::<u32>::store(memory, 3 * pixel + 1, 0);
            WordMemory::<u32>::store(memory, 3 * pixel + 2, 0);
        }
    }

    /// The post pass of a pixel whose slots hold its list: appends the occupied slots to `out`
    /// and returns no overflow, since what fell off (or was dropped) is not in memory: the
    /// executors count it from the walks.
    pub(crate) fn resolve_pixel<M: Memory>(
        self,
        memory: &M,
        pixel: usize,
        out: &mut Vec<u64>,
    ) -> u32 {
        out.extend(self.occupied(memory, pixel));
        0
    }

    /// The non-empty slots of `pixel`, in slot order: gaps, duplicates and disorder left by a
    /// hazard are kept, for the diff to see.
    pub(crate) fn occupied(
        self,
        slots: &impl WordMemory<u64>,
        pixel: usize,
    ) -> impl Iterator<Item = u64> + '_ {
        let base = pixel * self.k as usize;
        (0..self.k as usize)
            .map(move |i| slots.load(base + i))
            .filter(|&v| v != EMPTY)
    }
}
