//! The fragment word encoding that the sorting schemes share: a fragment as one `u32` (its depth
//! key) or one `u64` (depth key and primitive id), with the array of that width in a memory.
//! MDTS defined it first; peeling, dual peeling and bucket peeling store the same words.

use fragsim_memory::{Memory, Word, WordMemory};
use fragsim_raster::Fragment;

use fragsim_capture::Identity;

/// A word type MDTS can sort: `u32` (depth key) or `u64` (depth key and primitive id).
pub trait MdtsWord: Word {
    /// What the word identifies.
    const IDENTITY: Identity;
    /// The word for a fragment (before the descending variant's offset).
    fn encode(fragment: Fragment) -> Self;
    /// The packed `key << 32 | prim` form of a word made by [`MdtsWord::encode`].
    fn decode(self) -> u64;
    /// This word type's array in `memory`.
    fn words<M: Memory>(memory: &M) -> &impl WordMemory<Self>;
}

impl MdtsWord for u32 {
    const IDENTITY: Identity = Identity::KeyOnly;
    #[inline]
    fn encode(fragment: Fragment) -> Self {
        fragment.depth_key
    }
    #[inline]
    fn decode(self) -> u64 {
        u64::from(self) << 32
    }
    #[inline]
    fn words<M: Memory>(memory: &M) -> &impl WordMemory<Self> {
        memory
    }
}

impl MdtsWord for u64 {
    const IDENTITY: Identity = Identity::KeyAndPrim;
    #[inline]
    fn encode(fragment: Fragment) -> Self {
        fragment.packed()
    }
    #[inline]
    fn decode(self) -> u64 {
        self
    }
    #[inline]
    fn words<M: Memory>(memory: &M) -> &impl WordMemory<Self> {
        memory
    }
}
