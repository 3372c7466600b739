//! What a candidate is judged against: the oracle of a view under the precision its vertex stage
//! owes, the per-pixel view of the per-sample oracle (masked-node dumps), or another dump's lists
//! with what such a reference cannot know.

use std::borrow::Cow;

use fragsim_capture::MaskedLists;
use fragsim_capture::{Capacity, Capture, Identity, Keeps, PixelLists};
use fragsim_raster::{Conventions, EdgeTies, VertexPrecision, View};

use super::VerdictError;
use crate::compare::complete_pixels;
use crate::edge_ties::{candidates, pipeline_rule};
use crate::precision::Precision;
use crate::Oracle;
use fragsim_dump::Dump;

/// The reference side of a verdict ([`super::judge`]).
#[derive(Clone, Debug)]
pub struct Reference<'a> {
    /// The reference's lists: the oracle's, or a dump's decoded ones.
    lists: Cow<'a, Oracle>,
    /// How it knows them: what [`super::judge`] dispatches on.
    pub(super) kind: Kind<'a>,
    /// Viewport width, pixels.
    pub(super) width: u32,
    /// Viewport height, pixels.
    pub(super) height: u32,
    /// Notes on the sides made before the verdict (dumps of different scenes compared anyway).
    pub(super) notes: Vec<String>,
}

/// How a reference knows its lists.
#[derive(Clone, Debug)]
pub(super) enum Kind<'a> {
    /// The oracle, owed within `precision` by a vertex stage of `vertex_precision`, with the
    /// view to judge samples exactly on an edge under another rule than the pipeline's.
    Oracle {
        precision: Cow<'a, Precision>,
        vertex_precision: VertexPrecision,
        edge_ties: Option<EdgeTieSource<'a>>,
    },
    /// The per-pixel view of the per-sample oracle (masked nodes): every bit owed, or, with
    /// `within`, each node judged at each sample it covers within an f32 vertex stage's
    /// precision.
    Masked {
        nodes: MaskedLists,
        within: Option<MaskedWithin>,
    },
    /// Another dump's decoded lists.
    Dump {
        /// Whether each pixel's list holds every fragment of the pixel.
        complete: Vec<bool>,
        keeps: Keeps,
        identity: Identity,
        /// Words its layout says cannot be there: the comparison is then never equal.
        corrupt_words: u64,
        /// Why the dump may not be the whole truth.
        notes: Vec<String>,
    },
}

/// What judging masked nodes within precision needs: the per-sample oracle and the bounds of an
/// f32 vertex stage at every sample ([`JudgeDump::compare_masked_within`](super::JudgeDump::compare_masked_within)).
#[derive(Clone, Debug)]
pub(super) struct MaskedWithin {
    /// The exact oracle, a list per (pixel, sample).
    pub(super) samples: Oracle,
    /// The bounds at every sample.
    pub(super) precision: Precision,
}

/// What judging samples exactly on an edge under another rule needs: the view the oracle was
/// built from, the conventions the precision was derived under, and the rules the implementation
/// may follow (`docs/semantics.md` §4, "Edge ties").
#[derive(Clone, Debug)]
pub(super) struct EdgeTieSource<'a> {
    /// The view of the reference's oracle (the pipeline's rule).
    pub(super) view: &'a View<'a>,
    /// The conventions of the vertex stage judged (what [`Precision::derive_under`] takes).
    pub(super) conventions: Conventions,
    /// The rules, in fragsim's rows, a conforming capture may follow: the declared one, or all.
    pub(super) candidates: Vec<EdgeTies>,
    /// The rule the oracle was rasterized with.
    pub(super) pipeline: EdgeTies,
}

impl<'a> Reference<'a> {
    /// The oracle `oracle` of a `width × height` viewport, owed within `precision` by an
    /// implementation whose vertex stage computes in `vertex_precision` (an exact `precision`,
    /// f64: every bit). Samples exactly on an edge are owed as the oracle decides them, unless
    /// [`Reference::with_edge_ties`] gives the view.
    #[must_use]
    pub fn new(
        oracle: Cow<'a, Oracle>,
        precision: Cow<'a, Precision>,
        vertex_precision: VertexPrecision,
        (width, height): (u32, u32),
    ) -> Self {
        Self {
            lists: oracle,
            kind: Kind::Oracle {
                precision,
                vertex_precision,
                edge_ties: None,
            },
            width,
            height,
            notes: Vec::new(),
        }
    }

