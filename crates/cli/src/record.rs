//! The one output model of `--json` (`docs/json-schema.md`): every command prints JSON Lines,
//! one flat record per line (a scheme on an executor, a sweep angle, a differing pixel, …).
//!
//! Guarantee: every record opens with the same context fields ([`Context`]: `record`,
//! `fragsim_version`, `command`, the scene and its mesh hash, the viewport, the camera, K and
//! capacity, executor, threads), each present on every line (`null` where the command has no
//! such thing), and a quantity has one name everywhere (`time_ms`, `mismatched_pixels`, …).
//! Rates are fractions in JSON; the tables print them as percentages and say so.

use serde::Serialize;

use crate::args::{Count, SceneArgs, SchemeArgs};
use crate::colour_judge::ColourColumns;
use fragsim_raster::{Conventions, SceneSpec};
use fragsim_shade::colour_error::{colour_error_by_depth, BucketError, DEPTH_BUCKETS};
use image::RgbImage;

/// A slot count as a record writes it: a number, or `"auto"` when the scene sized it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slots {
    /// A fixed count.
    Fixed(u32),
    /// `auto`: sized by a counting pass (the run's own `slots_per_pixel` says to what).
    Auto,
}

impl Serialize for Slots {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            Self::Fixed(n) => serializer.serialize_u32(*n),
            Self::Auto => serializer.serialize_str("auto"),
        }
    }
}

impl From<Count> for Slots {
    fn from(count: Count) -> Self {
        match count {
            Count::Fixed(n) => Self::Fixed(n),
            Count::Auto => Self::Auto,
        }
    }
}

/// The fields every record carries, in this order, before its own.
#[derive(Debug, Clone, Serialize)]
pub struct Context {
    /// The version of fragsim that wrote the record.
    pub fragsim_version: &'static str,
    /// The subcommand (`render`, `bench`, `sweep`, `compare`, `hazard`, `explain`,
    /// `export-scene`).
    pub command: &'static str,
    /// The scene: a named scene (`bunny`, `spheres:8`) or a mesh file's name (never its
    /// directory).
    pub scene: String,
    /// The content hash of the mesh file (`fnv1a64:…`, as dumps write it); `null` for a named
    /// scene, which its name fixes.
    pub mesh_hash: Option<String>,
    /// Viewport width in pixels.
    pub width: u32,
    /// Viewport height in pixels.
    pub height: u32,
    /// Orbit angle of the camera, degrees (`null` for an engine's own matrix).
    pub view_degrees: Option<f64>,
    /// Elevation of the camera, degrees (`null` for an engine's own matrix).
    pub elevation_degrees: Option<f64>,
    /// `--k` as given: a number or `"auto"` (`null` where no scheme is sized by it).
    pub k: Option<Slots>,
    /// `--capacity` as given: a number or `"auto"` (`null` where no scheme is sized by it).
    pub capacity: Option<Slots>,
    /// The executor of the record's run (`null` where nothing ran on one).
    pub executor: Option<String>,
    /// Threads of the record's run (`null` where nothing ran).
    pub threads: Option<usize>,
}

impl Context {
    /// The context of `command` on the scene and camera of `spec`, at `width × height`.
    #[must_use]
    pub fn new(command: &'static str, spec: &SceneSpec, width: u32, height: u32) -> Self {
        let scene = match (&spec.name, &spec.mesh) {
            (Some(name), _) => name.clone(),
            (None, Some(mesh)) => file_name(mesh),
            (None, None) => "engine".into(),
        };
        let orbit = spec.view_projection.is_none();
        Self {
            fragsim_version: env!("CARGO_PKG_VERSION"),
            command,
            scene,
            mesh_hash: spec.mesh_hash.clone(),
            width,
            height,
            view_degrees: orbit.then_some(spec.view_degrees),
            elevation_degrees: orbit.then_some(spec.elevation_degrees),
            k: None,
            capacity: None,
            executor: None,
            threads: None,
        }
    }

    /// The context of `command` on the scene options (the mesh file hashed).
    ///
    /// # Errors
    /// The mesh file cannot be read.
    pub fn of_scene(command: &'static str, scene: &SceneArgs) -> Result<Self, String> {
        let spec = scene
            .spec(Conventions::REFERENCE)
            .hashed()
            .map_err(|e| e.to_string())?;
        Ok(Self::new(command, &spec, scene.width, scene.height))
    }

    /// With `--k` and `--capacity` of `schemes`.
    #[must_use]
    pub fn sized(mut self, schemes: &SchemeArgs) -> Self {
        self.k = Some(schemes.k.into());
        self.capacity = Some(schemes.capacity.into());
        self
    }

