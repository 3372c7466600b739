//! A capture judged against fragsim's oracle: the conformance verdict (the oracle's own,
//! [`fragsim_oracle::verdict::judge`], every word read) and, separately, **coverage**: whether the GPU produced exactly fragsim's
//! (pixel, primitive) pairs, whatever their depths.
//!
//! Coverage is what replay mode guarantees by construction (the GPU scans fragsim's own snapped
//! triangles), while depth is the GPU's f32 interpolation, so a replay capture can be
//! coverage-identical and still differ in depth keys: the two are reported apart. Coverage is
//! checked on the lists the dump decodes to (`Dump::capture`, the scheme's own resolve) at the
//! pixels where the scheme keeps every fragment (at most K, or the capacity, in the reference;
//! every pixel of the exact A-buffer), from the primitive ids stored (or, for key-only words, the
//! number of fragments).
//!
//! [`Within`] is the other verdict, the precision one: the dump judged within the precision of an
//! f32 vertex stage against the exact oracle under the dump's conventions, what `fragsim compare
//! oracle DIR --vertex-precision f32` prints (the same calls, [`f32_reference`] and the oracle's
//! verdict), its reference built once and shared by every capture of one view.

use std::borrow::Cow;

use fragsim_capture::{Capacity, Identity, Keeps};
use fragsim_dump::{Dump, DumpError, Words};
use fragsim_oracle::compare::Comparison;
use fragsim_oracle::precision::{f32_reference, Bounds, Precision};
use fragsim_oracle::verdict::{self, Candidate, Options, Reference, Verdict};
use fragsim_oracle::Oracle;
use fragsim_raster::scene_spec::SceneSpec;
use fragsim_raster::{Scene, VertexPrecision, Viewport};

/// The verdict and the coverage of one capture.
#[derive(Debug)]
pub struct Judgement {
    /// The oracle's verdict on the dump, every bit owed (`fragsim compare oracle DIR
    /// --depth-ulps N`).
    pub comparison: Comparison,
    /// Pixels where coverage was checked.
    pub coverage_checked: u64,
    /// Of those, pixels whose stored primitive ids (or fragment count) differ from fragsim's.
    pub coverage_differs: u64,
    /// A-buffer: pixels whose counter is not fragsim's fragment count (coverage of every pixel,
    /// overflowed ones included); `None` for MDTS layouts.
    pub counters_differ: Option<u64>,
}

impl Judgement {
    /// One line: the verdict's totals and the coverage.
    #[must_use]
    pub fn summary(&self) -> String {
        let c = &self.comparison;
        let d = &c.diff;
        let mut line = format!(
            "{}: {} differing pixels (missing {}, extra {}, misordered {}, miscounted {}, corrupt {}); fragments captured {}, lost {}, extra {}; coverage: {} of {} checked pixels differ",
            if c.is_equal() { "EQUAL" } else { "DIFFERENT" },
            d.mismatched_pixels,
            c.counts.missing,
            c.counts.extra,
            c.counts.misordered,
            c.counts.miscounted,
            c.counts.corrupt,
            d.captured,
            d.lost,
            d.extra,
            self.coverage_differs,
            self.coverage_checked
        );
        if let Some(n) = self.counters_differ {
            line += &format!(", counters differ at {n} pixels");
        }
        line
    }
}

