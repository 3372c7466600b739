// Mirrors crates/memory/src/lib.rs: the memory seam, the only place that knows which
// atomic type is underneath. On CUDA the schemes' words live in global memory (cudaMalloc) and
// the atomics are the hardware's; in the serial emulation they are host arrays and the atomics
// plain read-modify-writes, as the Rust side's SerialMemory is to its AtomicMemory.
#pragma once

#include "device.cuh"

#ifndef __CUDACC__
static inline unsigned atomicAdd(unsigned* a, unsigned v) { unsigned o = *a; *a = o + v; return o; }
static inline unsigned atomicMin(unsigned* a, unsigned v) { unsigned o = *a; *a = o < v ? o : v; return o; }
static inline unsigned long long atomicMin(unsigned long long* a, unsigned long long v) {
  unsigned long long o = *a; *a = o < v ? o : v; return o;
}
#endif

// An array in device memory (host memory in the emulation), freed when it goes out of scope, so
// that a case that fails half-way leaves nothing allocated behind it: the server (serve.cuh) runs
// case after case in one process, and its memory stays what one case needs.
template <class T>
class DeviceArray {
 public:
  explicit DeviceArray(uint64_t n) {
    const uint64_t bytes = std::max<uint64_t>(n, 1) * sizeof(T);
#ifdef __CUDACC__
    CK(cudaMalloc(&data_, bytes));
#else
    data_ = (T*)malloc(bytes);
    if (!data_) fail(STATUS_DEVICE, "out of memory (" + std::to_string(bytes) + " bytes)");
#endif
  }
  ~DeviceArray() {
    // Not checked: a destructor may not throw, and after a device error the server stops anyway.
#ifdef __CUDACC__
    cudaFree(data_);
#else
    free(data_);
#endif
  }
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  T* get() const { return data_; }

 private:
  T* data_ = nullptr;
};

template <class T>
static void to_device(T* dst, const T* src, uint64_t n) {
#ifdef __CUDACC__
  CK(cudaMemcpy(dst, src, n * sizeof(T), cudaMemcpyHostToDevice));
#else
  memcpy(dst, src, n * sizeof(T));
#endif
}
template <class T>
static void to_host(T* dst, const T* src, uint64_t n) {
#ifdef __CUDACC__
  CK(cudaMemcpy(dst, src, n * sizeof(T), cudaMemcpyDeviceToHost));
#else
  memcpy(dst, src, n * sizeof(T));
#endif
}

// Storage initialisation (the Rust side's begin-pass fill): one thread per word.
template <class W>
__global__ void fill_kernel(W* words, uint64_t n, W value) {
  uint64_t i = (uint64_t)blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) words[i] = value;
}
