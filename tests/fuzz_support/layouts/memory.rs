//! The `dump_layouts` target's memory layout: a memory dump of a catalog scheme that dumps so,
//! sized as the scheme's own memory (or one word off), with arbitrary words.

use fragsim::capture::Scheme;
use fragsim::catalog::{Build, DumpLayout, SchemeName, SchemeVisitor, CATALOG};
use fragsim::dump::{Header, LayoutSpec, Words};
use fragsim::raster::Viewport;

use super::super::input::Input;
use super::length;

/// The number of u32 and u64 words a scheme's memory has.
struct Sizes;

impl SchemeVisitor for Sizes {
    type Output = (usize, usize);
    fn visit<S: Scheme>(self, scheme: &S, _slots: Option<u32>) -> Self::Output {
        let layout = scheme.layout();
        (layout.words32, layout.words64)
    }
}

/// A memory dump of one of the schemes that dump so, sized as the scheme's memory (or one word
/// off), with arbitrary words.
pub(super) fn memory(
    input: &mut Input<'_>,
    header: &mut Header,
    viewport: Viewport,
    arrays: &mut Vec<(&'static str, Words)>,
) -> Result<(), String> {
    let schemes: Vec<SchemeName> = CATALOG
        .iter()
        .filter(|e| e.dump == Some(DumpLayout::Memory))
        .map(|e| e.scheme)
        .collect();
    let scheme = schemes[usize::from(input.u8()) % schemes.len()];
    let [k, capacity, layers] = [0; 3].map(|_| 1 + u32::from(input.u8() % 4));
    let Ok((words32, words64)) = scheme.build(
        &Build::fixed(viewport, k, capacity, layers, u64::MAX),
        Sizes,
    ) else {
        // No such scheme of these sizes: refused, with whatever error the catalog gives.
        return Err(String::new());
    };
    // Faults 0 and 1: an array one word off; any other value: none.
    let fault = input.u8() % 6;
    let words32: Vec<u32> = (0..length(words32, fault, 0))
        .map(|_| input.u32())
        .collect();
    let words64: Vec<u64> = (0..length(words64, fault, 1))
        .map(|_| input.u64())
        .collect();
    arrays.push(("words32", Words::U32(words32.clone())));
    arrays.push(("words64", Words::U64(words64.clone())));
    header.scheme = scheme.name().into();
    (header.k, header.capacity, header.layers) = (Some(k), Some(capacity), Some(layers));
    header.layout = Some(LayoutSpec::Memory);
    // A size past the dump's words is refused before the scheme is built.
    let total = (words32.len() + words64.len()).max(1);
    let sizes = [
        ("\"k\"", k),
        ("\"capacity\"", capacity),
        ("\"layers\"", layers),
    ];
    if let Some((field, _)) = sizes.iter().find(|(_, v)| *v as usize > total) {
        return Err((*field).into());
    }
    match fault {
        0 | 1 => Err(scheme.name().into()),
        _ => Ok(()),
    }
}
