// Mirrors crates/capture/src/executors/frame.rs: the one frame loop every scheme's run goes
// through. A frame is begin (storage initialisation), the geometry pass (the raster kernel with the
// scheme's step) and, for schemes that have one, the post pass (the A-buffer's sort); each is timed
// with its own pair of CUDA events (steady_clock in the emulation). One untimed frame, then `reps`
// timed frames; the medians are what RESULT lines and dump headers report.
#pragma once

#include <type_traits>

#include "device.cuh"
#include "oracle/triangles.cuh"

struct Timer {
#ifdef __CUDACC__
  cudaEvent_t a, b;
  Timer() { CK(cudaEventCreate(&a)); CK(cudaEventCreate(&b)); }
  ~Timer() { cudaEventDestroy(a); cudaEventDestroy(b); }
  void start() { CK(cudaEventRecord(a)); }
  float stop() {
    CK(cudaEventRecord(b));
    CK(cudaEventSynchronize(b));
    float ms = 0;
    CK(cudaEventElapsedTime(&ms, a, b));
    return ms;
  }
#else
  std::chrono::steady_clock::time_point a;
  void start() { a = std::chrono::steady_clock::now(); }
  float stop() {
    return std::chrono::duration<float, std::milli>(std::chrono::steady_clock::now() - a).count();
  }
#endif
};

static float median(std::vector<float> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5f * (v[n / 2 - 1] + v[n / 2]);
}

struct Timings {
  float init_ms = 0, raster_ms = 0, sort_ms = 0, frame_ms = 0;
  int reps = 0;
};

static std::string timings_json(const Timings& t) {
  char buf[256];
  snprintf(buf, sizeof buf,
           "{\"init_ms\": %.4f, \"raster_ms\": %.4f, \"sort_ms\": %.4f, \"frame_ms\": %.4f, \"reps\": %d}",
           t.init_ms, t.raster_ms, t.sort_ms, t.frame_ms, t.reps);
  return buf;
}

// What every scheme's run needs: the scene on the device, K and the command line's options.
struct Job {
  const Scene* scene = nullptr;
  const Tri* d_tris = nullptr;  // the scene's triangles in device memory
  u32 n = 0;                    // how many
  uint64_t pixels = 0;
  u32 k = 0;  // slots per pixel (the A-buffer's capacity)
  int reps = 20, block = 64;  // FreePipe: 64 threads a block for rasterization
  std::string out, device;
  u32* d_counters = nullptr;  // one u32 per pixel, the counting pass's; the A-buffer reuses them
};

// Stands for "no post pass": a frame is then begin + pass, with no third timer.
struct NoPostPass {
  void operator()() const {}
};

template <class Begin, class Pass, class Post = NoPostPass>
static Timings run_frames(int reps, Begin begin, Pass pass, Post post = Post()) {
  constexpr bool has_post = !std::is_same<Post, NoPostPass>::value;
  std::vector<float> init, raster, sort, frame;
  for (int r = -1; r < reps; r++) {
    Timer ti, tr;
    ti.start();
    begin();
    float a = ti.stop();
    tr.start();
    pass();
    float b = tr.stop();
    float c = 0;
    if (has_post) {
      Timer ts;
      ts.start();
      post();
      c = ts.stop();
    }
    if (r >= 0) {
      init.push_back(a);
      raster.push_back(b);
      if (has_post) sort.push_back(c);
      frame.push_back(has_post ? a + b + c : a + b);
    }
  }
  Timings t;
  t.init_ms = median(init); t.raster_ms = median(raster); t.sort_ms = median(sort); t.frame_ms = median(frame);
  t.reps = reps;
  return t;
}

// The RESULT line of one scheme's run on stdout (summarize.py reads it).
static void print_result(const Job& job, const char* name, const char* variant, const Timings& t, uint64_t bytes) {
  printf("RESULT {\"scheme\": \"%s\", \"variant\": \"%s\", \"k\": %u, \"memory_bytes\": %llu, \"timings\": %s}\n",
         name, variant, job.k, (unsigned long long)bytes, timings_json(t).c_str());
  fflush(stdout);
}