    /// This oracle reference judging samples exactly on an edge as the implementation's
    /// conventions allow (`view`, the oracle's view, says which): under the rule declared in
    /// `conventions.edge_ties`, or, undeclared, under whichever one rule explains the capture
    /// ([`crate::edge_ties`]). Another reference is returned as it is.
    #[must_use]
    pub fn with_edge_ties(mut self, view: &'a View<'a>) -> Self {
        if let Kind::Oracle {
            vertex_precision,
            edge_ties,
            ..
        } = &mut self.kind
        {
            let declared = view.conventions();
            let conventions = Conventions {
                vertex_precision: *vertex_precision,
                ..declared
            };
            *edge_ties = Some(EdgeTieSource {
                view,
                conventions,
                candidates: candidates(declared.edge_ties, declared.window_origin),
                pipeline: pipeline_rule(declared.window_origin),
            });
        }
        self
    }

    /// The oracle `oracle` of `view` (the reference's f64 pipeline under the conventions the
    /// implementation declares), owed by a vertex stage of `vertex_precision`: every bit under
    /// f64, the bounds [`Precision::derive`] finds under f32; samples exactly on an edge under
    /// any one rule, or the declared one ([`Reference::with_edge_ties`]).
    #[must_use]
    pub fn of_view(
        oracle: &'a Oracle,
        view: &'a View<'a>,
        vertex_precision: VertexPrecision,
    ) -> Self {
        let conventions = Conventions {
            vertex_precision,
            ..view.conventions()
        };
        let viewport = view.pixel_viewport();
        Self::new(
            Cow::Borrowed(oracle),
            Cow::Owned(Precision::derive(view, &conventions)),
            vertex_precision,
            (viewport.width, viewport.height),
        )
        .with_edge_ties(view)
    }

    /// The per-pixel view of the per-sample oracle, `nodes`, over a `width × height` viewport:
    /// what a masked-node dump is judged against.
    #[must_use]
    pub fn masked(nodes: MaskedLists, (width, height): (u32, u32)) -> Self {
        Self {
            lists: Cow::Owned(Oracle::from_capture(
                &nodes.packed_capture(Capacity::Unbounded),
            )),
            kind: Kind::Masked {
                nodes,
                within: None,
            },
            width,
            height,
            notes: Vec::new(),
        }
    }

    /// This masked-node reference judging each node at each sample it covers within
    /// `precision`, the bounds of an f32 vertex stage at every sample of `samples`, the exact
    /// per-sample oracle (a list per (pixel, sample)) whose per-pixel view this is. Another
    /// reference is returned as it is.
    #[must_use]
    pub fn masked_within(mut self, samples: Oracle, precision: Precision) -> Self {
        if let Kind::Masked { within, .. } = &mut self.kind {
            *within = Some(MaskedWithin { samples, precision });
        }
        self
    }

    /// `dump`'s decoded lists: a reference that knows every fragment only where its list is not
    /// full, and that is not trusted when a word of it is corrupt.
    ///
    /// # Errors
    /// A dump that cannot be decoded.
    pub fn dump(dump: &Dump) -> Result<Self, VerdictError> {
        let capture = dump.capture()?;
        let mut notes = caveats(&capture);
        let corrupt_words = dump.check_words()?.corrupt_words();
        if corrupt_words > 0 {
            notes.push(format!(
                "the reference dump holds {corrupt_words} words its layout says cannot be there: \
                 the comparison cannot be trusted, and is not called equal"
            ));
        }
        Ok(Self {
            lists: Cow::Owned(Oracle::from_capture(&capture)),
            kind: Kind::Dump {
                complete: complete_pixels(&capture),
                keeps: capture.keeps,
                identity: capture.identity,
                corrupt_words,
                notes,
            },
            width: dump.header.width,
            height: dump.header.height,
            notes: Vec::new(),
        })
    }

    /// The reference's lists.
    #[must_use]
    pub fn oracle(&self) -> &Oracle {
        &self.lists
    }

    /// The vertex stage the candidate is judged as (f64 but against the oracle under f32).
    pub(super) fn vertex_precision(&self) -> VertexPrecision {
        match &self.kind {
            Kind::Oracle {
                vertex_precision, ..
            } => *vertex_precision,
            Kind::Masked {
                within: Some(_), ..
            } => VertexPrecision::F32,
            _ => VertexPrecision::F64,
        }
    }

