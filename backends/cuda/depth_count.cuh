// Mirrors crates/capture/src/depth_count.rs: the counting pass. One u32 counter per pixel, one
// atomicAdd per fragment; the counters are each pixel's depth complexity, whose maximum sizes K as
// fragsim's `--k auto` does (never the oracle's numbers).
#pragma once

#include "device.cuh"
#include "executors/frame.cuh"
#include "executors/parallel.cuh"
#include "memory/mod.cuh"

struct CountOp {
  u32* counters;
  __device__ void operator()(u32 p, u32, u32) { atomicAdd(&counters[p], 1u); }
};

struct DepthCounts {
  u32 max = 0;             // the maximum depth complexity
  uint64_t fragments = 0;  // the scene's fragments
  float ms = 0;            // the pass's raster kernel
};

// Runs the counting pass into job.d_counters and reads the counts back.
static DepthCounts depth_count(const Job& job) {
  LAUNCH(fill_kernel<u32>, job.pixels, 512, job.d_counters, job.pixels, 0u);
  Timer timer;
  timer.start();
  LAUNCH(raster_kernel<CountOp>, job.n, job.block, job.d_tris, job.n, (int)job.scene->width, (int)job.scene->height,
         CountOp{job.d_counters});
  DepthCounts counts;
  counts.ms = timer.stop();
  std::vector<u32> host(job.pixels);
  to_host(host.data(), job.d_counters, job.pixels);
  for (u32 c : host) { counts.max = std::max(counts.max, c); counts.fragments += c; }
  return counts;
}
