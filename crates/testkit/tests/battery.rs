//! The battery on fragsim itself: its exact schemes pass, and the k-buffer on the scheduled
//! executor, held to exactness, fails with a counterexample shrunk to one pixel and two fragments.
//!
//! Few cases each (CI runs them on two cores): the exact schemes are exact on every case, so a
//! handful already exercises the judge end to end; the k-buffer's hazard needs two fragments of a
//! pixel in flight together, which the first few dozen cases give.

use fragsim_capture::executors::Executor;
use fragsim_capture::Guarantee;
use fragsim_catalog::SchemeName;
use fragsim_testkit::{Battery, CatalogBackend, Failure, Params, Property};

fn params(scheme: SchemeName) -> Params {
    Params {
        scheme,
        k: 2,
        capacity: 2,
    }
}

#[test]
fn the_exact_schemes_pass_the_battery() {
    for (scheme, executor) in [
        (SchemeName::Mdts, Executor::Parallel),
        (SchemeName::MdtsDesc, Executor::Scheduled),
        (SchemeName::Abuffer, Executor::Parallel),
        (SchemeName::KbufferInterlock, Executor::Scheduled),
        (SchemeName::Kbuffer, Executor::Serial),
    ] {
        let backend = CatalogBackend::on(executor);
        let passed = Battery::new(&backend, params(scheme)).cases(24).run();
        match passed {
            Ok(passed) => assert_eq!(passed.cases, 24),
            Err(failure) => panic!("{scheme} on {}: {failure:?}", executor.name()),
        }
    }
}

#[test]
fn the_kbuffer_on_the_scheduled_executor_fails_with_one_pixel_and_two_fragments() {
    let backend = CatalogBackend::on(Executor::Scheduled);
    let battery = Battery::new(&backend, params(SchemeName::Kbuffer)).cases(200);
    // Its own claim owes nothing where pixels are not serialised: refused, not passed.
    assert!(matches!(battery.run(), Err(Failure::Refused(_))));
    let failure = Battery::new(&backend, params(SchemeName::Kbuffer))
        .cases(200)
        .claiming(Guarantee::Exact)
        .run();
    let Err(Failure::Counterexample(found)) = failure else {
        panic!("the racy k-buffer passed: {failure:?}");
    };
    assert!(
        matches!(found.property, Property::Equal | Property::OrderIndependent),
        "{found:?}"
    );
    assert_eq!(found.submitted.viewport.pixels(), 1, "{found:?}");
    assert_eq!(found.fragments, 2, "{found:?}");
    assert!(!found.mismatches().is_empty(), "{found:?}");
}
