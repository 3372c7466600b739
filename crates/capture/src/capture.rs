//! What a scheme hands back: per-pixel fragment lists, and what it was meant to keep.

/// How much of a fragment a scheme's words identify.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Identity {
    /// Depth key and primitive id (64-bit words): compared fragment for fragment.
    KeyAndPrim,
    /// Depth key only (32-bit words, as FreePipe's Table 1): compared by key.
    KeyOnly,
    /// Primitive id only, in the order the scheme resolved them: for schemes that keep a lossy
    /// depth beside an attribute (FreePipe §4.1.2), compared with the oracle's primitive
    /// sequence in canonical depth order. The high half is the lossy depth key the scheme holds
    /// (what the image judge shades), never compared.
    PrimOnly,
    /// Masked nodes, `samples` a pixel (the masked-node A-buffer's per-sample resolve): each
    /// sample's list holds the nodes whose coverage mask holds the sample, as the packed words
    /// of their nearest depth key (the nearest of the primitive's samples in the pixel) and
    /// primitive id. Compared node by node with the oracle's lists, each primitive's samples in
    /// a pixel merged into one node, the masks included: the capacity counts nodes a pixel,
    /// and a pixel's dropped nodes are reported on its first sample.
    MaskedNodes(u32),
}

/// Which of a pixel's fragments a scheme promises to keep.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Keeps {
    /// The `K` nearest in canonical order (ascending MDTS).
    Nearest(u32),
    /// The `K` farthest (descending MDTS).
    Farthest(u32),
    /// Every fragment, except the per-pixel counts that overflowed fixed storage; which ones
    /// overflow depends on arrival order.
    All {
        /// The storage the fragments had: what lets the oracle predict each pixel's overflow
        /// instead of trusting the scheme's count.
        capacity: Capacity,
        /// Per pixel, how many fragments found no free slot, as the scheme counted them.
        overflow: Vec<u32>,
    },
}

/// How many fragments of a pixel a scheme's storage holds: with a pixel's fragment count `n` from
/// the oracle, the overflow the scheme must report is known exactly.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Capacity {
    /// Storage sized to hold every fragment (from a counting pass, or unbounded by design):
    /// nothing may overflow.
    Unbounded,
    /// `C` slots per pixel: a pixel of `n` fragments overflows by exactly `max(0, n − C)`, and
    /// the scheme counts it.
    PerPixel(u32),
    /// `C` slots per pixel, the overflow discarded without a count (Bevy's clamped layer
    /// counter, a linked list resolve that stops at `C` nodes): the oracle's `max(0, n − C)` is
    /// the only count there is, and the scheme must report 0.
    PerPixelUncounted(u32),
}

impl Capacity {
    /// The overflow a pixel of `fragments` fragments must report.
    #[must_use]
    pub fn overflow(self, fragments: usize) -> usize {
        match self {
            Self::Unbounded => 0,
            Self::PerPixel(c) | Self::PerPixelUncounted(c) => fragments.saturating_sub(c as usize),
        }
    }

    /// The overflow a pixel of `fragments` fragments must report itself: 0 where the scheme
    /// cannot count it.
    #[must_use]
    pub fn reported_overflow(self, fragments: usize) -> usize {
        match self {
            Self::PerPixelUncounted(_) => 0,
            _ => self.overflow(fragments),
        }
    }
}

/// Per-pixel lists of packed fragment words, pixel after pixel: what a scheme captures
/// ([`Capture`]) and what the oracle holds (`fragsim_oracle::Oracle`), one type so that either
/// side reads the other's lists without a conversion.
///
/// Entries are packed `depth_key << 32 | prim` (see `Fragment::packed`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PixelLists {
    /// `offsets[p]..offsets[p + 1]` indexes pixel `p`'s entries; `offsets[0]` is 0.
    pub offsets: Vec<usize>,
    /// The entries of all pixels, pixel after pixel.
    pub entries: Vec<u64>,
}

impl PixelLists {
    /// No pixel yet, room for `pixels` of them: a builder for [`PixelLists::push_pixel`].
    #[must_use]
    pub fn with_pixels(pixels: usize) -> Self {
        let mut offsets = Vec::with_capacity(pixels + 1);
        offsets.push(0);
        Self {
            offsets,
            entries: Vec::new(),
        }
    }

    /// Appends the next pixel's list.
    pub fn push_pixel(&mut self, entries: impl IntoIterator<Item = u64>) {
        self.entries.extend(entries);
        self.offsets.push(self.entries.len());
    }

    /// Number of pixels.
    #[must_use]
    pub fn pixels(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Pixel `p`'s entries.
    #[must_use]
    pub fn pixel(&self, p: usize) -> &[u64] {
        &self.entries[self.offsets[p]..self.offsets[p + 1]]
    }

    /// Each pixel's entry count, pixel after pixel.
    pub fn lengths(&self) -> impl Iterator<Item = usize> + '_ {
        self.offsets.windows(2).map(|w| w[1] - w[0])
    }

    /// Second and later copies of an entry within one pixel's list, over every pixel: what a
    /// torn write-back leaves (the k-buffer's hazard), and what no exact scheme may.
    #[must_use]
    pub fn duplicates(&self) -> u64 {
        let mut sorted = Vec::new();
        (0..self.pixels())
            .map(|p| {
                sorted.clear();
                sorted.extend_from_slice(self.pixel(p));
                sorted.sort_unstable();
                sorted.windows(2).filter(|w| w[0] == w[1]).count() as u64
            })
            .sum()
    }

    /// Sorts each pixel's list (ascending words: canonical order for `key << 32 | prim`).
    pub fn sort_each_pixel(&mut self) {
        for p in 0..self.pixels() {
            self.entries[self.offsets[p]..self.offsets[p + 1]].sort_unstable();
        }
    }
}

/// Per-pixel lists of captured fragments in the order the scheme's post pass produced them, with
/// what they identify and what the scheme promised to keep.
///
/// The lists are [`Capture::lists`]; a capture dereferences to them, so `capture.pixel(p)` and
/// `capture.entries` read them directly. With [`Identity::KeyOnly`] the low half of each entry
/// is zero.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Capture {
    /// The per-pixel lists.
    pub lists: PixelLists,
    /// What the entries identify.
    pub identity: Identity,
    /// What the scheme promises to keep.
    pub keeps: Keeps,
}

impl std::ops::Deref for Capture {
    type Target = PixelLists;

    fn deref(&self) -> &PixelLists {
        &self.lists
    }
}

impl std::ops::DerefMut for Capture {
    fn deref_mut(&mut self) -> &mut PixelLists {
        &mut self.lists
    }
}

impl Capture {
    /// An empty capture builder for `pixels` pixels ([`PixelLists::push_pixel`] adds them).
    #[must_use]
    pub fn with_pixels(pixels: usize, identity: Identity, keeps: Keeps) -> Self {
        Self {
            lists: PixelLists::with_pixels(pixels),
            identity,
            keeps,
        }
    }

    /// The nearest depth key per pixel (`None` where nothing was captured), for images.
    #[must_use]
    pub fn nearest_keys(&self) -> Vec<Option<u32>> {
        (0..self.pixels())
            .map(|p| self.pixel(p).iter().map(|&e| (e >> 32) as u32).min())
            .collect()
    }
}
