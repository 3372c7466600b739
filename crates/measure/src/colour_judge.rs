//! The error-pixel judge shared by `bench` and `sweep`: shades an effect from a capture and
//! counts the pixels whose 8-bit colour differs from the oracle's image (the papers' EPR).
//!
//! **The judge shades what the scheme holds.** Entries with a depth key and a primitive id are
//! shaded as they are. FreePipe's packed MDTS ([`Identity::PrimOnly`](fragsim_capture::Identity))
//! is shaded from its own words: the primitive ids its colours decode to, in its own slot order,
//! at the depths its 20 bits hold (the entries' high half, `mdts_packed::held_depth`), so its
//! precision loss (FreePipe §5) shows in every effect. Nothing of it comes from the oracle.
//!
//! Two things are not in the words; the deferred attribute pass
//! ([`fragsim_shade::deferred`]) supplies them, and each row reports what it did
//! ([`AttributePass`]): the **normals** (Fresnel only), recomputed per captured entry from its
//! pixel and primitive id, counted and timed; and the **primitive ids of key-only captures**
//! (32-bit MDTS, peeling and bucket schemes), completed from the oracle's lists.
//!
//! Every capture is then compared with the one reference image, shaded from the oracle's lists:
//! the error pixels, and the colour error ([`fragsim_shade::colour_error`]: mean and maximum
//! absolute error per channel, PSNR), which the approximate OIT schemes' images
//! ([`crate::approximate`]) are judged by too.

use std::time::Instant;

use fragsim_capture::{Capture, PixelLists};
use fragsim_oracle::Oracle;
use fragsim_raster::attributes::Attributes;
use fragsim_raster::{OrbitCamera, Scene, View};
use fragsim_shade::colour_error::{colour_error, ColourDeviation};
use fragsim_shade::deferred::{self, PerEntry};
use fragsim_shade::effects::{self, Effect, Entries, Geometry, Material};
use image::RgbImage;
use serde::Serialize;

/// Effects whose images are compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "args", derive(clap::ValueEnum))]
pub enum EffectName {
    /// Front-to-back transparency.
    Transparency,
    /// Beer–Lambert translucency.
    Translucency,
    /// Schlick's Fresnel transmittance along the list (needs normals: computed only for it).
    Fresnel,
}

impl EffectName {
    /// The effect.
    #[must_use]
    pub fn effect(self) -> Effect {
        match self {
            Self::Transparency => Effect::Transparency,
            Self::Translucency => Effect::Translucency,
            Self::Fresnel => Effect::Fresnel,
        }
    }

    /// Its name in file names and reports.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            Self::Transparency => "transparency",
            Self::Translucency => "translucency",
            Self::Fresnel => "fresnel",
        }
    }
}

type Distance<'a> = Box<dyn Fn(f32) -> f64 + Sync + 'a>;

/// What the judge had to do to a capture beyond reading its entries (`None` in a row: nothing).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AttributePass {
    /// What the judge took from the oracle's lists because the scheme's words do not hold it
    /// (`None`: the image is shaded from the scheme's own words alone).
    pub completed_from_oracle: Option<&'static str>,
    /// Entries whose attributes (the interpolated normal) were recomputed from pixel and
    /// primitive id: the deferred attribute pass, run for Fresnel.
    pub recomputed_entries: u64,
    /// Time of the completion and the recomputation on this machine, in milliseconds (for a
    /// completed capture, a GPU would pay a second geometry pass instead).
    pub ms: f64,
}

/// The colour error of an image as rows and records carry it (`docs/json-schema.md`): every
/// field `None` (`null`) where there is no image (the words cannot resolve the effect).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct ColourColumns {
    /// Mean absolute error per channel (R, G, B), in 8-bit units.
    pub mean_abs_error: Option<[f64; 3]>,
    /// Largest absolute error per channel, in 8-bit units.
    pub max_abs_error: Option<[u8; 3]>,
    /// Peak signal-to-noise ratio in dB; `None` also for an image equal to the oracle's (its
    /// PSNR is infinite, which JSON cannot hold: `mean_abs_error` is then zeros, not `null`).
    pub psnr_db: Option<f64>,
}

