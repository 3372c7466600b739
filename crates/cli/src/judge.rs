//! The error-pixel judge shared by `bench` and `sweep`: shades an effect from a capture and
//! counts the pixels whose 8-bit colour differs from the oracle's image (the papers' EPR).
//!
//! Every scheme is shaded for every effect. A capture whose words hold only depth keys (32-bit
//! schemes) or only primitive ids (FreePipe's packed MDTS) first goes through a **deferred
//! attribute pass**, as a GPU application renders attributes in a second geometry pass: the
//! scene's fragments of each pixel, in canonical order (the oracle's lists: what rasterizing
//! again gives), supply the missing half. A key takes the primitive of the next fragment with
//! that key not yet taken (equal keys in canonical order); a primitive id takes the depth key of
//! its fragment at the pixel. An entry that matches no fragment (a scheme that invented one)
//! keeps an unknown half ([`UNKNOWN_PRIM`] or depth 1). Then normals, colours and depths come
//! from full identities, and every capture is compared with the one full reference image: the
//! error-pixel rate measures lost, merged and misordered fragments, whatever the words stored.

use std::borrow::Cow;

use clap::ValueEnum;
use fragsim_capture::{Capture, Identity};
use fragsim_oracle::Oracle;
use fragsim_raster::attributes::Attributes;
use fragsim_raster::{OrbitCamera, Scene, View};
use fragsim_shade::effects::{self, Effect, Entries, Geometry, Material};
use image::RgbImage;
use rayon::prelude::*;

/// The primitive id the deferred pass gives a key that matches no fragment of its pixel.
pub const UNKNOWN_PRIM: u32 = u32::MAX;

/// Effects whose images are compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
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
            EffectName::Transparency => Effect::Transparency,
            EffectName::Translucency => Effect::Translucency,
            EffectName::Fresnel => Effect::Fresnel,
        }
    }

    /// Its name in file names and reports.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            EffectName::Transparency => "transparency",
            EffectName::Translucency => "translucency",
            EffectName::Fresnel => "fresnel",
        }
    }
}

type Distance<'a> = Box<dyn Fn(f32) -> f64 + Sync + 'a>;

/// Shades captures and compares them with the oracle's image.
pub(crate) struct Judge<'a> {
    effect: Effect,
    material: Material,
    size: (u32, u32),
    distance: Distance<'a>,
    /// The deferred attribute pass of the view: only when the effect needs normals.
    attributes: Option<Attributes<'a>>,
    oracle: &'a Oracle,
    reference: RgbImage,
    /// Pixels the oracle covers: the rate's denominator.
    pub covered: usize,
}

impl<'a> Judge<'a> {
    /// The judge of `effect` for `view` of `scene` through `orbit`.
    pub fn new(
        effect: EffectName,
        scene: &Scene,
        view: &View<'a>,
        orbit: OrbitCamera,
        oracle: &'a Oracle,
    ) -> Self {
        let viewport = view.viewport();
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
        let covered = oracle.depth_complexity().iter().filter(|&&c| c > 0).count();
        let mut judge = Self {
            effect,
            material,
            size: (viewport.width, viewport.height),
            distance,
            attributes,
            oracle,
            reference: RgbImage::new(0, 0),
            covered,
        };
        judge.reference = judge.shade(|p| oracle.pixel(p));
        judge
    }

    /// The oracle's image.
    pub fn reference(&self) -> Option<&RgbImage> {
        Some(&self.reference)
    }

