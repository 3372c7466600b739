// Mirrors crates/schemes/src/common/word.rs (the fragment word encoding, `MdtsWord`):
// a u64 word is `depth_key << 32 | prim`, so every fragment is distinct and ordered by depth, then
// primitive; a u32 word is the depth key alone. All ones is the empty sentinel of both widths: no
// depth key reaches it (the largest is 0x3F800000, depth 1.0).
#pragma once

#include "device.cuh"

constexpr u64 EMPTY64 = ~0ull;
constexpr u32 EMPTY32 = ~0u;

// The empty sentinel of a word type.
template <class W>
constexpr W empty_word() { return ~W(0); }

__device__ inline u64 fragment_word(u32 key, u32 prim) { return ((u64)key << 32) | prim; }