/// Judges `dump` against `oracle`: `depth_ulps` as `fragsim compare --depth-ulps`.
///
/// # Errors
/// A dump its layout cannot decode, or one over another number of pixels than the oracle's.
pub fn judge(dump: &Dump, oracle: &Oracle, depth_ulps: u32) -> Result<Judgement, DumpError> {
    let pixels = oracle.pixels();
    let dump_pixels = dump.viewport()?.pixels();
    if dump_pixels != pixels {
        return Err(DumpError::Invalid(format!(
            "the dump covers {dump_pixels} pixels, the oracle {pixels}"
        )));
    }
    let (width, height) = (dump.header.width, dump.header.height);
    let reference = Reference::new(
        Cow::Borrowed(oracle),
        Cow::Owned(Precision::exact()),
        VertexPrecision::F64,
        (width, height),
    );
    let options = Options {
        depth_ulps,
        examples: 8,
    };
    let comparison = verdict::judge(&reference, Candidate::Dump(dump), &options)?.comparison;
    let capture = dump.capture()?;
    // The most fragments of a pixel the scheme keeps.
    let keeps = match &capture.keeps {
        Keeps::Nearest(k) | Keeps::Farthest(k) => *k as usize,
        Keeps::All { capacity, .. } => match capacity {
            Capacity::Unbounded => usize::MAX,
            Capacity::PerPixel(c) | Capacity::PerPixelUncounted(c) => *c as usize,
        },
    };
    let key_only = capture.identity == Identity::KeyOnly;
    let (mut checked, mut differs) = (0_u64, 0_u64);
    for p in 0..pixels {
        #[expect(
            clippy::shadow_unrelated,
            reason = "this pixel's list of the whole reference above"
        )]
        let reference = oracle.pixel(p);
        if reference.len() > keeps {
            continue;
        }
        checked += 1;
        let got = capture.pixel(p);
        let same = if key_only {
            got.len() == reference.len()
        } else {
            #[expect(
                clippy::cast_possible_truncation,
                reason = "a word's low half is its primitive id"
            )]
            let prims = |list: &[u64]| {
                let mut ids: Vec<u32> = list.iter().map(|&w| w as u32).collect();
                ids.sort_unstable();
                ids
            };
            prims(got) == prims(reference)
        };
        differs += u64::from(!same);
    }
    let counters = match dump.arrays.get("counters") {
        Some(Words::U32(c)) if dump.header.scheme == "abuffer" => Some(c.as_slice()),
        _ => None,
    };
    let counters_differ = counters.map(|c| {
        let n = oracle.depth_complexity();
        c.iter().zip(&n).filter(|(a, b)| a != b).count() as u64
    });
    Ok(Judgement {
        comparison,
        coverage_checked: checked,
        coverage_differs: differs,
        counters_differ,
    })
}

/// The reference of the precision verdict for one scene and viewport: the exact oracle under the
/// scene's conventions and what an f32 vertex stage may produce ([`f32_reference`]), with the
/// scene loaded, so that each verdict can judge samples exactly on an edge under whichever rule
/// the capture follows (the oracle's [`Reference::with_edge_ties`]).
#[derive(Debug)]
pub struct Within {
    scene: SceneSpec,
    /// The scene with the exact f64 vertex stage, as the oracle was built.
    exact: SceneSpec,
    loaded: Scene,
    viewport: Viewport,
    oracle: Oracle,
    precision: Precision,
    covered: u64,
}

/// One capture judged by [`Within::judge`].
#[derive(Debug)]
pub struct WithinJudgement {
    /// The verdict: error pixels are `diff.mismatched_pixels`, ambiguous ones `counts.ambiguous`.
    pub comparison: Comparison,
    /// The bounds derived for the view.
    pub bounds: Bounds,
    /// Pixels the reference covers (what the ambiguous pixels are a share of).
    pub covered: u64,
}

impl WithinJudgement {
    /// One line: the verdict, the error and ambiguous pixels, and the bounds, as `fragsim
    /// compare` prints them.
    #[must_use]
    pub fn summary(&self) -> String {
        let (c, b) = (&self.comparison, &self.bounds);
        format!(
            "{}: {} error pixels (missing {}, extra {}, misordered {}, miscounted {}, corrupt {}), {} ambiguous, {} within precision, of {} covered; bounds: vertex error up to {:.3} subpixels, depth intervals up to {} ulps, {} ambiguous (pixel, triangle) pairs; one snap per vertex: {} of {} jointly judged pixels decided by the pins, {} but for the triangle of a key-only word, {} contradicting",
            if c.is_equal() { "EQUAL" } else { "DIFFERENT" },
            c.diff.mismatched_pixels,
            c.counts.missing,
            c.counts.extra,
            c.counts.misordered,
            c.counts.miscounted,
            c.counts.corrupt,
            c.counts.ambiguous,
            c.counts.within_precision,
            self.covered,
            b.max_vertex_error_subpixels,
            b.max_depth_interval_ulps,
            b.ambiguous_pairs,
            c.snaps.decided_pixels,
            c.snaps.joint_pixels,
            c.snaps.unnamed_pixels,
            c.snaps.contradicting_pixels
        )
    }
}

