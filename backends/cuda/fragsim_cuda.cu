// fragsim_cuda: FreePipe's multi-fragment schemes (Liu et al., I3D 2010, §3-4) on a CUDA GPU,
// checked against fragsim's oracle through the dump format (docs/dump-format.md).
//
// Input: fragsim's triangle export (`fragsim export-scene`): the screen triangles after fragsim's
// vertex stage, clipping, snapping and orientation. This program is FreePipe's rasterizer from
// there on: one thread per screen triangle, a bounding-box scan with the integer edge functions
// and the top-left rule of docs/semantics.md §4, depth (E0*z0 + E1*z1 + E2*z2) / area in f64,
// evaluated left to right, rounded once to f32 (§5), and the depth key of §6. Every arithmetic
// step that rounds is an explicit round-to-nearest intrinsic, so that nvcc cannot contract it into
// an FMA and change the last bit.
//
// Schemes (each writes a dump directory OUT/<name>/):
//   mdts      u64 words key<<32|prim, K slots per pixel, atomicMin walk (FreePipe Table 1, 64-bit)
//   mdts32    u32 depth keys, K slots, atomicMin walk (FreePipe Table 1 as printed)
//   abuffer   u32 counter per pixel (atomicAdd) + K fixed slots of u64 words, then a per-pixel
//             insertion-sort kernel (FreePipe §4.2); dumped with "sorted": true
//   kbuffer   DELIBERATELY BROKEN: a k-buffer style read-all / insert / write-all of the K slots
//             with plain loads and stores (no atomics), MDTS layout: concurrent fragments of one
//             pixel overwrite each other. fragsim compare must catch it.
// K defaults to the scene's maximum depth complexity, measured by a counting pass on the GPU.
//
// Timing: CUDA events around each kernel; each scheme runs one untimed frame, then --reps timed
// frames (init + raster [+ sort]); the medians are printed and stored in the dump's "extra".
//
// Build: nvcc -O3 -arch=sm_90 -fmad=false -o fragsim_cuda fragsim_cuda.cu
// The same file builds without CUDA as a serial CPU emulation (g++ -x c++ -DFRAGSIM_EMULATE),
// which runs the identical scan and scheme code one thread at a time: used to check the code
// against fragsim before spending GPU time.

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
#define LAUNCH(kernel, n, block, ...)                                                      \
  do {                                                                                    \
    uint64_t n_ = (n);                                                                    \
    if (n_ > 0) kernel<<<(unsigned)((n_ + (block)-1) / (block)), (block)>>>(__VA_ARGS__); \
    CK(cudaGetLastError());                                                               \
  } while (0)
#else
// Serial CPU emulation: kernels are plain functions called once per thread index.
#include <chrono>
#define __global__
#define __device__
#define __host__
struct Dim { unsigned x; };
static Dim blockIdx, threadIdx, blockDim;
#define LAUNCH(kernel, n, block, ...)                                              \
  do {                                                                            \
    uint64_t n_ = (n);                                                            \
    blockDim.x = (block);                                                         \
    for (blockIdx.x = 0; blockIdx.x < (n_ + (block)-1) / (block); blockIdx.x++)   \
      for (threadIdx.x = 0; threadIdx.x < (unsigned)(block); threadIdx.x++)       \
        kernel(__VA_ARGS__);                                                      \
  } while (0)
static inline double __dmul_rn(double a, double b) { return a * b; }
static inline double __dadd_rn(double a, double b) { return a + b; }
static inline double __ddiv_rn(double a, double b) { return a / b; }
static inline float __double2float_rn(double a) { return (float)a; }
static inline unsigned __float_as_uint(float f) { unsigned u; memcpy(&u, &f, 4); return u; }
static inline unsigned atomicAdd(unsigned* a, unsigned v) { unsigned o = *a; *a = o + v; return o; }
static inline unsigned atomicMin(unsigned* a, unsigned v) { unsigned o = *a; *a = o < v ? o : v; return o; }
static inline unsigned long long atomicMin(unsigned long long* a, unsigned long long v) {
  unsigned long long o = *a; *a = o < v ? o : v; return o;
}
#endif

