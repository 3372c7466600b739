// The build seam, with no Rust twin: what lets every other file compile both with nvcc (the GPU
// backend) and with g++ as the serial CPU emulation (`-DFRAGSIM_EMULATE`, `make emulate`). On
// CUDA it brings the runtime and the error check; in the emulation it defines the CUDA keywords
// away and supplies the round-to-nearest intrinsics as the plain IEEE operations they are.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#ifdef __CUDACC__
#include <cuda_runtime.h>
#define CK(call)                                                                          \
  do {                                                                                    \
    cudaError_t e_ = (call);                                                              \
    if (e_ != cudaSuccess) {                                                              \
      fprintf(stderr, "CUDA error %s at %s:%d\n", cudaGetErrorString(e_), __FILE__, __LINE__); \
      exit(3);                                                                            \
    }                                                                                     \
  } while (0)
#else
#include <chrono>
#define __global__
#define __device__
#define __host__
// CUDA's built-in thread coordinates, set by the emulation's LAUNCH (executors/serial.cuh).
struct Dim { unsigned x; };
static Dim blockIdx, threadIdx, blockDim;
static inline double __dmul_rn(double a, double b) { return a * b; }
static inline double __dadd_rn(double a, double b) { return a + b; }
static inline double __ddiv_rn(double a, double b) { return a / b; }
static inline float __double2float_rn(double a) { return (float)a; }
static inline unsigned __float_as_uint(float f) { unsigned u; memcpy(&u, &f, 4); return u; }
#endif

typedef unsigned long long u64;
typedef unsigned int u32;

template <class T>
__device__ __host__ inline T lo(T a, T b) { return a < b ? a : b; }
template <class T>
__device__ __host__ inline T hi(T a, T b) { return a < b ? b : a; }
