//! Multi-fragment effects resolved from per-pixel fragment lists (nearest first).
//!
//! - **Transparency**: front-to-back "under" blending (Bavoil & Myers 2008):
//!   `C += T · α · c_i`, `T *= 1 − α`, then `C += T · background`.
//! - **Translucency**: Beer–Lambert absorption through the thickness between successive entering
//!   and leaving layers, `(d1 − d0) + (d3 − d2) + …` in eye-space distance (bucket depth peeling
//!   §4): `T = exp(−σ · thickness)`, `C = T · background + (1 − T) · colour`; the caller's
//!   `distance` fixes the unit (the bench uses the model's bounding radius).
//!
//! Colours are linear; each pixel is encoded to sRGB once, at the end ([`encode_srgb`]).

use image::{Rgb, RgbImage};

/// The effect to resolve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Effect {
    /// Front-to-back transparency.
    Transparency,
    /// Beer–Lambert translucency.
    Translucency,
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
pub fn encode_srgb(linear: f32) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// Resolves one pixel's list (nearest first) to a linear colour. `distance` maps a window depth
/// to eye-space distance (translucency). `None` when the effect needs what the entries lack.
#[must_use]
pub fn shade_pixel(
    effect: Effect,
    material: &Material,
    entries: Entries,
    list: &[u64],
    distance: &dyn Fn(f32) -> f64,
) -> Option<[f32; 3]> {
    let colour_of = |entry: u64| match entries {
        Entries::KeyAndPrim | Entries::PrimOnly => {
            primitive_colour(entry as u32, material.primitives)
        }
        Entries::KeyOnly => material.base,
    };
    match effect {
        Effect::Transparency => {
            let (mut colour, mut transmittance) = ([0.0f32; 3], 1.0f32);
            for &entry in list {
                let c = colour_of(entry);
                for ch in 0..3 {
                    colour[ch] += transmittance * material.opacity * c[ch];
                }
                transmittance *= 1.0 - material.opacity;
            }
            Some([0, 1, 2].map(|ch| colour[ch] + transmittance * material.background[ch]))
        }
        Effect::Translucency => {
            if entries == Entries::PrimOnly {
                return None;
            }
            let depths: Vec<f64> = list
                .iter()
                .map(|&e| distance(f32::from_bits((e >> 32) as u32)))
                .collect();
            let thickness: f64 = depths.chunks_exact(2).map(|pair| pair[1] - pair[0]).sum();
            let t = (-material.sigma * thickness).exp() as f32;
            Some([0, 1, 2].map(|ch| t * material.background[ch] + (1.0 - t) * material.base[ch]))
        }
    }
}

/// Resolves every pixel; `list(p)` gives pixel `p`'s entries. `None` when the effect cannot be
/// resolved from these entries.
#[must_use]
pub fn render<'a>(
    effect: Effect,
    material: &Material,
    entries: Entries,
    (width, height): (u32, u32),
    list: impl Fn(usize) -> &'a [u64],
    distance: &dyn Fn(f32) -> f64,
) -> Option<RgbImage> {
    let mut image = RgbImage::new(width, height);
    for (p, pixel) in image.pixels_mut().enumerate() {
        let colour = shade_pixel(effect, material, entries, list(p), distance)?;
        *pixel = Rgb(colour.map(encode_srgb));
    }
    Some(image)
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
        assert_eq!(
            shade_pixel(Effect::Transparency, &m, Entries::KeyAndPrim, &[], &flat),
            Some(m.background)
        );
        let near_first = shade_pixel(
            Effect::Transparency,
            &m,
            Entries::KeyAndPrim,
            &[1 << 32, (2 << 32) | 1],
            &flat,
        );
        let swapped = shade_pixel(
            Effect::Transparency,
            &m,
            Entries::KeyAndPrim,
            &[(2 << 32) | 1, 1 << 32],
            &flat,
        );
        assert_ne!(near_first, swapped);
    }

    #[test]
    fn translucency_absorbs_by_thickness() {
        let m = Material {
            sigma: 1.0,
            ..Material::default()
        };
        let linear = |z: f32| f64::from(z) * 10.0;
        let key = |d: f32| u64::from(d.to_bits()) << 32;
        let thin = shade_pixel(
            Effect::Translucency,
            &m,
            Entries::KeyOnly,
            &[key(0.1), key(0.2)],
            &linear,
        )
        .unwrap();
        let thick = shade_pixel(
            Effect::Translucency,
            &m,
            Entries::KeyOnly,
            &[key(0.1), key(0.5)],
            &linear,
        )
        .unwrap();
        // More material hides more of the background: closer to the medium's colour everywhere.
        for ch in 0..3 {
            assert!((thick[ch] - m.base[ch]).abs() < (thin[ch] - m.base[ch]).abs());
        }
        assert_eq!(
            shade_pixel(Effect::Translucency, &m, Entries::PrimOnly, &[1], &linear),
            None
        );
    }
}
