//! Multi-fragment effects resolved from per-pixel fragment lists (nearest first).
//!
//! - **Transparency**: front-to-back "under" blending (Bavoil & Myers 2008):
//!   `C += T · α · c_i`, `T *= 1 − α`, then `C += T · background`.
//! - **Translucency**: Beer–Lambert absorption through the thickness between successive entering
//!   and leaving layers, `(d1 − d0) + (d3 − d2) + …` in eye-space distance (bucket depth peeling
//!   §4): `T = exp(−σ · thickness)`, `C = T · background + (1 − T) · colour`; the caller's
//!   [`Geometry::distance`] fixes the unit (the bench uses the model's bounding radius).
//! - **Fresnel**: Schlick's transmittance `Ft = 1 − (1 − cos θ)^5` of every fragment, from its
//!   interpolated normal and the view ray ([`Geometry::cosine`]), multiplied along the list and
//!   applied to the Beer–Lambert ambient term, as the bucket sort chapter's Listing 1.3:
//!   `C = (Π Ft) · exp(−σ · thickness) · colour`; an empty pixel is the background.
//!
//! Colours are linear; each pixel is encoded to sRGB once, at the end ([`encode_srgb`]). Pixels
//! are shaded in parallel, a row per rayon task.

use image::{Rgb, RgbImage};
use rayon::prelude::*;

/// The effect to resolve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Effect {
    /// Front-to-back transparency.
    Transparency,
    /// Beer–Lambert translucency.
    Translucency,
    /// Schlick's Fresnel transmittance along the list, over Beer–Lambert absorption.
    Fresnel,
}

impl Effect {
    /// Whether a list of these entries holds what the effect needs: translucency needs depths,
    /// Fresnel depths and primitives (for the normal).
    #[must_use]
    pub fn resolvable_from(self, entries: Entries) -> bool {
        match self {
            Self::Transparency => true,
            Self::Translucency => entries != Entries::PrimOnly,
            Self::Fresnel => entries == Entries::KeyAndPrim,
        }
    }
}

/// What shading needs to know of the geometry beyond the entries.
#[derive(Clone, Copy)]
pub struct Geometry<'a> {
    /// Eye-space distance of a window depth (translucency's thickness), in the caller's unit.
    pub distance: &'a (dyn Fn(f32) -> f64 + Sync),
    /// `|cos θ|` between the normal of the entry's fragment at pixel `p` and the view ray
    /// (`(p, entry)`); called for Fresnel only.
    pub cosine: &'a (dyn Fn(usize, u64) -> f64 + Sync),
}

impl std::fmt::Debug for Geometry<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Geometry")
    }
}

/// Schlick's approximation of the Fresnel transmittance, `1 − (1 − cos θ)^5`.
#[must_use]
pub fn schlick_transmittance(cos_theta: f64) -> f64 {
    1.0 - (1.0 - cos_theta.clamp(0.0, 1.0)).powi(5)
}

/// Material and scene constants of the effects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Opacity of every fragment (transparency).
    pub opacity: f32,
    /// Extinction coefficient per unit of eye-space distance (translucency).
    pub sigma: f64,
    /// Linear background colour.
    pub background: [f32; 3],
    /// Linear colour of fragments whose primitive is unknown (key-only captures), and the
    /// absorbing medium's colour.
    pub base: [f32; 3],
    /// Number of primitives of the mesh (spreads [`primitive_colour`] over the wheel).
    pub primitives: u32,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            opacity: 0.35,
            sigma: 1.5,
            background: [0.02, 0.02, 0.03],
            base: [0.9, 0.5, 0.1],
            primitives: 1,
        }
    }
}

/// What a list's entries identify, as far as shading is concerned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Entries {
    /// `depth_key << 32 | prim`.
    KeyAndPrim,
    /// `depth_key << 32`: colour falls back to the material's base colour.
    KeyOnly,
    /// `prim` only, in depth order: depth is unknown (translucency cannot be resolved).
    PrimOnly,
}

/// A per-triangle colour in linear RGB: the hue runs once round the colour wheel over the mesh's
/// primitive ids, so that neighbouring triangles (which scanned meshes number close together)
/// get close colours and a misordered or lost fragment still changes the pixel.
#[must_use]
#[expect(
    clippy::cast_possible_truncation,
    reason = "a channel in [0.1, 0.9], f32 as colours are"
)]
pub fn primitive_colour(prim: u32, primitives: u32) -> [f32; 3] {
    let hue = f64::from(prim) / f64::from(primitives.max(1));
    let channel = |offset: f64| {
        let h = (hue + offset).fract() * 6.0;
        let v = (h - 3.0).abs() - 1.0;
        (v.clamp(0.0, 1.0) * 0.8 + 0.1) as f32
    };
    [channel(0.0), channel(2.0 / 3.0), channel(1.0 / 3.0)]
}