impl ColourColumns {
    /// The columns of `error`, where there is an image.
    pub fn of(error: Option<ColourDeviation>) -> Self {
        error.map_or_else(Self::default, |e| Self {
            mean_abs_error: Some(e.mean_abs),
            max_abs_error: Some(e.max_abs),
            psnr_db: e.psnr_db.is_finite().then_some(e.psnr_db),
        })
    }

    /// The table's three cells: the mean over the channels of the mean absolute error, the
    /// largest error of any channel, the PSNR (`inf` for an equal image); `n/a` without an image.
    pub fn cells(&self) -> [String; 3] {
        match (self.mean_abs_error, self.max_abs_error) {
            (Some(mean), Some(max)) => [
                format!("{:.3}", mean.iter().sum::<f64>() / 3.0),
                max.into_iter().max().unwrap_or(0).to_string(),
                self.psnr_db.map_or("inf".into(), |p| format!("{p:.2}")),
            ],
            _ => ["n/a".into(), "n/a".into(), "n/a".into()],
        }
    }
}

/// A capture's image against the oracle's.
#[derive(Debug)]
pub struct JudgedImage<'j> {
    /// The capture's image.
    pub image: RgbImage,
    /// The oracle's image.
    pub reference: &'j RgbImage,
    /// Pixels whose 8-bit colour differs.
    pub errors: u64,
    /// How far its colours are from the oracle's.
    pub colour: ColourDeviation,
    /// What was completed or recomputed, if anything.
    pub pass: Option<AttributePass>,
}

/// Shades captures and compares them with the oracle's image.
///
/// A judge of a view rasterizing per sample ([`ColourJudge::per_sample`]) shades every sample of the
/// sample-expanded lists and resolves each pixel from its samples
/// ([`effects::render_resolved`], `docs/semantics.md` §11): its images are the render target's
/// size, its reference the per-sample oracle's resolved image.
pub struct ColourJudge<'a> {
    effect: Effect,
    material: Material,
    size: (u32, u32),
    /// Samples a pixel (1: the view does not rasterize per sample).
    samples: u32,
    distance: Distance<'a>,
    /// The deferred attribute pass of the view: only when the effect needs normals.
    attributes: Option<Attributes<'a>>,
    oracle: &'a Oracle,
    reference: RgbImage,
    /// Pixels the oracle covers (at any of their samples): the rate's denominator.
    pub covered: usize,
}

impl std::fmt::Debug for ColourJudge<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ColourJudge")
            .field("effect", &self.effect)
            .field("size", &self.size)
            .field("samples", &self.samples)
            .field("covered", &self.covered)
            .finish_non_exhaustive()
    }
}