typedef unsigned long long u64;
typedef unsigned int u32;

constexpr u64 EMPTY64 = ~0ull;
constexpr u32 EMPTY32 = ~0u;
constexpr int SUBPIXEL_BITS = 8;
constexpr int64_t ONE = 1 << SUBPIXEL_BITS, HALF = ONE / 2;
constexpr int KMAX_LOCAL = 64;  // largest K the k-buffer and the register sort handle

// One record of the triangle export (56 bytes, little-endian, docs/dump-format.md).
struct Tri {
  u32 prim;
  int32_t xy[6];  // x0 y0 x1 y1 x2 y2 in 1/256 pixel, y down, oriented: doubled area > 0
  u32 reserved;
  double z[3];    // window depth z/w of each vertex
};
static_assert(sizeof(Tri) == 56, "triangle record is 56 bytes");

template <class T>
__device__ __host__ inline T lo(T a, T b) { return a < b ? a : b; }
template <class T>
__device__ __host__ inline T hi(T a, T b) { return a < b ? b : a; }

__device__ inline int64_t edge_fn(int64_t ax, int64_t ay, int64_t bx, int64_t by, int64_t px, int64_t py) {
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

__device__ inline bool top_left(int64_t ax, int64_t ay, int64_t bx, int64_t by) {
  int64_t dx = bx - ax, dy = by - ay;
  return dy < 0 || (dy == 0 && dx > 0);
}

// Rust's i64::div_euclid for a positive divisor: floor division.
__device__ inline int64_t floor_div(int64_t a, int64_t b) {
  int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

// Scans one screen triangle exactly as fragsim's View::scan does and calls op(pixel, key, prim)
// for every covered pixel centre whose f32 depth lies in [0, 1].
template <class Op>
__device__ void scan(const Tri& t, int width, int height, Op& op) {
  const int64_t ax = t.xy[0], ay = t.xy[1], bx = t.xy[2], by = t.xy[3], cx = t.xy[4], cy = t.xy[5];
  const int64_t area = edge_fn(ax, ay, bx, by, cx, cy);
  if (area <= 0) return;  // the export holds oriented, non-degenerate triangles only
  const int64_t minx = lo(ax, lo(bx, cx)), maxx = hi(ax, hi(bx, cx));
  const int64_t miny = lo(ay, lo(by, cy)), maxy = hi(ay, hi(by, cy));
  const int64_t x0 = hi<int64_t>(floor_div(minx - HALF + ONE - 1, ONE), 0);
  const int64_t x1 = lo<int64_t>(floor_div(maxx - HALF, ONE), width - 1);
  const int64_t y0 = hi<int64_t>(floor_div(miny - HALF + ONE - 1, ONE), 0);
  const int64_t y1 = lo<int64_t>(floor_div(maxy - HALF, ONE), height - 1);
  // Edge i is opposite vertex i: (B, C), (C, A), (A, B).
  const int64_t bias0 = top_left(bx, by, cx, cy) ? 0 : -1;
  const int64_t bias1 = top_left(cx, cy, ax, ay) ? 0 : -1;
  const int64_t bias2 = top_left(ax, ay, bx, by) ? 0 : -1;
  const double areaf = (double)area;
  for (int64_t y = y0; y <= y1; y++) {
    const int64_t py = y * ONE + HALF;
    for (int64_t x = x0; x <= x1; x++) {
      const int64_t px = x * ONE + HALF;
      const int64_t e0 = edge_fn(bx, by, cx, cy, px, py);
      const int64_t e1 = edge_fn(cx, cy, ax, ay, px, py);
      const int64_t e2 = edge_fn(ax, ay, bx, by, px, py);
      if (e0 + bias0 >= 0 && e1 + bias1 >= 0 && e2 + bias2 >= 0) {
        const double num = __dadd_rn(__dadd_rn(__dmul_rn((double)e0, t.z[0]), __dmul_rn((double)e1, t.z[1])),
                                     __dmul_rn((double)e2, t.z[2]));
        const float d = __double2float_rn(__ddiv_rn(num, areaf));
        if (d >= 0.0f && d <= 1.0f) {  // false for NaN, as Rust's range test
          u32 key = __float_as_uint(d);
          if (key == 0x80000000u) key = 0;  // -0.0 is depth 0
          op((u32)(y * width + x), key, t.prim);
        }
      }
    }
  }
}

struct CountOp {
  u32* counters;
  __device__ void operator()(u32 p, u32, u32) { atomicAdd(&counters[p], 1u); }
};

// FreePipe Table 1 on 64-bit words: carry the larger value on, stop on an empty slot.
struct MdtsOp {
  u64* slots;
  u32 k;
  __device__ void operator()(u32 p, u32 key, u32 prim) {
    u64 v = ((u64)key << 32) | prim;
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

// FreePipe §4.2: take a slot with fetch-and-add, write the fragment there. The counter keeps
// counting past the capacity: counter - capacity is the pixel's overflow.
struct ABufferOp {
  u32* counters;
  u64* slots;
  u32 capacity;
  __device__ void operator()(u32 p, u32 key, u32 prim) {
    u32 slot = atomicAdd(&counters[p], 1u);
    if (slot < capacity) slots[(u64)p * capacity + slot] = ((u64)key << 32) | prim;
  }
};

// The broken variant: the k-buffer's read-modify-write with no atomicity (Bavoil et al. 2007).
struct KBufferOp {
  u64* slots;
  u32 k;
  __device__ void operator()(u32 p, u32 key, u32 prim) {
    volatile u64* s = slots + (u64)p * k;
    u64 list[KMAX_LOCAL];
    for (u32 i = 0; i < k; i++) list[i] = s[i];
    u64 v = ((u64)key << 32) | prim;
    if (v >= list[k - 1]) return;  // not among the K nearest seen so far
    u32 i = k - 1;
    while (i > 0 && list[i - 1] > v) {
      list[i] = list[i - 1];
      i--;
    }
    list[i] = v;
    for (u32 j = 0; j < k; j++) s[j] = list[j];
  }
};

template <class Op>
__global__ void raster_kernel(const Tri* tris, u32 n, int width, int height, Op op) {
  u32 i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) scan(tris[i], width, height, op);
}

template <class W>
__global__ void fill_kernel(W* words, uint64_t n, W value) {
  uint64_t i = (uint64_t)blockIdx.x * blockDim.x + threadIdx.x;
  if (i < n) words[i] = value;
}

// FreePipe's post-sort: one thread per pixel, insertion sort in registers (local memory for
// long lists), written back in place.
__global__ void sort_kernel(const u32* counters, u64* slots, u32 pixels, u32 capacity) {
  u32 p = blockIdx.x * blockDim.x + threadIdx.x;
  if (p >= pixels) return;
  u32 n = lo(counters[p], capacity);
  u64* s = slots + (u64)p * capacity;
  if (n <= (u32)KMAX_LOCAL) {
    u64 list[KMAX_LOCAL];
    for (u32 i = 0; i < n; i++) {
      u64 v = s[i];
      u32 j = i;
      while (j > 0 && list[j - 1] > v) {
        list[j] = list[j - 1];
        j--;
      }
      list[j] = v;
    }
    for (u32 i = 0; i < n; i++) s[i] = list[i];
  } else {
    for (u32 i = 1; i < n; i++) {
      u64 v = s[i];
      u32 j = i;
      while (j > 0 && s[j - 1] > v) {
        s[j] = s[j - 1];
        j--;
      }
      s[j] = v;
    }
  }
}

// ---- host side: memory and timers that work on both builds ----

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

// ---- the triangle export ----

struct Scene {
  u32 width = 0, height = 0, mesh_triangles = 0;
  std::string scene_json;  // copied verbatim into each dump's "scene"
  std::vector<Tri> tris;
};

static u32 le32(const unsigned char* b) { return b[0] | b[1] << 8 | b[2] << 16 | (u32)b[3] << 24; }

static Scene read_scene(const char* path) {
  FILE* f = fopen(path, "rb");
  if (!f) { fprintf(stderr, "cannot open %s\n", path); exit(2); }
  unsigned char h[40];
  if (fread(h, 1, 40, f) != 40 || memcmp(h, "FRAGTRI1", 8) != 0 || le32(h + 8) != 1) {
    fprintf(stderr, "%s: not a version-1 fragsim triangle export\n", path);
    exit(2);
  }
  Scene s;
  s.width = le32(h + 12);
  s.height = le32(h + 16);
  if (le32(h + 20) != (u32)SUBPIXEL_BITS || le32(h + 36) != sizeof(Tri)) {
    fprintf(stderr, "%s: unexpected subpixel bits or record size\n", path);
    exit(2);
  }
  s.mesh_triangles = le32(h + 24);
  u32 count = le32(h + 28), json_len = le32(h + 32);
  u32 padded = (json_len + 7) / 8 * 8;
  std::vector<char> json(padded);
  s.tris.resize(count);
  if (fread(json.data(), 1, padded, f) != padded ||
      fread(s.tris.data(), sizeof(Tri), count, f) != count) {
    fprintf(stderr, "%s: truncated\n", path);
    exit(2);
  }
  fclose(f);
  s.scene_json.assign(json.data(), json_len);
  return s;
}

// ---- the dump format ----

static void write_file(const std::string& path, const void* data, size_t bytes) {
  FILE* f = fopen(path.c_str(), "wb");
  if (!f || fwrite(data, 1, bytes, f) != bytes || fclose(f) != 0) {
    fprintf(stderr, "cannot write %s\n", path.c_str());
    exit(2);
  }
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

// Writes OUT/<dir>/dump.json; the array files are written by the caller.
static void write_header(const std::string& dir, const Scene& s, const char* scheme, const char* variant,
                         const std::string& params, const char* word, const std::string& arrays,
                         const Timings& t, const std::string& device) {
  std::string json = "{\n  \"format\": \"fragsim-dump\",\n  \"version\": 1,\n";
  json += "  \"producer\": \"fragsim-cuda (" + std::string(variant) + ")\",\n";
  json += "  \"scene\": " + s.scene_json + ",\n";
  json += "  \"width\": " + std::to_string(s.width) + ",\n  \"height\": " + std::to_string(s.height) + ",\n";
  json += "  \"scheme\": \"" + std::string(scheme) + "\",\n" + params;
  json += "  \"word\": \"" + std::string(word) + "\",\n";
  json += "  \"arrays\": {" + arrays + "},\n";
  json += "  \"extra\": {\"backend\": \"cuda\", \"variant\": \"" + std::string(variant) + "\", \"device\": \"" +
          device + "\", \"timings\": " + timings_json(t) + "}\n}\n";
  write_file(dir + "/dump.json", json.data(), json.size());
}

static std::string array_json(const char* name, const char* file, const char* dtype, uint64_t a, uint64_t b) {
  std::string shape = b ? std::to_string(a) + ", " + std::to_string(b) : std::to_string(a);
  return "\"" + std::string(name) + "\": {\"file\": \"" + file + "\", \"dtype\": \"" + dtype +
         "\", \"shape\": [" + shape + "]}";
}

static void make_dir(const std::string& dir) {
  std::string cmd = "mkdir -p '" + dir + "'";
  if (system(cmd.c_str()) != 0) { fprintf(stderr, "cannot create %s\n", dir.c_str()); exit(2); }
}

// ---- main ----

static bool has(const std::string& list, const char* name) {
  return ("," + list + ",").find("," + std::string(name) + ",") != std::string::npos;
}

int main(int argc, char** argv) {
  if (argc < 3) {
    fprintf(stderr,
            "usage: %s TRIANGLES OUTDIR [--schemes mdts,mdts32,abuffer,kbuffer] [--k N] [--reps N] [--block N]\n",
            argv[0]);
    return 2;
  }
  const char* tri_path = argv[1];
  std::string out = argv[2];
  std::string schemes = "mdts,mdts32,abuffer,kbuffer";
  u32 k_arg = 0;
  int reps = 20, block = 64;  // FreePipe: 64 threads a block for rasterization
  for (int i = 3; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--schemes") schemes = argv[i + 1];
    else if (a == "--k") k_arg = (u32)atoi(argv[i + 1]);
    else if (a == "--reps") reps = std::max(1, atoi(argv[i + 1]));
    else if (a == "--block") block = std::max(32, atoi(argv[i + 1]));
    else { fprintf(stderr, "unknown option %s\n", a.c_str()); return 2; }
  }
  std::string device = "CPU emulation";
#ifdef __CUDACC__
  cudaDeviceProp prop;
  CK(cudaGetDeviceProperties(&prop, 0));
  device = prop.name;
#endif
  Scene s = read_scene(tri_path);
  const u32 n = (u32)s.tris.size();
  const uint64_t pixels = (uint64_t)s.width * s.height;
  Tri* d_tris = dev_alloc<Tri>(n);
  to_device(d_tris, s.tris.data(), n);

  // Counting pass: per-pixel depth complexity, to size K as fragsim's `--k auto` does.
  u32* d_counters = dev_alloc<u32>(pixels);
  LAUNCH(fill_kernel<u32>, pixels, 512, d_counters, pixels, 0u);
  Timer timer;
  timer.start();
  LAUNCH(raster_kernel<CountOp>, n, block, d_tris, n, (int)s.width, (int)s.height, CountOp{d_counters});
  float count_ms = timer.stop();
  std::vector<u32> counts(pixels);
  to_host(counts.data(), d_counters, pixels);
  u32 max_dc = 0;
  uint64_t fragments = 0;
  for (u32 c : counts) { max_dc = std::max(max_dc, c); fragments += c; }
  const u32 k = k_arg ? k_arg : std::max(max_dc, 1u);
  printf("SCENE {\"device\": \"%s\", \"triangles\": %u, \"mesh_triangles\": %u, \"width\": %u, \"height\": %u, "
         "\"fragments\": %llu, \"max_depth_complexity\": %u, \"k\": %u, \"count_pass_ms\": %.4f, \"scene\": %s}\n",
         device.c_str(), n, s.mesh_triangles, s.width, s.height, (unsigned long long)fragments, max_dc, k, count_ms,
         s.scene_json.c_str());

  auto report = [&](const char* name, const char* variant, const Timings& t, uint64_t bytes) {
    printf("RESULT {\"scheme\": \"%s\", \"variant\": \"%s\", \"k\": %u, \"memory_bytes\": %llu, \"timings\": %s}\n",
           name, variant, k, (unsigned long long)bytes, timings_json(t).c_str());
    fflush(stdout);
  };
  const std::string kparam = "  \"k\": " + std::to_string(k) + ",\n";

  // MDTS and the broken k-buffer share the layout: K u64 slots per pixel, empty = all ones.
  for (const char* name : {"mdts", "kbuffer"}) {
    if (!has(schemes, name)) continue;
    bool broken = strcmp(name, "kbuffer") == 0;
    if (broken && k > (u32)KMAX_LOCAL) { fprintf(stderr, "kbuffer: K > %d unsupported, skipped\n", KMAX_LOCAL); continue; }
    uint64_t words = pixels * k;
    u64* d_slots = dev_alloc<u64>(words);
    std::vector<float> init, raster, frame;
    for (int r = -1; r < reps; r++) {
      Timer ti, tr;
      ti.start();
      LAUNCH(fill_kernel<u64>, words, 512, d_slots, words, EMPTY64);
      float a = ti.stop();
      tr.start();
      if (broken) LAUNCH(raster_kernel<KBufferOp>, n, block, d_tris, n, (int)s.width, (int)s.height, KBufferOp{d_slots, k});
      else LAUNCH(raster_kernel<MdtsOp>, n, block, d_tris, n, (int)s.width, (int)s.height, MdtsOp{d_slots, k});
      float b = tr.stop();
      if (r >= 0) { init.push_back(a); raster.push_back(b); frame.push_back(a + b); }
    }
    Timings t;
    t.init_ms = median(init); t.raster_ms = median(raster); t.frame_ms = median(frame); t.reps = reps;
    std::vector<u64> host(words);
    to_host(host.data(), d_slots, words);
    std::string dir = out + "/" + name;
    make_dir(dir);
    write_file(dir + "/slots.u64", host.data(), words * 8);
    const char* variant = broken ? "kbuffer-nonatomic-rmw (deliberately broken)" : "atomicMin-u64";
    write_header(dir, s, "mdts", variant, kparam, "key<<32|prim",
                 array_json("slots", "slots.u64", "u64", pixels, k), t, device);
    report(name, variant, t, words * 8);
    dev_free(d_slots);
  }

  if (has(schemes, "mdts32")) {
    uint64_t words = pixels * k;
    u32* d_slots = dev_alloc<u32>(words);
    std::vector<float> init, raster, frame;
    for (int r = -1; r < reps; r++) {
      Timer ti, tr;
      ti.start();
      LAUNCH(fill_kernel<u32>, words, 512, d_slots, words, EMPTY32);
      float a = ti.stop();
      tr.start();
      LAUNCH(raster_kernel<Mdts32Op>, n, block, d_tris, n, (int)s.width, (int)s.height, Mdts32Op{d_slots, k});
      float b = tr.stop();
      if (r >= 0) { init.push_back(a); raster.push_back(b); frame.push_back(a + b); }
    }
    Timings t;
    t.init_ms = median(init); t.raster_ms = median(raster); t.frame_ms = median(frame); t.reps = reps;
    std::vector<u32> host(words);
    to_host(host.data(), d_slots, words);
    std::string dir = out + "/mdts32";
    make_dir(dir);
    write_file(dir + "/slots.u32", host.data(), words * 4);
    write_header(dir, s, "mdts32", "atomicMin-u32", kparam, "key", array_json("slots", "slots.u32", "u32", pixels, k),
                 t, device);
    report("mdts32", "atomicMin-u32", t, words * 4);
    dev_free(d_slots);
  }

  if (has(schemes, "abuffer")) {
    const u32 capacity = k;
    uint64_t words = pixels * capacity;
    u64* d_slots = dev_alloc<u64>(words);
    // Slots need no initialisation (only min(counter, capacity) of them are read); they are
    // filled once so that the dump's unused slots are deterministic.
    LAUNCH(fill_kernel<u64>, words, 512, d_slots, words, EMPTY64);
    std::vector<float> init, raster, sort, frame;
    for (int r = -1; r < reps; r++) {
      Timer ti, tr, ts;
      ti.start();
      LAUNCH(fill_kernel<u32>, pixels, 512, d_counters, pixels, 0u);
      float a = ti.stop();
      tr.start();
      LAUNCH(raster_kernel<ABufferOp>, n, block, d_tris, n, (int)s.width, (int)s.height,
             ABufferOp{d_counters, d_slots, capacity});
      float b = tr.stop();
      ts.start();
      LAUNCH(sort_kernel, pixels, 64, d_counters, d_slots, (u32)pixels, capacity);
      float c = ts.stop();
      if (r >= 0) { init.push_back(a); raster.push_back(b); sort.push_back(c); frame.push_back(a + b + c); }
    }
    Timings t;
    t.init_ms = median(init); t.raster_ms = median(raster); t.sort_ms = median(sort); t.frame_ms = median(frame);
    t.reps = reps;
    std::vector<u64> host(words);
    std::vector<u32> host_counters(pixels);
    to_host(host.data(), d_slots, words);
    to_host(host_counters.data(), d_counters, pixels);
    std::string dir = out + "/abuffer";
    make_dir(dir);
    write_file(dir + "/slots.u64", host.data(), words * 8);
    write_file(dir + "/counters.u32", host_counters.data(), pixels * 4);
    std::string params = "  \"capacity\": " + std::to_string(capacity) + ",\n  \"sorted\": true,\n";
    write_header(dir, s, "abuffer", "atomicAdd+insertion-sort", params, "key<<32|prim",
                 array_json("counters", "counters.u32", "u32", pixels, 0) + ", " +
                     array_json("slots", "slots.u64", "u64", pixels, capacity),
                 t, device);
    report("abuffer", "atomicAdd+insertion-sort", t, words * 8 + pixels * 4);
    dev_free(d_slots);
  }
  dev_free(d_counters);
  dev_free(d_tris);
  return 0;
}
