//! The arrays' sizes checked against the header fields that fix them, before any array is read
//! where the header alone fixes them, and before any word is decoded, so that a mismatch names
//! the field at fault (`k`, `width`, `capacity`, `pool`, the array's `shape`) instead of a total
//! of words. A two-dimensional shape must be the one the fields make; its transpose is named as
//! such, since it is what a slot array in the other order looks like.

use crate::masked::MASKED_SCHEME;
use crate::spec::{LayoutSpec, SlotOrder};
use crate::{err, Dump, DumpError, DumpScheme, Header};

/// Checks the shapes the header alone fixes (every layout's but the masked nodes' and an
/// A-buffer's with `offsets`, whose sizes come from an array), before any array is read. A
/// header whose scheme cannot be read is left to decoding, which names the fault.
///
/// # Errors
/// As [`Dump::check_shapes`].
pub(super) fn check_shapes(header: &Header) -> Result<(), DumpError> {
    if header.scheme == MASKED_SCHEME {
        return Ok(());
    }
    match DumpScheme::from_header(header, None) {
        Ok(scheme) => check_scheme_shapes(header, &scheme),
        Err(_) => Ok(()),
    }
}

/// One dimension of an array as the header fixes it: its size, and the fields that make it.
struct Dim {
    size: u64,
    from: String,
}

impl Dump {
    /// Checks that each array the layout of `scheme` sizes from the header holds as many words
    /// as the header's fields say. A shape of another rank with the same number of words (a flat
    /// `[pixels · k]`) is accepted, as the reader takes the words row-major; one of the same rank
    /// must be the one the fields make.
    ///
    /// # Errors
    /// An array of another number of words, naming the array, its `shape` and the header fields
    /// whose dimension it contradicts; a shape of the right rank and words but other dimensions
    /// (the transpose of the right one says so, and which order would fit it).
    pub(super) fn check_shapes(&self, scheme: &DumpScheme) -> Result<(), DumpError> {
        check_scheme_shapes(&self.header, scheme)
    }
}

fn check_scheme_shapes(header: &Header, scheme: &DumpScheme) -> Result<(), DumpError> {
    for (name, dims) in expected_shapes(header, scheme)? {
        let Some(spec) = header.arrays.get(name) else {
            continue; // Decoding names a missing array.
        };
        let wanted: Vec<u64> = dims.iter().map(|d| d.size).collect();
        let words = |shape: &[u64]| shape.iter().try_fold(1_u64, |n, &d| n.checked_mul(d));
        if words(&spec.shape) == words(&wanted) {
            if spec.shape.len() != wanted.len() || spec.shape == wanted {
                continue;
            }
            let reversed: Vec<u64> = wanted.iter().rev().copied().collect();
            if spec.shape == reversed {
                return err(format!(
                    "array {name:?}: shape {:?} looks transposed: the header's fields make it \
                     {wanted:?}{}",
                    spec.shape,
                    transposed_hint(header, name)
                ));
            }
        }
        // The fields whose dimension the shape has nowhere (a shape in the other slot order
        // still has the pixels); every field when each dimension is there in another rank.
        let mut at_fault: Vec<&str> = dims
            .iter()
            .filter(|d| !spec.shape.contains(&d.size))
            .map(|d| d.from.as_str())
            .collect();
        if at_fault.is_empty() {
            at_fault = dims.iter().map(|d| d.from.as_str()).collect();
        }
        let verb = if at_fault.len() == 1 { "makes" } else { "make" };
        return err(format!(
            "array {name:?}: shape {:?} disagrees with the header's {}, which {verb} it \
             {wanted:?}",
            spec.shape,
            at_fault.join(" and ")
        ));
    }
    Ok(())
}

/// What a transposed array's shape would fit: the other slot order, where the layout has one.
fn transposed_hint(header: &Header, name: &str) -> &'static str {
    match header.layout {
        _ if name != "slots" => "",
        Some(LayoutSpec::Slots {
            order: SlotOrder::SlotMajor,
            ..
        }) => "; did you mean layout pixel-major?",
        _ => "; did you mean layout slot-major?",
    }
}

/// The arrays whose sizes the header fixes, each with its dimensions.
fn expected_shapes(
    header: &Header,
    scheme: &DumpScheme,
) -> Result<Vec<(&'static str, Vec<Dim>)>, DumpError> {
    let pixels = header.framebuffer()?.pixels() as u64;
    let samples = header.samples()?;
    let mut of_pixels = format!("\"width\" {} × \"height\" {}", header.width, header.height);
    if samples > 1 {
        of_pixels += &format!(" × {samples} samples");
    }
    let pixel_dim = || Dim {
        size: pixels,
        from: format!("{of_pixels} = {pixels} lists"),
    };
    let field = |name: &str, size: u32| Dim {
        size: u64::from(size),
        from: format!("{name:?} {size}"),
    };
    // A slot array's two dimensions in the header's slot order.
    let slots = |per_pixel: Dim| {
        let slot_major = matches!(
            header.layout,
            Some(LayoutSpec::Slots {
                order: SlotOrder::SlotMajor,
                ..
            })
        );
        if slot_major {
            vec![per_pixel, pixel_dim()]
        } else {
            vec![pixel_dim(), per_pixel]
        }
    };
    Ok(match scheme {
        DumpScheme::Mdts { k, .. } | DumpScheme::Mdts32 { k } | DumpScheme::KBuffer { k, .. } => {
            vec![("slots", slots(field("k", *k)))]
        }
        DumpScheme::ABufferFixed { capacity, .. } => vec![
            ("counters", vec![pixel_dim()]),
            ("slots", slots(field("capacity", *capacity))),
        ],
        DumpScheme::ABufferExact { counts, .. } => vec![
            ("counters", vec![pixel_dim()]),
            (
                "slots",
                vec![Dim {
                    size: counts.iter().map(|&c| u64::from(c)).sum(),
                    from: "the last of \"offsets\"".into(),
                }],
            ),
        ],
        // The nodes first: a wrong `pool` is named by them, before the links.
        DumpScheme::LinkedLists { pool, .. } => vec![
            ("nodes", vec![field("pool", *pool)]),
            ("heads", vec![pixel_dim()]),
            ("next", vec![field("pool", *pool)]),
            (
                "counter",
                vec![Dim {
                    size: 1,
                    from: "one counter".into(),
                }],
            ),
        ],
        DumpScheme::LayerMajor { k, .. } => vec![
            ("counters", vec![pixel_dim()]),
            ("layers", vec![field("k", *k), pixel_dim()]),
        ],
        // The scheme's own memory, sized by its constructor: decoding names the sizes.
        DumpScheme::Memory { .. } => Vec::new(),
    })
}
