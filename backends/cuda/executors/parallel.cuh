// Mirrors crates/capture/src/executors/parallel.rs: FreePipe's model, one logical thread per
// triangle, each rasterizing its triangle and running the scheme's step on every fragment as it is
// produced (never collected first). On CUDA, LAUNCH starts a grid of ceil(n / block) blocks; in the
// serial emulation it is the loop of executors/serial.cuh.
#pragma once

#include "device.cuh"
#include "executors/serial.cuh"
#include "raster/pipeline/scan.cuh"

#ifdef __CUDACC__
#define LAUNCH(kernel, n, block, ...)                                                      \
  do {                                                                                    \
    uint64_t n_ = (n);                                                                    \
    if (n_ > 0) kernel<<<(unsigned)((n_ + (block)-1) / (block)), (block)>>>(__VA_ARGS__); \
    CK(cudaGetLastError());                                                               \
  } while (0)
#endif

template <class Op>
__global__ void raster_kernel(const Tri* tris, u32 n, int width, int height, Op op) {
  u32 i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) scan(tris[i], width, height, op);
}