impl Within {
    /// The reference for the scene and pixel viewport `dump` names: for a per-sample dump
    /// (`conventions.samples` above 1, [`crate::capture_samples`]) the exact oracle per sample
    /// and the bounds of an f32 vertex stage at every sample.
    ///
    /// # Errors
    /// As [`f32_reference`]: a bad viewport, or a scene that cannot be loaded or rasterized.
    pub fn of(dump: &Dump) -> Result<Self, DumpError> {
        let viewport = dump.header.pixel_viewport()?;
        let scene = dump.header.scene.clone();
        let (oracle, precision) = f32_reference(&scene, viewport, None)?;
        let covered = (0..oracle.pixels())
            .filter(|&p| !oracle.pixel(p).is_empty())
            .count() as u64;
        let mut exact = scene.clone();
        exact.conventions.vertex_precision = VertexPrecision::F64;
        Ok(Self {
            loaded: exact.load(None)?,
            scene,
            exact,
            viewport,
            oracle,
            precision,
            covered,
        })
    }

    /// The exact oracle judged against (for replay dumps, which declare the reference
    /// conventions, fragsim's own oracle of the view: what [`judge`] takes).
    #[must_use]
    pub fn oracle(&self) -> &Oracle {
        &self.oracle
    }

    /// Whether `dump` names this reference's scene (its sample count included) and viewport.
    #[must_use]
    pub fn fits(&self, dump: &Dump) -> bool {
        dump.header.scene == self.scene
            && (dump.header.width, dump.header.height)
                == (self.viewport.width, self.viewport.height)
    }

    /// `dump` judged within precision by the oracle's verdict, every word read: one line of
    /// figures ([`WithinJudgement`]).
    ///
    /// # Errors
    /// A dump of another scene or viewport, or one its layout cannot decode.
    pub fn judge(&self, dump: &Dump) -> Result<WithinJudgement, DumpError> {
        let verdict = self.verdict(dump)?;
        Ok(WithinJudgement {
            bounds: verdict.bounds.unwrap_or_default(),
            comparison: verdict.comparison,
            covered: self.covered,
        })
    }

    /// `dump` judged within precision: the oracle's whole [`Verdict`] (per sample, its
    /// `per_sample` counts), what `fragsim compare oracle DIR --vertex-precision f32` prints.
    ///
    /// # Errors
    /// As [`Within::judge`].
    pub fn verdict(&self, dump: &Dump) -> Result<Verdict, DumpError> {
        if !self.fits(dump) {
            return Err(DumpError::Invalid(
                "the dump names another scene or viewport than the reference's".into(),
            ));
        }
        let options = Options {
            depth_ulps: 0,
            examples: 8,
        };
        let view = self.exact.view(&self.loaded, self.viewport)?;
        let reference = Reference::new(
            Cow::Borrowed(&self.oracle),
            Cow::Borrowed(&self.precision),
            VertexPrecision::F32,
            (self.viewport.width, self.viewport.height),
        )
        .with_edge_ties(&view);
        verdict::judge(&reference, Candidate::Dump(dump), &options).map_err(DumpError::from)
    }

    /// Lists (pixels, or samples of a per-sample dump) the reference covers: what ambiguous
    /// ones are a share of.
    #[must_use]
    pub fn covered(&self) -> u64 {
        self.covered
    }
}
