//! What the peeling schemes share: the per-pixel layer storage of depth peeling and dual depth
//! peeling, and the z-buffer's depth test that depth peeling's passes and the z-buffer end a walk
//! with.

use std::marker::PhantomData;

use fragsim_memory::{Layout, Memory, Word, WordMemory};
use fragsim_raster::Viewport;

use super::MdtsWord;
use fragsim_capture::Guarantee;
use fragsim_capture::{Capacity, Identity};
use fragsim_capture::{CaptureError, Descriptor, Promise, Step};

/// The storage of a peeling scheme: per pixel, `working` words of type `W` that the geometry
/// passes compete on, `layers` output slots that the between-pass kernel fills, and a `u32`
/// overflow counter.
///
/// Every word starts all ones (a [`Layout`] has one initial value per array, and with `u32` words
/// the counters share the array): all ones is the empty value of a slot and of an `atomicMin`
/// word, no fragment's value reaches it, and the counter is kept complemented so that it reads 0.
#[derive(Clone, Debug)]
pub(crate) struct LayerStorage<W> {
    descriptor: Descriptor,
    working: usize,
    layers: usize,
    _word: PhantomData<W>,
}

impl<W: MdtsWord> LayerStorage<W> {
    /// Storage for `viewport` with `working` words and `max_layers` slots per pixel, for the
    /// peeling scheme named `base` (`base32` on `u32` words), whose descriptor it holds.
    ///
    /// # Errors
    /// `max_layers == 0`, or storage beyond `memory_cap` bytes.
    pub(crate) fn new(
        base: &str,
        viewport: Viewport,
        working: usize,
        max_layers: u32,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        let name = match W::IDENTITY {
            Identity::KeyOnly => format!("{base}32"),
            _ => base.into(),
        };
        if max_layers == 0 {
            return Err(CaptureError::BadParameter(format!(
                "{name} needs storage for at least 1 layer per pixel, got 0 layers"
            )));
        }
        let pixels = viewport.pixels();
        let words = pixels * (working + max_layers as usize);
        // With `u32` words the counters follow the words of type `W`.
        let (words32, words64) = match W::IDENTITY {
            Identity::KeyOnly => (words + pixels, 0),
            _ => (pixels, words),
        };
        let descriptor = Descriptor {
            name,
            layout: Layout {
                words32,
                init32: u32::MAX,
                words64,
                init64: u64::MAX,
                table_bytes: 0,
            },
            identity: W::IDENTITY,
            // 32-bit depth keys merge equal depths into one layer; 64-bit words are all distinct.
            guarantee: match W::IDENTITY {
                Identity::KeyOnly => Guarantee::ExactDistinctDepths,
                _ => Guarantee::Exact,
            },
            promise: Promise::All(Capacity::PerPixel(max_layers)),
            pixels,
            counts_every_drop: false,
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            working,
            layers: max_layers as usize,
            _word: PhantomData,
        })
    }

    /// The peeling scheme's descriptor.
    pub(crate) fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn stride(&self) -> usize {
        self.working + self.layers
    }

    /// Words of type `W` before the counters: with `u32` words the counters follow them.
    fn words(&self) -> usize {
        self.pixels() * self.stride()
    }

    pub(crate) fn pixels(&self) -> usize {
        self.descriptor.pixels
    }

    /// Output slots per pixel.
    pub(crate) fn layers(&self) -> usize {
        self.layers
    }

    /// Index of `pixel`'s first working word.
    pub(crate) fn working(&self, pixel: usize) -> usize {
        pixel * self.stride()
    }

    fn slot(&self, pixel: usize, slot: usize) -> usize {
        pixel * self.stride() + self.working + slot
    }

    fn counter(&self, pixel: usize) -> usize {
        match W::IDENTITY {
            Identity::KeyOnly => self.words() + pixel,
            _ => pixel,
        }
    }

    /// Writes a peeled layer into `slot` of `pixel`, or counts it as overflow where there is no
    /// slot for it (`None`).
    pub(crate) fn put<M: Memory>(&self, memory: &M, pixel: usize, slot: Option<usize>, value: W) {
        match slot {
            Some(slot) => W::words(memory).store(self.slot(pixel, slot), value),
            None => {
                let counter = self.counter(pixel);
                let complemented = WordMemory::<u32>::load(memory, counter);
                WordMemory::<u32>::store(memory, counter, complemented - 1);
            }
        }
    }

    /// The post pass: the pixel's filled slots in slot order (which the schemes keep ascending),
    /// decoded; returns the pixel's overflow count.
    pub(crate) fn resolve<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        let words = W::words(memory);
        out.extend(
            (0..self.layers)
                .map(|slot| words.load(self.slot(pixel, slot)))
                .filter(|&value| value != W::MAX)
                .map(MdtsWord::decode),
        );
        u32::MAX - WordMemory::<u32>::load(memory, self.counter(pixel))
    }
}

/// The end of a walk whose `atomicMin` with `value` saw `old`: stored when it lowered the word,
/// discarded when it failed the depth test (an equal word fails it too, as the GPU's `LESS` test
/// does).
pub(crate) fn depth_test<W: Word>(old: W, value: W) -> Step {
    if value < old {
        Step::Stored
    } else {
        Step::Discarded
    }
}
