// Mirrors crates/schemes/src/common/sort.rs (`insertion_sort`): the per-pixel sort of
// FreePipe's post pass (§4.2), an insertion sort in registers (local memory for long lists) when
// the list fits KMAX_LOCAL entries, else in place in global memory.
#pragma once

#include "device.cuh"

constexpr int KMAX_LOCAL = 64;  // largest K the k-buffer and the register sort handle

// Sorts the n words of s ascending, written back in place.
__device__ inline void insertion_sort(u64* s, u32 n) {
  if (n <= (u32)KMAX_LOCAL) {
    u64 list[KMAX_LOCAL];
    for (u32 i = 0; i < n; i++) {
      u64 v = s[i];
      u32 j = i;
      while (j > 0 && list[j - 1] > v) {
        list[j] = list[j - 1];
        j--;
      }
      list[j] = v;
    }
    for (u32 i = 0; i < n; i++) s[i] = list[i];
  } else {
    for (u32 i = 1; i < n; i++) {
      u64 v = s[i];
      u32 j = i;
      while (j > 0 && s[j - 1] > v) {
        s[j] = s[j - 1];
        j--;
      }
      s[j] = v;
    }
  }
}