    /// What a masked reference judges within precision with (`None`: every bit owed).
    pub(super) fn masked_within_precision(&self) -> Option<&MaskedWithin> {
        match &self.kind {
            Kind::Masked { within, .. } => within.as_ref(),
            _ => None,
        }
    }

    /// Corrupt words of a reference dump.
    pub(super) fn corrupt_words(&self) -> u64 {
        match &self.kind {
            Kind::Dump { corrupt_words, .. } => *corrupt_words,
            _ => 0,
        }
    }

    /// Lists per pixel: the samples of a per-sample layout, else 1.
    #[expect(
        clippy::cast_possible_truncation,
        reason = "samples per pixel, at most 16"
    )]
    pub(super) fn lists_per_pixel(&self) -> u32 {
        let pixels = (self.width as usize * self.height as usize).max(1);
        // Masked nodes judged within precision are judged a sample at a time.
        let lists = self
            .masked_within_precision()
            .map_or(self.lists.pixels(), |within| within.samples.pixels());
        (lists / pixels).max(1) as u32
    }

    /// Takes out of `candidate` the fragments a K-list dump reference cannot know: in a pixel
    /// where the reference is full, those beyond its K-th (farther for K nearest, nearer for K
    /// farthest), which it would have dropped itself. Returns the note that says how many.
    pub(super) fn drop_unknowable(&self, candidate: &mut Capture) -> Option<String> {
        let Kind::Dump {
            keeps, complete, ..
        } = &self.kind
        else {
            return None;
        };
        let nearest = match keeps {
            Keeps::Nearest(_) => true,
            Keeps::Farthest(_) => false,
            Keeps::All { .. } => return None,
        };
        let mask = match candidate.identity {
            Identity::KeyAndPrim | Identity::MaskedNodes(_) => u64::MAX,
            Identity::KeyOnly => u64::MAX << 32,
            Identity::PrimOnly => return None,
        };
        let mut lists = PixelLists::with_pixels(candidate.pixels());
        let (mut dropped, mut pixels) = (0, 0);
        for (p, &known) in complete.iter().enumerate() {
            let reference = self.lists.pixel(p);
            let bound = if nearest {
                reference.last()
            } else {
                reference.first()
            };
            let got = candidate.pixel(p);
            #[expect(
                clippy::shadow_unrelated,
                reason = "the bound each caller passes, not the one above"
            )]
            let beyond = |e: u64, bound: u64| {
                if nearest {
                    e & mask > bound & mask
                } else {
                    e & mask < bound & mask
                }
            };
            let kept: Vec<u64> = match bound.filter(|_| !known) {
                Some(&bound) => got
                    .iter()
                    .copied()
                    .filter(|&e| e == u64::MAX || !beyond(e, bound))
                    .collect(),
                None => got.to_vec(),
            };
            let gone = (got.len() - kept.len()) as u64;
            dropped += gone;
            pixels += u64::from(gone > 0);
            lists.push_pixel(kept);
        }
        candidate.lists = lists;
        (dropped > 0).then(|| {
            format!(
                "{dropped} candidate fragments in {pixels} pixels lie beyond what the reference \
                 kept there (its K-th fragment) and cannot be judged: not counted as extra"
            )
        })
    }
}

/// Why a dump used as the reference may not be the whole truth.
fn caveats(capture: &Capture) -> Vec<String> {
    match &capture.keeps {
        Keeps::Nearest(k) | Keeps::Farthest(k) => {
            let full = (0..capture.pixels())
                .filter(|&p| capture.pixel(p).len() >= *k as usize)
                .count();
            (full > 0)
                .then(|| {
                    format!(
                        "the reference is an MDTS dump keeping {k} fragments per pixel and \
                         {full} pixels are full: fragments beyond K there are unknown to it"
                    )
                })
                .into_iter()
                .collect()
        }
        Keeps::All { overflow, .. } => {
            let lost: u64 = overflow.iter().map(|&o| u64::from(o)).sum();
            (lost > 0)
                .then(|| {
                    format!("the reference A-buffer overflowed: {lost} fragments are unknown to it")
                })
                .into_iter()
                .collect()
        }
    }
}
