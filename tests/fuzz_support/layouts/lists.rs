//! The `dump_layouts` target's list layouts: a linked-list dump (fragsim's, Vulkan-Samples' or any
//! numbering, links drawn from a few node numbers around the pool) and a layer-major dump
//! (counters past their layers), each with the model of what decoding must give.

use fragsim::catalog::SchemeName;
use fragsim::dump::{Corruption, Header, LayoutSpec, Words};
use fragsim::raster::Viewport;

use super::super::input::Input;
use super::{k, length, outside_fields, payload, payload_word, payload_words, Model};

/// A linked-list dump (`scheme` is `linked-list` or `linked-list-nearest`) and its model.
pub(super) fn linked_lists(
    input: &mut Input<'_>,
    header: &mut Header,
    viewport: Viewport,
    scheme: SchemeName,
    arrays: &mut Vec<(&'static str, Words)>,
) -> Result<Option<Model>, String> {
    let pixels = viewport.pixels();
    let k = k(input);
    let pool = 1 + usize::from(input.u8() % 8);
    let pool_nodes = u32::try_from(pool).expect("a pool of 1 to 8 nodes");
    let (null, node_base) = match input.u8() % 3 {
        0 => (0, 1),
        1 => (u32::MAX, 0),
        _ => (u32::from(input.u8()), u32::from(input.u8() % 4)),
    };
    let payload = payload(input);
    // Faults 0 to 4: an array one word off, 5: the nodes in the other dtype, 6: the counter in
    // two words; any other value: none.
    let fault = input.u8() % 12;
    let link = |bytes: &mut Input<'_>| match bytes.u8() {
        255 => u32::MAX,
        b if b & 3 == 0 => null,
        b => node_base.wrapping_add(u32::from(b >> 2) % (pool_nodes + 2)),
    };
    let heads: Vec<u32> = (0..length(pixels, fault, 0)).map(|_| link(input)).collect();
    let next: Vec<u32> = (0..length(pool, fault, 1)).map(|_| link(input)).collect();
    let nodes: Vec<u64> = (0..length(pool, fault, 2))
        .map(|_| payload_word(input, &payload))
        .collect();
    let counter = match input.u8() {
        255 => u32::MAX,
        b => u32::from(b) % (pool_nodes + 3),
    };
    let counters = if fault == 6 { 2 } else { 1 };
    arrays.push(("heads", Words::U32(heads.clone())));
    arrays.push(("next", Words::U32(next.clone())));
    arrays.push(("nodes", payload_words(nodes.clone(), &payload, fault == 5)));
    arrays.push(("counter", Words::U32(vec![counter; counters])));
    header.scheme = scheme.name().into();
    header.k = Some(k);
    header.pool = Some(length(pool, fault, 3) as u64);
    header.layout = Some(LayoutSpec::LinkedList {
        payload,
        null,
        node_base,
    });
    // What the reader refuses first: a `null` that numbers a node of the header's pool (the
    // header alone says it), the payload, then `k`, then the arrays (the nodes, whose count the
    // header's pool sets, before the heads and links).
    let numbered = u64::from(node_base)..u64::from(node_base) + length(pool, fault, 3) as u64;
    let fault = match fault {
        _ if numbered.contains(&u64::from(null)) => "\"null\"",
        _ if payload.check().is_err() => "payload",
        _ if k == 0 => "\"k\"",
        0 => "\"heads\"",
        1 => "\"next\"",
        2 | 3 | 5 => "\"nodes\"",
        6 => "\"counter\"",
        _ => "",
    };
    if !fault.is_empty() {
        return Err(fault.into());
    }
    // The model: each list walked once from its head, cut at its first bad link.
    let allocated = (counter as usize).min(pool);
    let mut visited = vec![false; pool];
    let mut steps = 0;
    let mut model = Model {
        corrupt: vec![Vec::new(); pixels],
        lists: Vec::with_capacity(pixels),
        unreachable: 0,
        stored_words: None,
        judged_against_itself: true,
    };
    for (p, &head) in heads.iter().enumerate() {
        let mut walked = Vec::new();
        let mut node = head;
        while node != null {
            steps += 1;
            assert!(steps <= pool + pixels, "the model's own walk is bounded");
            let index = node.checked_sub(node_base).map(|i| i as usize);
            let why = match index {
                Some(i) if i >= pool => Some(Corruption::OutOfPool),
                Some(i) if i >= allocated => Some(Corruption::Unallocated),
                Some(i) if visited[i] => Some(Corruption::Revisited),
                Some(_) => None,
                None => Some(Corruption::OutOfPool),
            };
            if let Some(why) = why {
                model.corrupt[p].push((walked.len(), why));
                break;
            }
            let i = index.expect("checked above");
            visited[i] = true;
            let (fragment, possible) = payload.fragment(nodes[i]);
            if !possible {
                model.corrupt[p].push((walked.len(), Corruption::ImpossibleKey));
            } else if nodes[i] & outside_fields(&payload) != 0 {
                model.corrupt[p].push((walked.len(), Corruption::OutsideFields));
            }
            walked.push(fragment);
            node = next[i];
        }
        // The verdict judges every node a list reaches, whatever the resolve's `k` keeps for
        // shading (`Dump::capture`), sorted.
        walked.sort_unstable();
        model.lists.push(walked);
    }
    model.unreachable = (allocated - visited.iter().filter(|&&v| v).count()) as u64;
    Ok(Some(model))
}

