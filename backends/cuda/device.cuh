// The build seam, with no Rust twin: what lets every other file compile both with nvcc (the GPU
// backend) and with g++ as the serial CPU emulation (`-DFRAGSIM_EMULATE`, `make emulate`). Both
// get the error a failing case throws; on CUDA it brings the runtime and the error check; in the
// emulation it defines the CUDA keywords away and supplies the round-to-nearest intrinsics as the
// plain IEEE operations they are.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

// A case that cannot run, with the exit status the one-shot command gives it: 2 for its input or
// output (a missing scene, a directory that cannot be written, bad options), 3 for the device.
// Thrown rather than exiting so that the server (serve.cuh) answers it and goes on to the next
// case; after a device error it stops, since a CUDA context that saw one may be unusable.
struct CaseError : std::runtime_error {
  int status;
  CaseError(int status, const std::string& message) : std::runtime_error(message), status(status) {}
};
constexpr int STATUS_INPUT = 2, STATUS_DEVICE = 3;

[[noreturn]] static inline void fail(int status, const std::string& message) { throw CaseError(status, message); }

#ifdef __CUDACC__
#include <cuda_runtime.h>
#define CK(call)                                                                                       \
  do {                                                                                                 \
    cudaError_t e_ = (call);                                                                           \
    if (e_ != cudaSuccess)                                                                             \
      fail(STATUS_DEVICE, std::string("CUDA error ") + cudaGetErrorString(e_) + " at " + __FILE__ + ":" + \
                              std::to_string(__LINE__));                                              \
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