    fn shade<'l>(&self, list: impl Fn(usize) -> &'l [u64] + Sync) -> RgbImage {
        let cosine = |p: usize, entry: u64| {
            self.attributes
                .as_ref()
                .and_then(|a| a.cosine(entry as u32, p as u32))
                .unwrap_or(1.0)
        };
        let geometry = Geometry {
            distance: &*self.distance,
            cosine: &cosine,
        };
        effects::render(
            self.effect,
            &self.material,
            Entries::KeyAndPrim,
            self.size,
            list,
            geometry,
        )
        .expect("full identities resolve every effect")
    }

    /// The capture's image, the reference it is compared with, and the error pixels.
    pub fn judge(&self, capture: &Capture) -> Option<(RgbImage, &RgbImage, u64)> {
        let full = deferred_attributes(capture, self.oracle);
        let image = self.shade(|p| full.pixel(p));
        let errors = effects::error_pixels(&self.reference, &image) as u64;
        Some((image, &self.reference, errors))
    }
}

/// The deferred attribute pass (see the module's documentation): the capture with full
/// `depth_key << 32 | prim` entries, in the capture's order.
#[must_use]
pub fn deferred_attributes<'c>(capture: &'c Capture, oracle: &Oracle) -> Cow<'c, Capture> {
    let resolve: fn(&[u64], &[u64]) -> Vec<u64> = match capture.identity {
        Identity::KeyAndPrim => return Cow::Borrowed(capture),
        Identity::KeyOnly => prims_of_keys,
        Identity::PrimOnly => keys_of_prims,
    };
    let entries = (0..capture.pixels())
        .into_par_iter()
        .with_min_len(256)
        .flat_map_iter(|p| resolve(capture.pixel(p), oracle.pixel(p)))
        .collect();
    Cow::Owned(Capture {
        offsets: capture.offsets.clone(),
        entries,
        identity: Identity::KeyAndPrim,
        keeps: capture.keeps.clone(),
    })
}

/// Key-only entries to full ones: the i-th occurrence of a key takes the primitive of the i-th
/// fragment with that key in canonical order.
fn prims_of_keys(list: &[u64], fragments: &[u64]) -> Vec<u64> {
    let mut order: Vec<usize> = (0..list.len()).collect();
    order.sort_by_key(|&i| list[i] >> 32);
    let mut out = vec![0u64; list.len()];
    let mut previous: Option<(u64, usize)> = None;
    for i in order {
        let key = list[i] >> 32;
        let occurrence = match previous {
            Some((k, n)) if k == key => n + 1,
            _ => 0,
        };
        previous = Some((key, occurrence));
        let first = fragments.partition_point(|&f| f >> 32 < key);
        let prim = fragments
            .get(first + occurrence)
            .filter(|&&f| f >> 32 == key)
            .map_or(UNKNOWN_PRIM, |&f| f as u32);
        out[i] = (key << 32) | u64::from(prim);
    }
    out
}

/// Primitive-only entries to full ones: each takes its fragment's depth key at the pixel.
fn keys_of_prims(list: &[u64], fragments: &[u64]) -> Vec<u64> {
    const FAR: u64 = 0x3F80_0000; // the key of depth 1.0
    list.iter()
        .map(|&e| {
            let prim = e as u32;
            let key = fragments
                .iter()
                .find(|&&f| f as u32 == prim)
                .map_or(FAR, |&f| f >> 32);
            (key << 32) | u64::from(prim)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_keys_take_their_primitives_in_canonical_order() {
        let fragments = [(5 << 32) | 2, (5 << 32) | 7, (9 << 32) | 1];
        // A capture that kept both fives (in any order) and the nine, and one invented key.
        assert_eq!(
            prims_of_keys(&[9 << 32, 5 << 32, 5 << 32, 6 << 32], &fragments),
            vec![
                (9 << 32) | 1,
                (5 << 32) | 2,
                (5 << 32) | 7,
                (6 << 32) | u64::from(UNKNOWN_PRIM)
            ]
        );
        // A merging scheme that kept one five gets the first.
        assert_eq!(prims_of_keys(&[5 << 32], &fragments), vec![(5 << 32) | 2]);
        assert_eq!(
            keys_of_prims(&[1, 7], &fragments),
            vec![(9 << 32) | 1, (5 << 32) | 7]
        );
    }
}