/// Linear to 8-bit sRGB (IEC 61966-2-1), the one place where encoding happens.
#[must_use]
#[expect(
    clippy::cast_possible_truncation,
    reason = "s is in [0, 1], so the scaled value is a byte (and `as` saturates)"
)]
pub fn encode_srgb(linear: f32) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// Resolves pixel `pixel`'s list (nearest first) to a linear colour; `None` when the effect
/// needs what the entries lack ([`Effect::resolvable_from`]).
#[must_use]
#[expect(
    clippy::cast_possible_truncation,
    reason = "an entry packs the depth key (high 32 bits) and the primitive id (low 32); colours are f32; the f64 arithmetic narrows back to them"
)]
pub fn shade_pixel(
    effect: Effect,
    material: &Material,
    entries: Entries,
    pixel: usize,
    list: &[u64],
    geometry: Geometry<'_>,
) -> Option<[f32; 3]> {
    if !effect.resolvable_from(entries) {
        return None;
    }
    let colour_of = |entry: u64| match entries {
        Entries::KeyAndPrim | Entries::PrimOnly => {
            primitive_colour(entry as u32, material.primitives)
        }
        Entries::KeyOnly => material.base,
    };
    let absorption = || {
        let depths: Vec<f64> = list
            .iter()
            .map(|&e| (geometry.distance)(f32::from_bits((e >> 32) as u32)))
            .collect();
        let thickness: f64 = depths.chunks_exact(2).map(|pair| pair[1] - pair[0]).sum();
        (-material.sigma * thickness).exp() as f32
    };
    Some(match effect {
        Effect::Transparency => {
            let (mut colour, mut transmittance) = ([0.0_f32; 3], 1.0_f32);
            for &entry in list {
                let c = colour_of(entry);
                for ch in 0..3 {
                    colour[ch] += transmittance * material.opacity * c[ch];
                }
                transmittance *= 1.0 - material.opacity;
            }
            [0, 1, 2].map(|ch| colour[ch] + transmittance * material.background[ch])
        }
        Effect::Translucency => {
            let t = absorption();
            [0, 1, 2].map(|ch| t * material.background[ch] + (1.0 - t) * material.base[ch])
        }
        Effect::Fresnel => {
            if list.is_empty() {
                return Some(material.background);
            }
            let fresnel: f64 = list
                .iter()
                .map(|&e| schlick_transmittance((geometry.cosine)(pixel, e)))
                .product();
            let t = absorption() * fresnel as f32;
            material.base.map(|c| t * c)
        }
    })
}

/// Resolves every pixel, rows in parallel; `list(p)` gives pixel `p`'s entries. `None` when the
/// effect cannot be resolved from these entries. The one-sample case of [`render_resolved`].
#[must_use]
pub fn render<'a>(
    effect: Effect,
    material: &Material,
    entries: Entries,
    size: (u32, u32),
    list: impl Fn(usize) -> &'a [u64] + Sync,
    geometry: Geometry<'_>,
) -> Option<RgbImage> {
    render_resolved(effect, material, entries, size, 1, list, geometry)
}

/// The multisample resolve of an effect: every sample shaded from its own list, then each
/// pixel's `samples` linear colours averaged, then encoded once ([`shade_image`]).
///
/// `list(i)` gives the entries of sample index `i = p * samples + s`, sample `s` of pixel `p`
/// (row-major): the sample-expanded framebuffer a sampled view rasterizes into
/// (`fragsim_raster::samples`, `docs/semantics.md` §11), whose per-sample oracle
/// (`fragsim_oracle::samples::SampleOracle::oracle`) is indexed the same way; `geometry`'s
/// `cosine` is called with the sample index too.
///
/// The filter is the standard MSAA box resolve: the unweighted mean of the pixel's samples (the
/// filter of GPUs' fixed-function colour resolve; Vulkan's `vkCmdResolveImage` leaves it to the
/// implementation). It is taken in linear light, before the sRGB encoding, like the blending
/// itself: averaging encoded bytes would darken every edge between a bright and a dark sample.
/// The sum runs in f64, where equal f32 colours add exactly, so a pixel whose samples all shade
/// alike resolves to exactly that colour, and one sample is the single-sample image bit for bit.
///
/// `None` when the effect cannot be resolved from these entries.
///
/// # Panics
/// If `samples` is 0.
#[must_use]
#[expect(
    clippy::cast_possible_truncation,
    reason = "colours are f32; the f64 arithmetic narrows back to them"
)]
pub fn render_resolved<'a>(
    effect: Effect,
    material: &Material,
    entries: Entries,
    size: (u32, u32),
    samples: u32,
    list: impl Fn(usize) -> &'a [u64] + Sync,
    geometry: Geometry<'_>,
) -> Option<RgbImage> {
    assert!(samples > 0, "a pixel has at least one sample");
    if !effect.resolvable_from(entries) {
        return None;
    }
    let n = samples as usize;
    Some(shade_image(size, |p| {
        let mut sum = [0.0_f64; 3];
        for sample in p * n..(p + 1) * n {
            let colour = shade_pixel(effect, material, entries, sample, list(sample), geometry)
                .expect("resolvable entries shade every sample");
            for ch in 0..3 {
                sum[ch] += f64::from(colour[ch]);
            }
        }
        sum.map(|c| (c / n as f64) as f32)
    }))
}