/// A layer-major dump (`layer-counter`) and its model.
pub(super) fn layer_major(
    input: &mut Input<'_>,
    header: &mut Header,
    viewport: Viewport,
    arrays: &mut Vec<(&'static str, Words)>,
) -> Result<Option<Model>, String> {
    let pixels = viewport.pixels();
    let k = k(input);
    let payload = payload(input);
    // Faults 0 and 1: an array one word off, 2: the layers one layer short, 3: the layers in
    // the other dtype; any other value: none.
    let fault = input.u8() % 8;
    let counters: Vec<u32> = (0..length(pixels, fault, 0))
        .map(|_| match input.u8() {
            255 => u32::MAX,
            b => u32::from(b) % (k + 3),
        })
        .collect();
    let mut layers_len = length(pixels * k as usize, fault, 1);
    if fault == 2 {
        layers_len = pixels * (k as usize).saturating_sub(1);
    }
    let layers: Vec<u64> = (0..layers_len)
        .map(|_| payload_word(input, &payload))
        .collect();
    arrays.push(("counters", Words::U32(counters.clone())));
    arrays.push((
        "layers",
        payload_words(layers.clone(), &payload, fault == 3),
    ));
    header.scheme = SchemeName::LayerCounter.name().into();
    header.k = Some(k);
    header.layout = Some(LayoutSpec::LayerMajor { payload });
    // What the reader refuses first: the payload, then `k`, then the layers, then the counters.
    let fault = match fault {
        _ if payload.check().is_err() => "payload",
        _ if k == 0 => "\"k\"",
        1..=3 => "\"layers\"",
        0 => "\"counters\"",
        _ => "",
    };
    if !fault.is_empty() {
        return Err(fault.into());
    }
    let mut model = Model {
        corrupt: vec![Vec::new(); pixels],
        lists: Vec::with_capacity(pixels),
        unreachable: 0,
        stored_words: None,
        judged_against_itself: true,
    };
    for (p, &count) in counters.iter().enumerate() {
        if count > k {
            model.corrupt[p].push((k as usize, Corruption::CounterPastStorage));
        }
        let mut list = Vec::new();
        for layer in 0..count.min(k) as usize {
            let (fragment, possible) = payload.fragment(layers[layer * pixels + p]);
            if !possible {
                model.corrupt[p].push((layer, Corruption::ImpossibleKey));
            } else if layers[layer * pixels + p] & outside_fields(&payload) != 0 {
                model.corrupt[p].push((layer, Corruption::OutsideFields));
            }
            list.push(fragment);
        }
        list.sort_unstable();
        model.lists.push(list);
    }
    Ok(Some(model))
}
