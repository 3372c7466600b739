// Mirrors crates/schemes/src/mdts.rs: the multi-depth test scheme, FreePipe (Liu et al.,
// I3D 2010) §4.1.1 and Table 1. Each pixel owns K words initialised to the empty sentinel; a
// fragment walks them with `old = atomicMin(&A[i], new)`, stops on an empty slot and carries
// `max(new, old)` on. Both word widths of mdts.rs: u64 words `key<<32|prim` (dump scheme `mdts`)
// and the paper's u32 depth keys (`mdts32`). Memory: K words per pixel; one pass, no post pass.
#pragma once

#include "device.cuh"
#include "executors/frame.cuh"
#include "executors/parallel.cuh"
#include "memory/mod.cuh"
#include "oracle/dump/write.cuh"
#include "schemes/common/word.cuh"

// FreePipe Table 1 on 64-bit words: carry the larger value on, stop on an empty slot.
struct MdtsOp {
  u64* slots;
  u32 k;
  __device__ void operator()(u32 p, u32 key, u32 prim) {
    u64 v = fragment_word(key, prim);
    u64* s = slots + (u64)p * k;
    for (u32 i = 0; i < k; i++) {
      u64 old = atomicMin(&s[i], v);
      if (old == EMPTY64) return;
      v = v > old ? v : old;
    }
  }
};

struct Mdts32Op {
  u32* slots;
  u32 k;
  __device__ void operator()(u32 p, u32 key, u32) {
    u32 v = key;
    u32* s = slots + (u64)p * k;
    for (u32 i = 0; i < k; i++) {
      u32 old = atomicMin(&s[i], v);
      if (old == EMPTY32) return;
      v = v > old ? v : old;
    }
  }
};

// Runs a scheme of MDTS's layout (K words of type W per pixel, empty = all ones; the k-buffer
// shares it) for job.reps frames and writes its dump OUT/<name>/ under the dump scheme `scheme`.
template <class Op, class W>
static void run_mdts_layout(const Job& job, const char* name, const char* scheme, const char* variant,
                            const char* word) {
  const uint64_t words = job.pixels * job.k;
  const DeviceArray<W> slots(words);
  W* d_slots = slots.get();
  const Timings t = run_frames(
      job.reps, [&] { LAUNCH(fill_kernel<W>, words, 512, d_slots, words, empty_word<W>()); },
      [&] {
        LAUNCH(raster_kernel<Op>, job.n, job.block, job.d_tris, job.n, (int)job.scene->width,
               (int)job.scene->height, Op{d_slots, job.k});
      });
  std::vector<W> host(words);
  to_host(host.data(), d_slots, words);
  std::string dir = job.out + "/" + name;
  make_dir(dir);
  const bool wide = sizeof(W) == 8;
  const char* file = wide ? "slots.u64" : "slots.u32";
  write_file(dir + "/" + file, host.data(), words * sizeof(W));
  write_header(dir, *job.scene, scheme, variant, k_param(job.k), word,
               array_json("slots", file, wide ? "u64" : "u32", job.pixels, job.k), t, job.device);
  print_result(job, name, variant, t, words * sizeof(W));
}

static void run_mdts(const Job& job) {
  run_mdts_layout<MdtsOp, u64>(job, "mdts", "mdts", "atomicMin-u64", "key<<32|prim");
}

static void run_mdts32(const Job& job) {
  run_mdts_layout<Mdts32Op, u32>(job, "mdts32", "mdts32", "atomicMin-u32", "key");
}
