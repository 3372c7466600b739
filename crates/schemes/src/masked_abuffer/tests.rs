//! Tests of the masked-node A-buffer and linked list: one primitive's samples in a pixel merge into
//! one node with the nearest key, whole nodes are dropped and counted past the capacity or the
//! pool, and bad parameters are refused by name.

use super::*;
use fragsim_capture::merge_samples;
use fragsim_memory::SerialMemory;
use fragsim_raster::Fragment;

/// Runs `node`'s walk into `pixel` to its end; whether it was stored.
fn insert(scheme: &MaskedABuffer, pixel: u32, node: MaskedNode, memory: &SerialMemory) -> bool {
    let mut steps = 0;
    scheme.insert(PixelNode { pixel, node }, memory, &mut steps) == Step::Stored
}

fn sample(pixel: u32, depth_key: u32, prim: u32) -> Fragment {
    Fragment {
        pixel,
        depth_key,
        prim,
    }
}

#[test]
fn one_primitives_samples_in_one_pixel_merge_into_one_node_with_the_nearest_key() {
    // 4 samples a pixel: pixel 0 is samples 0..4, pixel 1 is 4..8.
    let mut fragments = vec![
        sample(5, 30, 7),
        sample(0, 20, 7),
        sample(2, 10, 7),
        sample(1, 50, 9),
    ];
    let mut nodes = Vec::new();
    merge_samples(4, &mut fragments, &mut |p, n| nodes.push((p, n)));
    let node = |depth_key, prim, mask| MaskedNode {
        depth_key,
        prim,
        mask,
    };
    assert_eq!(
        nodes,
        [
            (0, node(10, 7, 0b0101)),
            (0, node(50, 9, 0b0010)),
            (1, node(30, 7, 0b0010))
        ]
    );
}

#[test]
fn past_its_capacity_a_pixel_drops_whole_nodes_and_counts_them() {
    let scheme = MaskedABuffer::new(Viewport::new(1, 1).unwrap(), 4, 2, u64::MAX).unwrap();
    let memory: SerialMemory = scheme.layout().allocate();
    for (prim, key) in [(3, 30), (1, 10), (2, 20)] {
        let node = MaskedNode {
            depth_key: key,
            prim,
            mask: 1 << prim,
        };
        assert_eq!(insert(&scheme, 0, node, &memory), prim != 2);
    }
    let lists = scheme.node_lists(&memory);
    assert_eq!(lists.overflow, [1]);
    let prims: Vec<u32> = lists.pixel(0).iter().map(|n| n.prim).collect();
    assert_eq!(prims, [1, 3]);
    let per_sample = lists.per_sample();
    assert_eq!(per_sample.pixel(1), [10 << 32 | 1]);
    assert!(per_sample.pixel(2).is_empty());
}

#[test]
fn past_its_pool_the_linked_list_drops_whole_nodes_and_counts_them_in_all() {
    let two = Viewport::new(2, 1).unwrap();
    let pool = MaskedStorage::Pool(3);
    let scheme = MaskedABuffer::with_storage(two, 4, pool, u64::MAX).unwrap();
    assert_eq!(scheme.name(), "linked-list-masked");
    let memory: SerialMemory = scheme.layout().allocate();
    // Pixel 0 gets three nodes, pixel 1 one: the pool of three is shared, the fourth dropped.
    for (pixel, prim, key) in [(0, 3, 30), (1, 5, 50), (0, 1, 10), (0, 2, 20)] {
        let node = MaskedNode {
            depth_key: key,
            prim,
            mask: 1 << (prim % 4),
        };
        assert_eq!(insert(&scheme, pixel, node, &memory), prim != 2);
    }
    let lists = scheme.node_lists(&memory);
    assert_eq!(scheme.dropped(&memory), 1);
    assert_eq!(lists.overflow, [0, 0]);
    let prims = |p| lists.pixel(p).iter().map(|n| n.prim).collect::<Vec<_>>();
    assert_eq!((prims(0), prims(1)), (vec![1, 3], vec![5]));
    assert_eq!(lists.pixel(1)[0].mask, 0b0010);
}

#[test]
fn bad_parameters_are_refused_by_name() {
    let one = Viewport::new(1, 1).unwrap();
    assert!(MaskedABuffer::new(one, 4, 0, u64::MAX)
        .unwrap_err()
        .to_string()
        .contains("capacity"));
    assert!(MaskedABuffer::new(one, 64, 1, u64::MAX)
        .unwrap_err()
        .to_string()
        .contains("64 samples"));
    assert!(matches!(
        MaskedABuffer::new(one, 4, 8, 10),
        Err(CaptureError::TooMuchMemory { .. })
    ));
    assert!(
        MaskedABuffer::with_storage(one, 4, MaskedStorage::Pool(0), u64::MAX)
            .unwrap_err()
            .to_string()
            .contains("pool")
    );
}