impl<'a> ColourJudge<'a> {
    /// The judge of `effect` for `view` of `scene` through `orbit` (a view rasterizing per
    /// sample through [`ColourJudge::per_sample`], which refuses what is not resolved per sample).
    pub fn new(
        effect: EffectName,
        scene: &Scene,
        view: &View<'a>,
        orbit: OrbitCamera,
        oracle: &'a Oracle,
    ) -> Self {
        let viewport = view.pixel_viewport();
        let aspect = f64::from(viewport.width) / f64::from(viewport.height);
        let bounds = scene.mesh.bounds();
        let (lo, hi) = bounds;
        let radius = (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt() * 0.5;
        // Thickness in units of the model's bounding radius, so σ means the same on every mesh.
        let distance: Distance<'a> =
            Box::new(move |z: f32| orbit.eye_distance(bounds, aspect, z) / radius.max(1e-12));
        let material = Material {
            primitives: view.triangle_count(),
            ..Material::default()
        };
        let effect = effect.effect();
        let attributes = (effect == Effect::Fresnel).then(|| Attributes::new(view));
        let samples = view.samples().map_or(1, |pattern| pattern.count());
        let covered = oracle
            .depth_complexity()
            .chunks(samples as usize)
            .filter(|pixel| pixel.iter().any(|&c| c > 0))
            .count();
        let mut judge = Self {
            effect,
            material,
            size: (viewport.width, viewport.height),
            samples,
            distance,
            attributes,
            oracle,
            reference: RgbImage::new(0, 0),
            covered,
        };
        let cosines = judge.recompute(|p| oracle.pixel(p));
        judge.reference = judge.shade(|p| oracle.pixel(p), cosines.as_ref());
        judge
    }

    /// The judge of `effect` for `view` rasterizing per sample, against `oracle`, the per-sample
    /// oracle's lists ([`fragsim_oracle::samples::SampleOracle::oracle`]).
    ///
    /// # Errors
    /// A view at one sample, or Fresnel: its normals are recomputed per pixel centre, not per
    /// sample.
    pub fn per_sample(
        effect: EffectName,
        scene: &Scene,
        view: &View<'a>,
        orbit: OrbitCamera,
        oracle: &'a Oracle,
    ) -> Result<Self, String> {
        if view.samples().is_none() {
            return Err("a per-sample judge needs a view rasterizing per sample".into());
        }
        if effect.effect() == Effect::Fresnel {
            return Err(format!(
                "{} is not resolved per sample (its normals are a pixel centre's)",
                effect.label()
            ));
        }
        Ok(Self::new(effect, scene, view, orbit, oracle))
    }

    /// The oracle's image.
    pub fn reference(&self) -> Option<&RgbImage> {
        Some(&self.reference)
    }

    /// The effect judged.
    pub fn effect(&self) -> Effect {
        self.effect
    }

    /// The material every image is shaded with.
    pub fn material(&self) -> &Material {
        &self.material
    }

    /// The images' width and height.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// `image`, shaded by whatever means at the judge's size, compared with the oracle's;
    /// `pass`: what was completed or recomputed to shade it.
    ///
    /// # Errors
    /// The image is not the judge's size.
    pub fn judge_image(
        &self,
        image: RgbImage,
        pass: Option<AttributePass>,
    ) -> Result<JudgedImage<'_>, String> {
        let colour = colour_error(&self.reference, &image).map_err(|e| e.to_string())?;
        let errors = effects::error_pixels(&self.reference, &image) as u64;
        Ok(JudgedImage {
            image,
            reference: &self.reference,
            errors,
            colour,
            pass,
        })
    }

    fn pixels(&self) -> usize {
        self.size.0 as usize * self.size.1 as usize
    }

