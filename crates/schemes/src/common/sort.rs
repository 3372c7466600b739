//! The post passes' sorts of a pixel's list: the A-buffer's two (FreePipe §4.2 names both), which
//! the stencil-routed A-buffer, the layer counter and the linked lists reuse.

/// Insertion sort, as a GPU thread sorts a short list in registers.
pub fn insertion_sort(list: &mut [u64]) {
    for i in 1..list.len() {
        let value = list[i];
        let mut j = i;
        while j > 0 && list[j - 1] > value {
            list[j] = list[j - 1];
            j -= 1;
        }
        list[j] = value;
    }
}

/// Bitonic sort: the list is padded with `u64::MAX` to a power of two and sorted by the network of
/// Batcher (1968), compare-exchange stage by stage as a GPU thread (or warp) runs it.
pub fn bitonic_sort(list: &mut [u64]) {
    let padded = list.len().next_power_of_two();
    let mut network = list.to_vec();
    network.resize(padded, u64::MAX);
    let mut size = 2;
    while size <= padded {
        let mut stride = size / 2;
        while stride > 0 {
            for i in 0..padded {
                let partner = i ^ stride;
                if partner > i {
                    let ascending = i & size == 0;
                    if (network[i] > network[partner]) == ascending {
                        network.swap(i, partner);
                    }
                }
            }
            stride /= 2;
        }
        size *= 2;
    }
    let len = list.len();
    list.copy_from_slice(&network[..len]);
}