/// The image whose pixel `p` (row-major) is `colour(p)`, a linear colour encoded to sRGB; rows
/// are shaded in parallel, a row per rayon task. Every image of this crate is made here: the
/// exact effects' ([`render`]) and the approximate schemes'
/// ([`Approximation::render`](crate::approximate::Approximation::render)).
pub fn shade_image(
    (width, height): (u32, u32),
    colour: impl Fn(usize) -> [f32; 3] + Sync,
) -> RgbImage {
    let row = width as usize * 3;
    let mut bytes = vec![0_u8; row * height as usize];
    bytes
        .par_chunks_mut(row.max(1))
        .enumerate()
        .for_each(|(y, out)| {
            for (x, rgb) in out.chunks_exact_mut(3).enumerate() {
                let p = y * width as usize + x;
                rgb.copy_from_slice(&colour(p).map(encode_srgb));
            }
        });
    RgbImage::from_raw(width, height, bytes).expect("the buffer has width × height pixels")
}

/// The paper's error-pixel count: pixels whose 8-bit colour differs.
///
/// # Panics
/// If the images differ in size.
#[must_use]
pub fn error_pixels(reference: &RgbImage, candidate: &RgbImage) -> usize {
    assert_eq!(
        reference.dimensions(),
        candidate.dimensions(),
        "images of different sizes"
    );
    reference
        .pixels()
        .zip(candidate.pixels())
        .filter(|(a, b)| a != b)
        .count()
}

