//! A capture judged against fragsim's oracle: the conformance verdict (`Dump::compare`, every
//! word read) and, separately, **coverage**: whether the GPU produced exactly fragsim's
//! (pixel, primitive) pairs, whatever their depths.
//!
//! Coverage is what replay mode guarantees by construction (the GPU scans fragsim's own snapped
//! triangles), while depth is the GPU's f32 interpolation, so a replay capture can be
//! coverage-identical and still differ in depth keys: the two are reported apart. Coverage is
//! checked on the lists the dump decodes to (`Dump::capture`, the scheme's own resolve) at the
//! pixels where the scheme keeps every fragment (at most K, or the capacity, in the reference;
//! every pixel of the exact A-buffer), from the primitive ids stored (or, for key-only words, the
//! number of fragments).

use fragsim_capture::{Capacity, Identity, Keeps};
use fragsim_oracle::compare::{CompareOptions, Comparison};
use fragsim_oracle::dump::{Dump, DumpError, Words};
use fragsim_oracle::Oracle;

/// The verdict and the coverage of one capture.
#[derive(Debug)]
pub struct Judgement {
    /// `Dump::compare` against the oracle.
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
        return Err(DumpError(format!(
            "the dump covers {dump_pixels} pixels, the oracle {pixels}"
        )));
    }
    // The oracle knows every fragment (`complete: None`); any option added later keeps its
    // default.
    let options = CompareOptions {
        depth_ulps,
        examples: 8,
        ..Default::default()
    };
    let comparison = dump.compare(oracle, &options)?;
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
    let (mut checked, mut differs) = (0u64, 0u64);
    for p in 0..pixels {
        let reference = oracle.pixel(p);
        if reference.len() > keeps {
            continue;
        }
        checked += 1;
        let got = capture.pixel(p);
        let same = if key_only {
            got.len() == reference.len()
        } else {
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
