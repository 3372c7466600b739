//! Tests of the dump layouts: the header names are the catalog's layouts, and every catalog entry
//! with a layout dumps in it.

use super::*;
use crate::{Dtype, FORMAT, VERSION};
use fragsim_raster::scene_spec::SceneSpec;

fn header(scheme: &str) -> Header {
    Header {
        format: FORMAT.into(),
        version: VERSION,
        producer: String::new(),
        scene: SceneSpec::named("quads:1", 0.0, 0.0),
        width: 1,
        height: 1,
        scheme: scheme.into(),
        k: Some(2),
        capacity: Some(2),
        sorted: false,
        filled: false,
        pool: Some(4),
        layers: None,
        layout: None,
        word: String::new(),
        // Memory dumps' sizes are bounded by their words.
        arrays: [(
            "words32".to_string(),
            crate::ArraySpec {
                file: "words32.u32".into(),
                dtype: Dtype::U32,
                shape: vec![8],
            },
        )]
        .into_iter()
        .collect(),
        extra: serde_json::Value::Null,
    }
}

#[test]
fn header_names_are_the_catalogs_layouts() {
    for name in DumpLayout::names() {
        if DumpLayout::named(name) == Some(DumpLayout::MaskedNodes) {
            // Masked nodes are read apart (`masked.rs`): no dump scheme of fragments.
            let refused = DumpScheme::from_header(&header(name), None).unwrap_err();
            assert!(refused.to_string().contains("masked nodes"), "{refused}");
            continue;
        }
        let scheme = DumpScheme::from_header(&header(name), None).unwrap();
        assert_eq!(scheme.name(), name);
        assert_eq!(Some(scheme.layout()), DumpLayout::named(name));
    }
    // A scheme that dumps under another's name is no header name of its own.
    let unknown = DumpScheme::from_header(&header("abuffer-exact"), None)
        .unwrap_err()
        .to_string();
    assert!(
        unknown.starts_with("unknown scheme \"abuffer-exact\": expected mdts, mdts32, mdts-desc, ")
            && !unknown.contains("abuffer-exact,"),
        "{unknown}"
    );
    // A layout description of another kind than the scheme's is refused.
    let mut lists = header("linked-list");
    lists.layout = Some(LayoutSpec::Memory);
    let refused = DumpScheme::from_header(&lists, None).unwrap_err();
    assert_eq!(
        refused,
        DumpError::Invalid(
            "scheme linked-list dumps as linked-list, the header's layout is memory".into()
        )
    );
}

#[test]
fn every_catalog_entry_with_a_layout_dumps_in_it() {
    let sizes = Build::fixed(Viewport::new(2, 1).unwrap(), 3, 3, 1, u64::MAX);
    for entry in CATALOG {
        let dumped = DumpScheme::for_run(entry.scheme, 3, &sizes, Some(&[1, 2]));
        match entry.dump {
            Some(DumpLayout::MaskedNodes) => {
                let error = dumped.unwrap_err().to_string();
                assert!(error.contains("masked nodes"), "{error}");
            }
            Some(layout) => assert_eq!(dumped.unwrap().layout(), layout, "{}", entry.name),
            None => {
                let error = dumped.unwrap_err().to_string();
                let expected = format!(
                    "scheme {} has no dump layout; these have one: mdts, ",
                    entry.name
                );
                assert!(error.starts_with(&expected), "{error}");
            }
        }
    }
    let exact = DumpScheme::for_run(SchemeName::AbufferExact, 1, &sizes, Some(&[1, 2])).unwrap();
    assert_eq!(
        exact,
        DumpScheme::ABufferExact {
            counts: vec![1, 2],
            sorted: false
        }
    );
    assert!(DumpScheme::for_run(SchemeName::AbufferExact, 1, &sizes, None).is_err());
    let fixed = DumpScheme::for_run(SchemeName::AbufferBitonic, 4, &sizes, Some(&[1, 2])).unwrap();
    assert_eq!(
        fixed,
        DumpScheme::ABufferFixed {
            capacity: 4,
            sorted: false
        }
    );
}