    /// The deferred attribute pass over `lists`: `|cos θ|` of every entry, from its pixel and
    /// primitive id (1 where the primitive does not cover the pixel: an entry no fragment has);
    /// `None` when the effect needs no normals.
    fn recompute<'l>(&self, lists: impl Fn(usize) -> &'l [u64] + Sync) -> Option<PerEntry> {
        let attributes = self.attributes.as_ref()?;
        Some(deferred::cosines(attributes, self.pixels(), lists))
    }

    fn shade<'l>(
        &self,
        list: impl Fn(usize) -> &'l [u64] + Sync,
        cosines: Option<&PerEntry>,
    ) -> RgbImage {
        let cosine = |p: usize, entry: u64| cosines.map_or(1.0, |c| c.get(list(p), p, entry));
        let geometry = Geometry {
            distance: &*self.distance,
            cosine: &cosine,
        };
        // At one sample the resolve is the single-sample image bit for bit (§11).
        effects::render_resolved(
            self.effect,
            &self.material,
            Entries::KeyAndPrim,
            self.size,
            self.samples,
            &list,
            geometry,
        )
        .expect("full identities resolve every effect")
    }

    /// The capture's image, compared with the oracle's.
    pub fn judge(&self, capture: &Capture) -> Option<JudgedImage<'_>> {
        let start = Instant::now();
        let (full, completed) = deferred::complete(capture, self.oracle);
        self.judge_full(&full.lists, completed, start)
    }

    /// The image of `lists` of full identities (depth key and primitive id, indexed like the
    /// oracle's), compared with the oracle's: the masked nodes' per-sample resolve.
    pub fn judge_lists(&self, lists: &PixelLists) -> Option<JudgedImage<'_>> {
        self.judge_full(lists, None, Instant::now())
    }

    /// The image of `full`, `completed` from the oracle (what, if anything) since `start`.
    fn judge_full(
        &self,
        full: &PixelLists,
        completed: Option<&'static str>,
        start: Instant,
    ) -> Option<JudgedImage<'_>> {
        let cosines = self.recompute(|p| full.pixel(p));
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let recomputed_entries = cosines.as_ref().map_or(0, |c| c.len() as u64);
        let pass = (completed.is_some() || cosines.is_some()).then_some(AttributePass {
            completed_from_oracle: completed,
            recomputed_entries,
            ms,
        });
        let image = self.shade(|p| full.pixel(p), cosines.as_ref());
        self.judge_image(image, pass).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fragsim_capture::{Identity, Keeps};

    /// Two stacked squares: every covered pixel has a near and a far layer.
    fn two_layers() -> (Scene, OrbitCamera) {
        (
            Scene::procedural("quads:2").unwrap(),
            OrbitCamera::default(),
        )
    }

    /// The oracle's lists as a capture of `identity`, each entry passed through `entry(i, e)`
    /// (`i`: its position in the pixel's list).
    fn capture_of(
        oracle: &Oracle,
        identity: Identity,
        entry: impl Fn(usize, u64) -> u64,
    ) -> Capture {
        let mut capture = Capture::with_pixels(oracle.pixels(), identity, Keeps::Nearest(2));
        for p in 0..oracle.pixels() {
            capture.push_pixel(
                oracle
                    .pixel(p)
                    .iter()
                    .enumerate()
                    .map(|(i, &e)| entry(i, e)),
            );
        }
        capture
    }

    #[test]
    #[expect(
        clippy::shadow_unrelated,
        reason = "each `judged` and `pass` is its own case's"
    )]
    fn a_prim_only_capture_is_shaded_at_the_depths_it_holds_not_the_oracles() {
        let (scene, orbit) = two_layers();
        let view = scene
            .view(fragsim_raster::Viewport::new(24, 24).unwrap(), &orbit)
            .unwrap();
        let oracle = Oracle::build(&view);
        let two = oracle
            .depth_complexity()
            .iter()
            .filter(|&&n| n == 2)
            .count() as u64;
        assert!(two > 100, "{two}");
        let judge = ColourJudge::new(EffectName::Translucency, &scene, &view, orbit, &oracle);
        // Held depths equal to the true ones: nothing to see, nothing taken from the oracle.
        let held = capture_of(&oracle, Identity::PrimOnly, |_, e| e);
        let judged = judge.judge(&held).unwrap();
        assert_eq!((judged.errors, judged.pass), (0, None));
        // A scheme that holds its far layer at 0.0 has no thickness there: every two-layer
        // pixel changes colour. Filling the depth in from the oracle would hide it.
        let flat = capture_of(&oracle, Identity::PrimOnly, |i, e| {
            if i == 1 {
                e & u64::from(u32::MAX)
            } else {
                e
            }
        });
        let judged = judge.judge(&flat).unwrap();
        assert_eq!(judged.errors, two);
        assert_eq!(judged.pass, None);
    }

    #[test]
    #[expect(
        clippy::shadow_unrelated,
        reason = "each `judged` and `pass` is its own case's"
    )]
    fn a_key_only_capture_is_completed_from_the_oracle_and_its_row_says_so() {
        let (scene, orbit) = two_layers();
        let view = scene
            .view(fragsim_raster::Viewport::new(24, 24).unwrap(), &orbit)
            .unwrap();
        let oracle = Oracle::build(&view);
        let keys = capture_of(&oracle, Identity::KeyOnly, |_, e| e >> 32 << 32);
        let judge = ColourJudge::new(EffectName::Fresnel, &scene, &view, orbit, &oracle);
        let judged = judge.judge(&keys).unwrap();
        assert_eq!(judged.errors, 0);
        let pass = judged.pass.expect("completed and recomputed");
        assert_eq!(pass.completed_from_oracle, Some(deferred::COMPLETED_PRIMS));
        // Fresnel recomputes the normal of every captured entry, once each.
        assert_eq!(pass.recomputed_entries, oracle.fragments() as u64);
        let full = capture_of(&oracle, Identity::KeyAndPrim, |_, e| e);
        let pass = judge.judge(&full).unwrap().pass.expect("recomputed");
        assert_eq!(pass.completed_from_oracle, None);
        assert_eq!(pass.recomputed_entries, oracle.fragments() as u64);
    }
}
