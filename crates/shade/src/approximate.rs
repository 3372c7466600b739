//! Approximate order-independent transparency, the schemes engines ship instead of exact OIT:
//! weighted blended OIT ([`Approximation::Wboit`]), multi-layer alpha blending
//! ([`Approximation::Mlab`]) and tail blending ([`Approximation::TailBlend`]), each resolving a
//! pixel's fragments, **in the order the pixel receives them**, to the transparency effect's
//! colour ([`effects`](crate::effects): "under" blending of every fragment at the material's
//! opacity `α`, over the background), so that the image can be compared with the exact one
//! ([`colour_error`](crate::colour_error), [`effects::error_pixels`](crate::effects::error_pixels)).
//!
//! **Why arrival order, and which.** These schemes hold colour, not fragment lists, so there is
//! no list for the oracle to diff: what is compared is the image. Their result depends on the
//! order the pixel sees its fragments in (a sum in floating point, a merge of the two farthest
//! nodes, an eviction into the tail), and on a GPU that order is primitive order: fixed-function
//! blending (WBOIT's two targets, tail blending's tail) and the ordered interlock MLAB runs in
//! (Salvi & Vaidyanathan use Intel's PixelSync) both honour the API's primitive order per pixel.
//! So on a GPU each is deterministic, whatever the thread schedule, and so it is here: the
//! caller hands every pixel's fragments in submission order ([`in_submission_order`]).
//!
//! **Why these are shading options, and MLAB also a catalog entry.** A catalog entry is judged
//! by its fragment lists against the oracle's; what is here is judged by its image. WBOIT keeps
//! no fragment at all (two blend targets), so a catalog entry would capture nothing and its
//! verdict would say nothing. Tail blending's sorted part is any capture of the `K` nearest
//! (`mdts`, `kbuffer-interlock`, already in the catalog and judged there); its tail is the
//! blending hardware's, fragments folded into a colour target in arrival order, with no list
//! left to judge: so it is a shading option of those bounded captures, applied here to every
//! pixel's fragments in submission order. MLAB's node structure is a capture with a checkable
//! promise (its node depths are exactly the `K` nearest, whatever the interleaving), so it is
//! also the catalog's `mlab` (`fragsim_schemes::mlab`, judged on every executor);
//! its colour, the approximation, is measured here.
//!
//! **Guarantees.** [`Approximation::Mlab`] and [`Approximation::TailBlend`] with `K` nodes are
//! the exact image at every pixel with at most `K` fragments (nothing merged, nothing evicted:
//! the same operations, in the same order, as the exact effect), and may differ only at pixels
//! with more. [`Approximation::Wboit`] is exact at pixels with at most one fragment only.
//! Nothing is promised beyond: the error is measured, never judged. `tests/suite/approximate.rs`
//! checks each claim, per pixel and through `fragsim bench --approximate`.
//!
//! **Sources.** McGuire & Bavoil, "Weighted Blended Order-Independent Transparency", JCGT 2(2),
//! 2013 (the accumulation and revealage targets; the depth weight of their eq. (10)); Salvi &
//! Vaidyanathan, "Multi-layer Alpha Blending", I3D 2014 (K nodes, the two farthest merged when a
//! fragment arrives at a full pixel); nvpro-samples' `vk_order_independent_transparency`
//! (NVIDIA, 2020) for tail blending (what does not fit the K nearest is blended into the
//! colour target unsorted). `docs/baselines/{wboit,mlab,tail-blend}.md` state each departure.

use fragsim_capture::primitive_order::PrimitiveOrder;
use fragsim_raster::Fragment;
use image::RgbImage;

use crate::effects::{primitive_colour, shade_image, Material};

/// An approximate OIT scheme and its size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Approximation {
    /// Weighted blended OIT: one accumulation target (`Σ α w c`, `Σ α w`) and one revealage
    /// target (`Π (1 − α)`), no storage per fragment.
    Wboit,
    /// Multi-layer alpha blending with `k` nodes per pixel.
    Mlab {
        /// Nodes per pixel.
        k: u32,
    },
    /// The `k` nearest fragments kept and sorted, the rest blended into a tail unsorted.
    TailBlend {
        /// Fragments kept sorted per pixel.
        k: u32,
    },
}