    /// With the executor and threads of one run.
    #[must_use]
    pub fn on(&self, executor: &str, threads: usize) -> Self {
        Self {
            executor: Some(executor.into()),
            threads: Some(threads),
            ..self.clone()
        }
    }

    /// At orbit angle `degrees` (a sweep's).
    #[must_use]
    pub fn at_angle(&self, degrees: f64) -> Self {
        Self {
            view_degrees: Some(degrees),
            ..self.clone()
        }
    }
}

/// The last component of a path, as records and chart titles name a mesh file.
#[must_use]
pub fn file_name(path: &str) -> String {
    std::path::Path::new(path)
        .file_name()
        .map_or_else(|| path.to_string(), |f| f.to_string_lossy().into_owned())
}

/// One line: the record's kind, the context, then the record's own fields.
#[derive(Serialize)]
struct Line<'a, T: Serialize> {
    record: &'static str,
    #[serde(flatten)]
    context: &'a Context,
    #[serde(flatten)]
    fields: &'a T,
}

/// One record of kind `record` as one line of JSON (no newline).
///
/// # Errors
/// The record cannot be serialised (a map with non-string keys: a bug).
pub fn line<T: Serialize>(
    record: &'static str,
    context: &Context,
    fields: &T,
) -> Result<String, String> {
    serde_json::to_string(&Line {
        record,
        context,
        fields,
    })
    .map_err(|e| e.to_string())
}

/// Prints one record of kind `record` on stdout, as one line of JSON.
///
/// # Errors
/// The record cannot be serialised (a map with non-string keys: a bug).
pub fn emit<T: Serialize>(
    record: &'static str,
    context: &Context,
    fields: &T,
) -> Result<(), String> {
    outln!("{}", line(record, context, fields)?);
    Ok(())
}

/// The colour error of an effect's image per depth-complexity bucket, as `bench` and `sweep`
/// records carry it: for each bucket of [`DEPTH_BUCKETS`] (fragments per pixel, from the
/// oracle), six flat fields named `<quantity>_dc_<bucket>` (`dc_1`, `dc_2_4`, …, `dc_33+`):
/// `pixels` (covered pixels in the bucket), `error_pixels` (of them, those whose 8-bit colour
/// differs), `error_pixel_rate` (the fraction; `null` for an empty bucket), `mean_abs_error`,
/// `max_abs_error`, `psnr_db` (as the whole image's, over the bucket's pixels alone; `null` for
/// an empty bucket). Every field is `null` where there is no image (the words cannot resolve the
/// effect), so that every record has every field.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ColourByDepth {
    /// One entry per bucket of [`DEPTH_BUCKETS`], in order; empty where there is no image.
    pub buckets: Vec<BucketError>,
}

impl ColourByDepth {
    /// The buckets of `candidate` against `reference` (`None`: no image), pixel `p` having
    /// `depth_complexity[p]` fragments.
    ///
    /// # Errors
    /// The images differ in size, or `depth_complexity` is not one count a pixel (a bug).
    pub fn of(
        images: Option<(&RgbImage, &RgbImage)>,
        depth_complexity: &[u32],
    ) -> Result<Self, String> {
        let buckets = match images {
            Some((reference, candidate)) => {
                colour_error_by_depth(reference, candidate, depth_complexity)
                    .map_err(|e| e.to_string())?
            }
            None => Vec::new(),
        };
        Ok(Self { buckets })
    }

    /// The buckets with pixels in them.
    pub fn covered(&self) -> impl Iterator<Item = &BucketError> {
        self.buckets.iter().filter(|b| b.pixels > 0)
    }
}

impl Serialize for ColourByDepth {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(DEPTH_BUCKETS.len() * 6))?;
        for (i, &(lo, hi)) in DEPTH_BUCKETS.iter().enumerate() {
            let suffix = match (lo, hi) {
                (lo, hi) if lo == hi => format!("dc_{lo}"),
                (lo, u32::MAX) => format!("dc_{lo}+"),
                (lo, hi) => format!("dc_{lo}_{hi}"),
            };
            let bucket = self.buckets.get(i);
            let colour = ColourColumns::of(bucket.and_then(|b| b.error));
            let rate = bucket
                .filter(|b| b.pixels > 0)
                .map(|b| b.error_pixels as f64 / b.pixels as f64);
            map.serialize_entry(&format!("pixels_{suffix}"), &bucket.map(|b| b.pixels))?;
            map.serialize_entry(
                &format!("error_pixels_{suffix}"),
                &bucket.map(|b| b.error_pixels),
            )?;
            map.serialize_entry(&format!("error_pixel_rate_{suffix}"), &rate)?;
            map.serialize_entry(&format!("mean_abs_error_{suffix}"), &colour.mean_abs_error)?;
            map.serialize_entry(&format!("max_abs_error_{suffix}"), &colour.max_abs_error)?;
            map.serialize_entry(&format!("psnr_db_{suffix}"), &colour.psnr_db)?;
        }
        map.end()
    }
}