/// The candidate with every error pixel painted red and the rest dimmed to grey.
#[must_use]
pub fn difference_image(reference: &RgbImage, candidate: &RgbImage) -> RgbImage {
    RgbImage::from_fn(reference.width(), reference.height(), |x, y| {
        let (a, b) = (reference.get_pixel(x, y), candidate.get_pixel(x, y));
        if a == b {
            #[expect(
                clippy::cast_possible_truncation,
                reason = "three bytes summed and divided by 6 are below 128"
            )]
            let grey = ((u16::from(b[0]) + u16::from(b[1]) + u16::from(b[2])) / 6) as u8;
            Rgb([grey, grey, grey])
        } else {
            Rgb([255, 0, 0])
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(_: f32) -> f64 {
        0.0
    }

    fn facing(_: usize, _: u64) -> f64 {
        1.0
    }

    const FLAT: Geometry<'static> = Geometry {
        distance: &flat,
        cosine: &facing,
    };

    #[test]
    fn srgb_encoding_ends_and_midpoint() {
        assert_eq!(encode_srgb(0.0), 0);
        assert_eq!(encode_srgb(1.0), 255);
        // Linear 0.5 is sRGB 0.7354 (the standard's curve), 187.5 → 188; a gamma-free encoder
        // would give 128.
        assert_eq!(encode_srgb(0.5), 188);
    }

    #[test]
    fn an_empty_pixel_is_the_background_and_order_matters() {
        let m = Material {
            primitives: 4,
            ..Material::default()
        };
        let shade = |list: &[u64]| {
            shade_pixel(Effect::Transparency, &m, Entries::KeyAndPrim, 0, list, FLAT)
        };
        assert_eq!(shade(&[]), Some(m.background));
        assert_ne!(
            shade(&[1 << 32, (2 << 32) | 1]),
            shade(&[(2 << 32) | 1, 1 << 32])
        );
    }

    #[test]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "colours are f32; the f64 arithmetic narrows back to them"
    )]
    fn a_half_covered_pixel_resolves_to_the_mean_of_its_two_samples_in_linear_light() {
        let m = Material {
            opacity: 0.9,
            ..Material::default()
        };
        // Sample 0 holds one nearly opaque fragment (primitive 0: red), sample 1 nothing.
        let lists: [&[u64]; 2] = [&[0], &[]];
        let image = render_resolved(
            Effect::Transparency,
            &m,
            Entries::KeyAndPrim,
            (1, 1),
            2,
            |s| lists[s],
            FLAT,
        )
        .unwrap();
        let covered =
            shade_pixel(Effect::Transparency, &m, Entries::KeyAndPrim, 0, &[0], FLAT).unwrap();
        let linear_mean = [0, 1, 2].map(|ch| {
            let sum = f64::from(covered[ch]) + f64::from(m.background[ch]);
            encode_srgb((sum / 2.0) as f32)
        });
        assert_eq!(image.get_pixel(0, 0).0, linear_mean);
        // The mean of the encoded bytes is far darker in red: the resolve is not that.
        let encoded_mean =
            (u16::from(encode_srgb(covered[0])) + u16::from(encode_srgb(m.background[0]))) / 2;
        assert!(
            u16::from(linear_mean[0]) > encoded_mean + 20,
            "{linear_mean:?} against {encoded_mean}"
        );
    }

    #[test]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "an entry packs the depth key (high 32 bits) and the primitive id (low 32); a small test viewport's coordinates"
    )]
    fn one_sample_resolves_to_the_single_sample_image_and_four_change_only_mixed_pixels() {
        use fragsim_oracle::samples::SampleOracle;
        use fragsim_oracle::Oracle;
        use fragsim_raster::{OrbitCamera, SamplePattern, Scene, Viewport};

        let scene = Scene::procedural("bunny").unwrap();
        let side = 64;
        let view = scene
            .view(Viewport::new(side, side).unwrap(), &OrbitCamera::default())
            .unwrap();
        let m = Material {
            primitives: view.triangle_count(),
            ..Material::default()
        };
        let today = Oracle::build(&view);
        let shade = |p: usize, list: &[u64]| {
            shade_pixel(Effect::Transparency, &m, Entries::KeyAndPrim, p, list, FLAT).unwrap()
        };
        let single = shade_image((side, side), |p| shade(p, today.pixel(p)));
        let resolve = |count: u32| {
            let pattern = SamplePattern::standard(count).unwrap();
            let sampled =
                SampleOracle::build(&view.clone().with_samples(pattern).unwrap()).unwrap();
            let lists = sampled.oracle();
            let image = render_resolved(
                Effect::Transparency,
                &m,
                Entries::KeyAndPrim,
                (side, side),
                count,
                |s| lists.pixel(s),
                FLAT,
            )
            .unwrap();
            (image, sampled)
        };
        assert_eq!(resolve(1).0, single);
        let (four, sampled) = resolve(4);
        let sampled = sampled.oracle();
        let prims = |list: &[u64]| list.iter().map(|&e| e as u32).collect::<Vec<_>>();
        let (mut uniform, mut changed) = (0, 0);
        for p in 0..(side * side) as usize {
            let centre = prims(today.pixel(p));
            let (x, y) = ((p % side as usize) as u32, (p / side as usize) as u32);
            if (0..4).all(|s| prims(sampled.pixel(p * 4 + s)) == centre) {
                // Every sample shades as the centre does: the resolve keeps the colour exactly.
                uniform += 1;
                assert_eq!(four.get_pixel(x, y), single.get_pixel(x, y), "pixel {p}");
            } else if four.get_pixel(x, y) != single.get_pixel(x, y) {
                changed += 1;
            }
        }
        assert!(
            uniform > 1000 && changed > 100,
            "{uniform} uniform, {changed} changed"
        );
    }

    #[test]
    fn translucency_absorbs_by_thickness() {
        let m = Material {
            sigma: 1.0,
            ..Material::default()
        };
        let linear = |z: f32| f64::from(z) * 10.0;
        let geometry = Geometry {
            distance: &linear,
            cosine: &facing,
        };
        let key = |d: f32| u64::from(d.to_bits()) << 32;
        let shade = |list: &[u64], entries| {
            shade_pixel(Effect::Translucency, &m, entries, 0, list, geometry)
        };
        let thin = shade(&[key(0.1), key(0.2)], Entries::KeyOnly).unwrap();
        let thick = shade(&[key(0.1), key(0.5)], Entries::KeyOnly).unwrap();
        // More material hides more of the background: closer to the medium's colour everywhere.
        for ch in 0..3 {
            assert!((thick[ch] - m.base[ch]).abs() < (thin[ch] - m.base[ch]).abs());
        }
        assert_eq!(shade(&[1], Entries::PrimOnly), None);
    }

    #[test]
    fn fresnel_multiplies_schlick_along_the_list() {
        let m = Material::default();
        let half = |_: usize, _: u64| 0.5;
        let geometry = Geometry {
            distance: &flat,
            cosine: &half,
        };
        let two = shade_pixel(
            Effect::Fresnel,
            &m,
            Entries::KeyAndPrim,
            0,
            &[0, 1],
            geometry,
        )
        .unwrap();
        let ft = 1.0 - 0.5_f64.powi(5);
        for (got, base) in two.iter().zip(m.base) {
            assert!((f64::from(*got) - ft * ft * f64::from(base)).abs() < 1e-6);
        }
        assert_eq!(
            shade_pixel(Effect::Fresnel, &m, Entries::KeyOnly, 0, &[0], geometry),
            None
        );
    }
}