impl Approximation {
    /// Its name in tables, JSON and file names: `wboit`, `mlab`, `tail-blend`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Wboit => "wboit",
            Self::Mlab { .. } => "mlab",
            Self::TailBlend { .. } => "tail-blend",
        }
    }

    /// Its nodes per pixel, where it has a number.
    #[must_use]
    pub fn k(self) -> Option<u32> {
        match self {
            Self::Wboit => None,
            Self::Mlab { k } | Self::TailBlend { k } => Some(k),
        }
    }

    /// Bytes of per-pixel storage on a GPU, as the papers lay it out: WBOIT an RGBA16F
    /// accumulation and an R16F revealage target (10 bytes); MLAB `k` nodes of a 32-bit depth and
    /// an RGBA8 colour-and-transmittance word (8 bytes each, Salvi & Vaidyanathan §4); tail
    /// blending `k` 64-bit (depth, colour) slots and an RGBA16F tail (`8 k + 8`).
    #[must_use]
    pub fn bytes_per_pixel(self) -> u64 {
        match self {
            Self::Wboit => 10,
            Self::Mlab { k } => 8 * u64::from(k),
            Self::TailBlend { k } => 8 * u64::from(k) + 8,
        }
    }

    /// Resolves one pixel's entries (`depth_key << 32 | prim`), **in arrival order**, to a
    /// linear colour under `material` (its opacity, background and primitive colours).
    #[must_use]
    pub fn shade_pixel(self, material: &Material, arrivals: &[u64]) -> [f32; 3] {
        match self {
            Self::Wboit => wboit(material, arrivals),
            Self::Mlab { k } => mlab(material, k as usize, arrivals),
            Self::TailBlend { k } => tail_blend(material, k as usize, arrivals),
        }
    }

    /// The image of every pixel, rows in parallel; `arrivals(p)` gives pixel `p`'s entries in
    /// arrival order.
    #[must_use]
    pub fn render<'a>(
        self,
        material: &Material,
        size: (u32, u32),
        arrivals: impl Fn(usize) -> &'a [u64] + Sync,
    ) -> RgbImage {
        shade_image(size, |p| self.shade_pixel(material, arrivals(p)))
    }
}

/// Pixel `pixel`'s entries `sorted` (any order) rearranged into submission order: the order a
/// GPU's blending and ordered interlock see them in. An entry the order does not hold (it
/// cannot come from the recorded view) goes last, in its given order.
#[must_use]
#[expect(
    clippy::cast_possible_truncation,
    reason = "pixel indices fit u32: viewports are at most 16384² pixels (Viewport::new); an entry packs the depth key (high 32 bits) and the primitive id (low 32)"
)]
pub fn in_submission_order(order: &PrimitiveOrder, pixel: usize, sorted: &[u64]) -> Vec<u64> {
    let mut arrivals = sorted.to_vec();
    arrivals.sort_by_key(|&entry| {
        order
            .rank(Fragment {
                pixel: pixel as u32,
                depth_key: (entry >> 32) as u32,
                prim: entry as u32,
            })
            .unwrap_or(u32::MAX)
    });
    arrivals
}

/// The window depth of an entry (its key is the depth's bits: `depth_key` of a depth in [0, 1]).
fn depth_of(entry: u64) -> f32 {
    f32::from_bits((entry >> 32) as u32)
}

/// McGuire & Bavoil's weight of their eq. (10), on window depth `d` ∈ [0, 1]:
/// `w = α · max(10⁻², 3·10³ · (1 − d)³)`. Of the paper's four, the one defined on the depth
/// buffer's value rather than on eye-space distance, so that it needs nothing the entries lack.
#[must_use]
pub fn wboit_weight(alpha: f32, d: f32) -> f32 {
    alpha * (3.0e3 * (1.0 - d).powi(3)).max(1.0e-2)
}

/// WBOIT: accumulate `Σ c α w` and `Σ α w` (the accumulation target, additive blending) and
/// `Π (1 − α)` (the revealage target, multiplicative), then composite
/// `C = (Σ c α w / Σ α w) (1 − Π) + background · Π` (the paper's Listing 2 resolve).
#[expect(
    clippy::cast_possible_truncation,
    reason = "an entry packs the depth key (high 32 bits) and the primitive id (low 32)"
)]
fn wboit(material: &Material, arrivals: &[u64]) -> [f32; 3] {
    let alpha = material.opacity;
    let (mut accum, mut weight, mut revealage) = ([0.0_f32; 3], 0.0_f32, 1.0_f32);
    for &entry in arrivals {
        let c = primitive_colour(entry as u32, material.primitives);
        let w = wboit_weight(alpha, depth_of(entry));
        for ch in 0..3 {
            accum[ch] += c[ch] * w;
        }
        weight += w;
        revealage *= 1.0 - alpha;
    }
    if arrivals.is_empty() {
        return material.background;
    }
    // The paper clamps the denominator away from zero (1e-5), which only an underflow reaches.
    let average = accum.map(|a| a / weight.max(1.0e-5));
    [0, 1, 2].map(|ch| average[ch] * (1.0 - revealage) + material.background[ch] * revealage)
}

