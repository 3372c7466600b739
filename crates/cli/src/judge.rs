//! The error-pixel judge shared by `bench` and `sweep`: shades an effect from a capture and
//! counts the pixels whose 8-bit colour differs from the oracle's image (the papers' EPR).

use clap::ValueEnum;
use fragsim_capture::{Capture, Identity};
use fragsim_oracle::Oracle;
use fragsim_raster::{OrbitCamera, Scene, View};
use fragsim_shade::effects::{self, Effect, Entries, Material};
use image::RgbImage;

/// Effects whose images are compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum EffectName {
    /// Front-to-back transparency.
    Transparency,
    /// Beer–Lambert translucency.
    Translucency,
}

impl EffectName {
    /// The effect.
    #[must_use]
    pub fn effect(self) -> Effect {
        match self {
            EffectName::Transparency => Effect::Transparency,
            EffectName::Translucency => Effect::Translucency,
        }
    }

    /// Its name in file names and reports.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            EffectName::Transparency => "transparency",
            EffectName::Translucency => "translucency",
        }
    }
}

/// Shades captures and compares them with the oracle's image.
pub(crate) struct Judge<'a> {
    effect: Effect,
    material: Material,
    size: (u32, u32),
    distance: Box<dyn Fn(f32) -> f64 + 'a>,
    /// The oracle's image shaded from what each kind of capture can know: a key-only capture is
    /// compared with the oracle's fragments coloured by key only, so that the error-pixel rate
    /// measures lost and misordered fragments, not the attribute the scheme never stored.
    references: Vec<(Entries, Option<RgbImage>)>,
    /// Pixels the oracle covers: the rate's denominator.
    pub covered: usize,
}

impl<'a> Judge<'a> {
    /// The judge of `effect` for `view` of `scene` through `orbit`.
    pub fn new(
        effect: EffectName,
        scene: &Scene,
        view: &View<'_>,
        orbit: OrbitCamera,
        oracle: &Oracle,
    ) -> Self {
        let viewport = view.viewport();
        let aspect = f64::from(viewport.width) / f64::from(viewport.height);
        let bounds = scene.mesh.bounds();
        let (lo, hi) = bounds;
        let radius = (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt() * 0.5;
        // Thickness in units of the model's bounding radius, so σ means the same on every mesh.
        let distance: Box<dyn Fn(f32) -> f64 + 'a> =
            Box::new(move |z: f32| orbit.eye_distance(bounds, aspect, z) / radius.max(1e-12));
        let material = Material {
            primitives: view.triangle_count(),
            ..Material::default()
        };
        let size = (viewport.width, viewport.height);
        let effect = effect.effect();
        let references = [Entries::KeyAndPrim, Entries::KeyOnly, Entries::PrimOnly]
            .into_iter()
            .map(|entries| {
                let list = |p: usize| oracle.pixel(p);
                (
                    entries,
                    effects::render(effect, &material, entries, size, list, &*distance),
                )
            })
            .collect();
        let covered = oracle.depth_complexity().iter().filter(|&&c| c > 0).count();
        Self {
            effect,
            material,
            size,
            distance,
            references,
            covered,
        }
    }

    /// The oracle's full-identity image.
    pub fn reference(&self) -> Option<&RgbImage> {
        self.references
            .first()
            .and_then(|(_, image)| image.as_ref())
    }

    /// The capture's image, the reference it is compared with, and the error pixels; `None`
    /// when the capture's words cannot resolve the effect.
    pub fn judge(&self, capture: &Capture) -> Option<(RgbImage, &RgbImage, u64)> {
        let entries = match capture.identity {
            Identity::KeyAndPrim => Entries::KeyAndPrim,
            Identity::KeyOnly => Entries::KeyOnly,
            Identity::PrimOnly => Entries::PrimOnly,
        };
        let image = effects::render(
            self.effect,
            &self.material,
            entries,
            self.size,
            |p| capture.pixel(p),
            &*self.distance,
        )?;
        let reference = self
            .references
            .iter()
            .find(|(e, _)| *e == entries)?
            .1
            .as_ref()?;
        let errors = effects::error_pixels(reference, &image) as u64;
        Some((image, reference, errors))
    }
}
