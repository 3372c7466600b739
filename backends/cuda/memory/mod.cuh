// Mirrors crates/capture/src/memory/mod.rs: the memory seam, the only place that knows which
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

template <class T>
static T* dev_alloc(uint64_t n) {
  T* p = nullptr;
#ifdef __CUDACC__
  CK(cudaMalloc(&p, std::max<uint64_t>(n, 1) * sizeof(T)));
#else
  p = (T*)malloc(std::max<uint64_t>(n, 1) * sizeof(T));
  if (!p) { fprintf(stderr, "out of memory\n"); exit(3); }
#endif
  return p;
}
template <class T>
static void dev_free(T* p) {
#ifdef __CUDACC__
  CK(cudaFree(p));
#else
  free(p);
#endif
}
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
