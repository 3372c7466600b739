//! Where `bench` saves its rows' images (its own and its multisampled rows'): each effect image
//! as it is, and its difference from the oracle's, captioned with the scene.

use std::path::PathBuf;

use image::RgbImage;

/// Where bench's images go, and the scene and view their captions name.
#[derive(Debug, Clone)]
pub struct Images {
    /// The directory (`--out`).
    pub dir: PathBuf,
    /// The scene, view and size, as every caption opens.
    pub scene: String,
}

impl Images {
    /// Saves the effect image `image` as `name`, as it is: pixel data that readers compare
    /// (its file name says what it is; its figure, the difference, carries the caption).
    ///
    /// # Errors
    /// A file that cannot be written.
    pub fn save(&self, image: &RgbImage, name: &str) -> Result<(), String> {
        fragsim_shade::save_png(image, &self.dir.join(name)).map_err(|e| e.to_string())
    }

    /// Saves `image` as `stem.png` and its difference from `reference` (error pixels red, with
    /// a legend and insets) as `stem-diff.png`, captioned with the scene and `what` it shows.
    ///
    /// # Errors
    /// Images of different sizes, a font error, or a file that cannot be written.
    pub fn save_with_difference(
        &self,
        image: &RgbImage,
        reference: &RgbImage,
        stem: &str,
        what: &str,
    ) -> Result<(), String> {
        self.save(image, &format!("{stem}.png"))?;
        let difference = fragsim_shade::legend::effect_difference_figure(reference, image)
            .map_err(|e| e.to_string())?;
        let caption = format!("{}: {what} against the oracle's image", self.scene);
        let figure =
            fragsim_shade::legend::captioned(&difference, &caption).map_err(|e| e.to_string())?;
        self.save(&figure, &format!("{stem}-diff.png"))
    }
}
