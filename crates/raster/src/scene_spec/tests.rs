//! The up axis is the command line's, not the file's: what a spec writes, reads back and records.

use super::*;

fn spheres_up_z() -> SceneSpec {
    SceneSpec {
        up: UpAxis::Z,
        ..SceneSpec::named("spheres:2", 40.0, 20.0)
    }
}

#[test]
fn a_spec_written_and_read_back_is_the_same_but_for_its_up_axis() {
    let spec = spheres_up_z();
    let json = serde_json::to_string(&spec).unwrap();
    assert!(!json.contains("up"), "{json}");
    let back: SceneSpec = serde_json::from_str(&json).unwrap();
    assert_eq!(back.up, UpAxis::Y);
    assert_eq!(
        back,
        SceneSpec {
            up: UpAxis::Y,
            ..spec
        }
    );
}

#[test]
fn an_orbit_around_another_axis_is_recorded_as_the_matrix_it_was_seen_through() {
    let spec = spheres_up_z();
    let scene = spec.load(None).unwrap();
    let viewport = Viewport::new(48, 32).unwrap();
    let view = spec.view(&scene, viewport).unwrap();
    let recorded = spec.recorded(&view);
    assert_eq!(recorded.up, UpAxis::Y);
    assert!(recorded.view_projection.is_some());
    // The recorded spec, read back without its up axis, names the same view.
    let again = recorded.view(&scene, viewport).unwrap();
    assert_eq!(again.view_projection(), view.view_projection());
    // Around +y the orbit is recorded as it is.
    let upright = SceneSpec::named("spheres:2", 40.0, 20.0);
    let upright_view = upright.view(&scene, viewport).unwrap();
    assert_ne!(upright_view.view_projection(), view.view_projection());
    assert_eq!(upright.recorded(&upright_view), upright);
}

#[test]
fn an_engines_matrix_is_recorded_as_it_is() {
    let scene = Scene::procedural("spheres:2").unwrap();
    let viewport = Viewport::new(16, 16).unwrap();
    let mut row_major = [0.0; 16];
    for i in 0..4 {
        row_major[i * 5] = 0.5;
    }
    let engine = SceneSpec {
        view_projection: Some(ViewProjection {
            row_major,
            precision: VertexPrecision::F32,
        }),
        ..spheres_up_z()
    };
    let view = engine.view(&scene, viewport).unwrap();
    assert_eq!(
        engine.recorded(&view).view_projection,
        engine.view_projection
    );
}

#[test]
fn a_scene_that_cannot_load_says_so_in_its_own_words() {
    let unknown = SceneSpec::named("no-such-scene", 0.0, 0.0).load(None);
    let Err(SceneSpecError::Scene(e)) = unknown else {
        panic!("an unknown name is a scene error")
    };
    assert!(
        e.to_string().starts_with("unknown scene \"no-such-scene\""),
        "{e}"
    );
    let mut neither = SceneSpec::named("", 0.0, 0.0);
    neither.name = None;
    assert_eq!(
        neither.load(None).unwrap_err().to_string(),
        "the scene names neither a mesh nor a named scene"
    );
}
