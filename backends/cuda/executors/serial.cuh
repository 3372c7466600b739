// Mirrors crates/capture/src/executors/serial.rs: one thread, threads in index order, each run to
// its end before the next starts. This is how the serial CPU emulation (`make emulate`) runs every
// kernel: LAUNCH becomes a loop over the thread indices of a CUDA grid, so the same scan and scheme
// code gives the reference (race-free) result.
#pragma once

#include "device.cuh"

#ifndef __CUDACC__
#define LAUNCH(kernel, n, block, ...)                                              \
  do {                                                                            \
    uint64_t n_ = (n);                                                            \
    blockDim.x = (block);                                                         \
    for (blockIdx.x = 0; blockIdx.x < (n_ + (block)-1) / (block); blockIdx.x++)   \
      for (threadIdx.x = 0; threadIdx.x < (unsigned)(block); threadIdx.x++)       \
        kernel(__VA_ARGS__);                                                      \
  } while (0)
#endif
