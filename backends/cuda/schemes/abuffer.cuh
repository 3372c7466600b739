// Mirrors crates/schemes/src/abuffer.rs: FreePipe's A-buffer (§4.2) on fixed arrays. Each
// fragment takes a slot with fetch-and-add on its pixel's counter and stores its word there when
// the slot is below the capacity; the counter keeps counting past it, so counter - capacity is the
// pixel's overflow. The post pass sorts each pixel's min(counter, capacity) words (one thread per
// pixel). Memory: a u32 counter and `capacity` u64 words per pixel; dumped with "sorted": true.
#pragma once

#include "device.cuh"
#include "executors/frame.cuh"
#include "executors/parallel.cuh"
#include "memory/mod.cuh"
#include "oracle/dump/write.cuh"
#include "schemes/common/sort.cuh"
#include "schemes/common/word.cuh"

struct ABufferOp {
  u32* counters;
  u64* slots;
  u32 capacity;
  __device__ void operator()(u32 p, u32 key, u32 prim) {
    u32 slot = atomicAdd(&counters[p], 1u);
    if (slot < capacity) slots[(u64)p * capacity + slot] = fragment_word(key, prim);
  }
};

// FreePipe's post-sort: one thread per pixel.
__global__ void sort_kernel(const u32* counters, u64* slots, u32 pixels, u32 capacity) {
  u32 p = blockIdx.x * blockDim.x + threadIdx.x;
  if (p >= pixels) return;
  insertion_sort(slots + (u64)p * capacity, lo(counters[p], capacity));
}

// The capacity is job.k; the counters are job.d_counters.
static void run_abuffer(const Job& job) {
  const u32 capacity = job.k;
  const uint64_t pixels = job.pixels, words = pixels * capacity;
  u32* d_counters = job.d_counters;
  const DeviceArray<u64> slots(words);
  u64* d_slots = slots.get();
  // Slots need no initialisation (only min(counter, capacity) of them are read); they are
  // filled once so that the dump's unused slots are deterministic.
  LAUNCH(fill_kernel<u64>, words, 512, d_slots, words, EMPTY64);
  const Timings t = run_frames(
      job.reps, [&] { LAUNCH(fill_kernel<u32>, pixels, 512, d_counters, pixels, 0u); },
      [&] {
        LAUNCH(raster_kernel<ABufferOp>, job.n, job.block, job.d_tris, job.n, (int)job.scene->width,
               (int)job.scene->height, ABufferOp{d_counters, d_slots, capacity});
      },
      [&] { LAUNCH(sort_kernel, pixels, 64, d_counters, d_slots, (u32)pixels, capacity); });
  std::vector<u64> host(words);
  std::vector<u32> host_counters(pixels);
  to_host(host.data(), d_slots, words);
  to_host(host_counters.data(), d_counters, pixels);
  std::string dir = job.out + "/abuffer";
  make_dir(dir);
  write_file(dir + "/slots.u64", host.data(), words * 8);
  write_file(dir + "/counters.u32", host_counters.data(), pixels * 4);
  std::string params = "  \"capacity\": " + std::to_string(capacity) + ",\n  \"sorted\": true,\n";
  write_header(dir, *job.scene, "abuffer", "atomicAdd+insertion-sort", params, "key<<32|prim",
               array_json("counters", "counters.u32", "u32", pixels, 0) + ", " +
                   array_json("slots", "slots.u64", "u64", pixels, capacity),
               t, job.device);
  print_result(job, "abuffer", "atomicAdd+insertion-sort", t, words * 8 + pixels * 4);
}
