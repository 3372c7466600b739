// Mirrors crates/schemes/src/kbuffer/mod.rs, DELIBERATELY BROKEN, as `kbuffer-stores` is: the
// k-buffer's read-modify-write (Bavoil et al. 2007) as CUDA code writes it without atomics. Read
// all K slots, insert in registers, write all K back with plain (volatile) loads and stores;
// concurrent fragments of one pixel overwrite each other, and `fragsim compare` must catch it. It
// uses MDTS's layout, so compare judges it by MDTS's promise.
#pragma once

#include "device.cuh"
#include "executors/frame.cuh"
#include "schemes/common/sort.cuh"
#include "schemes/common/word.cuh"
#include "schemes/mdts.cuh"

struct KBufferOp {
  u64* slots;
  u32 k;
  __device__ void operator()(u32 p, u32 key, u32 prim) {
    volatile u64* s = slots + (u64)p * k;
    u64 list[KMAX_LOCAL];
    for (u32 i = 0; i < k; i++) list[i] = s[i];
    u64 v = fragment_word(key, prim);
    if (v >= list[k - 1]) return;  // not among the K nearest seen so far
    u32 i = k - 1;
    while (i > 0 && list[i - 1] > v) {
      list[i] = list[i - 1];
      i--;
    }
    list[i] = v;
    for (u32 j = 0; j < k; j++) s[j] = list[j];
  }
};

static void run_kbuffer(const Job& job) {
  if (job.k > (u32)KMAX_LOCAL) {
    fprintf(stderr, "kbuffer: K > %d unsupported, skipped\n", KMAX_LOCAL);
    return;
  }
  run_mdts_layout<KBufferOp, u64>(job, "kbuffer", "mdts", "kbuffer-nonatomic-rmw (deliberately broken)",
                                  "key<<32|prim");
}
