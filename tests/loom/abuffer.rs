//! The A-buffer.

use fragsim::capture::MEMORY_CAP_DEFAULT;
use fragsim::schemes::abuffer::{ABuffer, PostSort};

use super::{abuffer_model, fragments, one_pixel, DISTINCT};

/// A-buffer (fixed, capacity 4), 2 and 3 threads: distinct slots, every fragment captured,
/// counter = n. Exhaustive.
#[test]
fn abuffer_fixed_2_and_3_threads_capacity_4() {
    for n in [2, 3] {
        let scheme =
            ABuffer::fixed(one_pixel(), 4, PostSort::Insertion, MEMORY_CAP_DEFAULT).unwrap();
        let name = format!("abuffer_fixed_{n}_threads_capacity_4");
        let explored = abuffer_model(&name, scheme, 4, &fragments(&DISTINCT[..n]), None);
        assert!(explored >= 2);
    }
}

/// A-buffer (fixed, capacity 1 and 2), 3 threads: exactly `3 − capacity` walks dropped, the
/// stored fragments a subset, overflow `3 − capacity` reported, counter = 3. Exhaustive.
#[test]
fn abuffer_fixed_3_threads_overflow() {
    for capacity in [1, 2] {
        let scheme =
            ABuffer::fixed(one_pixel(), capacity, PostSort::Bitonic, MEMORY_CAP_DEFAULT).unwrap();
        let name = format!("abuffer_fixed_3_threads_capacity_{capacity}");
        abuffer_model(
            &name,
            scheme,
            capacity as usize,
            &fragments(&DISTINCT[..3]),
            None,
        );
    }
}

/// A-buffer (exact: one pixel of 4 slots from a count of 4), 4 threads, equal depths among
/// them: distinct slots, all four captured, counter = 4. Exhaustive.
#[test]
fn abuffer_exact_4_threads() {
    let scheme = ABuffer::exact(&[4], PostSort::Insertion, MEMORY_CAP_DEFAULT).unwrap();
    let list = fragments(&[(0.5, 0), (0.25, 1), (0.5, 2), (0.125, 3)]);
    let explored = abuffer_model("abuffer_exact_4_threads", scheme, 4, &list, None);
    assert!(explored >= 24);
}

/// A-buffer (exact, sized for 2 by a stale count), 4 threads: two stored, two dropped, overflow 2
/// reported. Exhaustive.
#[test]
fn abuffer_exact_4_threads_capacity_2() {
    let scheme = ABuffer::exact(&[2], PostSort::Insertion, MEMORY_CAP_DEFAULT).unwrap();
    abuffer_model(
        "abuffer_exact_4_threads_capacity_2",
        scheme,
        2,
        &fragments(&DISTINCT),
        None,
    );
}