/// The mean absolute error of an image over its three channels, as tables and charts print it
/// (`None`: no image).
#[must_use]
pub fn mean_of_channels(colour: &ColourColumns) -> Option<f64> {
    colour.mean_abs_error.map(|m| m.iter().sum::<f64>() / 3.0)
}

/// `fraction` as a percentage with `decimals` decimals for a table cell, where a rate that is not
/// zero never prints as zero: one error pixel in a million is `<0.001`, not `0.000` beside a
/// colour error of 68.
#[must_use]
pub fn percent(fraction: f64, decimals: usize) -> String {
    let percent = fraction * 100.0;
    let smallest = 10_f64.powi(-i32::try_from(decimals).unwrap_or(i32::MAX));
    if percent > 0.0 && percent < smallest / 2.0 {
        format!("<{smallest:.decimals$}")
    } else {
        format!("{percent:.decimals$}")
    }
}

/// A table's cells of one bucket: its name, pixels, EPR % of them, and the colour error's mean,
/// maximum and PSNR cells (as the whole image's: `inf` for a bucket equal to the oracle's).
#[must_use]
pub fn bucket_cells(bucket: &BucketError) -> [String; 6] {
    let [mean, max, psnr] = ColourColumns::of(bucket.error).cells();
    [
        bucket.label(),
        bucket.pixels.to_string(),
        percent(bucket.error_pixels as f64 / bucket.pixels.max(1) as f64, 3),
        mean,
        max,
        psnr,
    ]
}

/// A column of a terminal table: its heading, and the cell it shows of a row.
pub(crate) type Column<Row> = (&'static str, fn(&Row) -> String);

/// A terminal table of `rows`, one column per `(heading, cell)`: each column as wide as its
/// widest cell, the first `left` columns (names) aligned left and the rest (numbers) right, two
/// spaces between columns, a line a row under the line of headings.
pub(crate) fn aligned_table<Row>(columns: &[Column<Row>], rows: &[Row], left: usize) -> String {
    let mut cells = vec![columns
        .iter()
        .map(|(heading, _)| (*heading).to_string())
        .collect::<Vec<_>>()];
    cells.extend(
        rows.iter()
            .map(|row| columns.iter().map(|(_, cell)| cell(row)).collect()),
    );
    let widths: Vec<usize> = (0..columns.len())
        .map(|c| {
            cells
                .iter()
                .map(|line| line[c].chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut text = String::new();
    for line in &cells {
        let padded: Vec<String> = line
            .iter()
            .zip(&widths)
            .enumerate()
            .map(|(c, (cell, &w))| {
                if c < left {
                    format!("{cell:<w$}")
                } else {
                    format!("{cell:>w$}")
                }
            })
            .collect();
        text.push_str(padded.join("  ").trim_end());
        text.push('\n');
    }
    text
}

#[cfg(test)]
mod tests {
    use super::{aligned_table, percent, Column};

    #[test]
    fn a_rate_that_is_not_zero_never_prints_as_zero() {
        assert_eq!(percent(0.0, 3), "0.000", "zero is zero");
        assert_eq!(percent(1e-6, 3), "<0.001", "one pixel in a million");
        assert_eq!(percent(1e-7, 4), "<0.0001", "the cell's own precision");
        assert_eq!(percent(0.012_34, 3), "1.234", "rounded as before");
        assert_eq!(percent(1.0, 3), "100.000", "every pixel");
    }

    #[test]
    fn an_aligned_table_pads_names_left_and_numbers_right() {
        type Row = (&'static str, u32);
        let columns: [Column<Row>; 2] = [
            ("scheme", |r| r.0.to_string()),
            ("lost", |r| r.1.to_string()),
        ];
        let text = aligned_table(&columns, &[("mdts", 0), ("kbuffer-stores", 1234)], 1);
        assert_eq!(
            text, "scheme          lost\nmdts               0\nkbuffer-stores  1234\n",
            "{text}"
        );
    }
}