/// One MLAB node: the nearest depth of what it holds, its opacity and its colour (not
/// premultiplied), so that a node of one fragment shades with the exact effect's operations.
#[derive(Clone, Copy, Debug)]
struct Node {
    depth: u64,
    alpha: f32,
    colour: [f32; 3],
}

/// MLAB: insert each fragment into its pixel's depth-sorted nodes; when that makes `k + 1`,
/// merge the two farthest into one ("under": the nearer over the farther, at the nearer's
/// depth), so that a later fragment that belongs between them is blended in the wrong place.
/// Then composite the nodes front to back.
#[expect(
    clippy::cast_possible_truncation,
    reason = "an entry packs the depth key (high 32 bits) and the primitive id (low 32)"
)]
fn mlab(material: &Material, k: usize, arrivals: &[u64]) -> [f32; 3] {
    let mut nodes: Vec<Node> = Vec::with_capacity(k + 1);
    for &entry in arrivals {
        let node = Node {
            // The depth key and primitive: ties ordered as the exact lists order them.
            depth: entry,
            alpha: material.opacity,
            colour: primitive_colour(entry as u32, material.primitives),
        };
        let at = nodes.partition_point(|n| n.depth < node.depth);
        nodes.insert(at, node);
        if nodes.len() > k.max(1) {
            let far = nodes.pop().expect("k + 1 nodes");
            let near = nodes.last_mut().expect("k ≥ 1 nodes");
            let alpha = 1.0 - (1.0 - near.alpha) * (1.0 - far.alpha);
            for ch in 0..3 {
                let premultiplied =
                    near.alpha * near.colour[ch] + (1.0 - near.alpha) * far.alpha * far.colour[ch];
                near.colour[ch] = premultiplied / alpha.max(f32::MIN_POSITIVE);
            }
            near.alpha = alpha;
        }
    }
    composite(material, nodes.iter().map(|n| (n.alpha, n.colour)), None)
}

/// Tail blending: a k-buffer of the `k` nearest (inserted in arrival order, sorted); a fragment
/// that falls out of it (the newcomer, or the farthest it displaces) is blended at once into the
/// tail, over what the tail holds, unsorted ("over", in eviction order, starting from the
/// background); the `k` nearest are then composited front to back over the tail.
#[expect(
    clippy::cast_possible_truncation,
    reason = "an entry packs the depth key (high 32 bits) and the primitive id (low 32)"
)]
fn tail_blend(material: &Material, k: usize, arrivals: &[u64]) -> [f32; 3] {
    let alpha = material.opacity;
    let mut kept: Vec<u64> = Vec::with_capacity(k + 1);
    let mut tail: Option<[f32; 3]> = None;
    for &entry in arrivals {
        let at = kept.partition_point(|&e| e < entry);
        kept.insert(at, entry);
        if kept.len() > k {
            let evicted = kept.pop().expect("k + 1 entries");
            let c = primitive_colour(evicted as u32, material.primitives);
            let under = tail.unwrap_or(material.background);
            tail = Some([0, 1, 2].map(|ch| alpha * c[ch] + (1.0 - alpha) * under[ch]));
        }
    }
    let front = kept
        .iter()
        .map(|&e| (alpha, primitive_colour(e as u32, material.primitives)));
    composite(material, front, tail)
}

/// Front-to-back "under" compositing of `(α, colour)` layers over `behind` (the background when
/// `None`), with the exact effect's operations in its order (`C += T α c`, `T *= 1 − α`,
/// `C += T · behind`), so that the same layers give the same bits.
fn composite(
    material: &Material,
    layers: impl Iterator<Item = (f32, [f32; 3])>,
    behind: Option<[f32; 3]>,
) -> [f32; 3] {
    let (mut colour, mut transmittance) = ([0.0_f32; 3], 1.0_f32);
    for (alpha, c) in layers {
        for ch in 0..3 {
            colour[ch] += transmittance * alpha * c[ch];
        }
        transmittance *= 1.0 - alpha;
    }
    let behind = behind.unwrap_or(material.background);
    [0, 1, 2].map(|ch| colour[ch] + transmittance * behind[ch])
}
