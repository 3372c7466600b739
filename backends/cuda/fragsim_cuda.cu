// fragsim_cuda: FreePipe's multi-fragment schemes (Liu et al., I3D 2010, §3-4) on a CUDA GPU,
// checked against fragsim's oracle through the dump format (docs/dump-format.md). Mirrors the
// command line's `render` (crates/cli/src/render.rs): read the scene, size K, run each scheme,
// report; the rest of the backend mirrors the Rust tree file for file (README.md lists the pairs).
//
// Input: fragsim's triangle export (`fragsim export-scene`): the screen triangles after fragsim's
// vertex stage, clipping, snapping and orientation. This program is FreePipe's rasterizer from
// there on: one thread per screen triangle (executors/parallel.cuh), the exact scan
// (raster/pipeline/scan.cuh), the scheme's step on every fragment.
//
// Schemes (each writes a dump directory OUT/<name>/):
//   mdts      u64 words key<<32|prim, K slots per pixel, atomicMin walk (schemes/mdts.cuh)
//   mdts32    u32 depth keys, K slots, atomicMin walk (FreePipe Table 1 as printed; the same file)
//   abuffer   u32 counter per pixel (atomicAdd) + K fixed slots of u64 words, then a per-pixel
//             insertion-sort kernel (schemes/abuffer.cuh); dumped with "sorted": true
//   kbuffer   DELIBERATELY BROKEN: non-atomic read-all / insert / write-all (schemes/kbuffer.cuh)
// K defaults to the scene's maximum depth complexity, measured by a counting pass on the GPU
// (depth_count.cuh).
//
// Build: make (nvcc -O3 -arch=sm_90 -fmad=false -I. fragsim_cuda.cu). The same files build
// without CUDA as a serial CPU emulation (make emulate: g++ -x c++ -DFRAGSIM_EMULATE), which runs
// the identical scan and scheme code one thread at a time: used to check the code against fragsim
// before spending GPU time.

#include "depth_count.cuh"
#include "device.cuh"
#include "executors/frame.cuh"
#include "memory/mod.cuh"
#include "oracle/triangles.cuh"
#include "schemes/abuffer.cuh"
#include "schemes/kbuffer.cuh"
#include "schemes/mdts.cuh"

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
  std::string schemes = "mdts,mdts32,abuffer,kbuffer";
  u32 k_arg = 0;
  Job job;
  job.out = argv[2];
  for (int i = 3; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--schemes") schemes = argv[i + 1];
    else if (a == "--k") k_arg = (u32)atoi(argv[i + 1]);
    else if (a == "--reps") job.reps = std::max(1, atoi(argv[i + 1]));
    else if (a == "--block") job.block = std::max(32, atoi(argv[i + 1]));
    else { fprintf(stderr, "unknown option %s\n", a.c_str()); return 2; }
  }
  job.device = "CPU emulation";
#ifdef __CUDACC__
  cudaDeviceProp prop;
  CK(cudaGetDeviceProperties(&prop, 0));
  job.device = prop.name;
#endif
  const Scene s = read_scene(tri_path);
  job.scene = &s;
  job.n = (u32)s.tris.size();
  job.pixels = (uint64_t)s.width * s.height;
  Tri* d_tris = dev_alloc<Tri>(job.n);
  to_device(d_tris, s.tris.data(), job.n);
  job.d_tris = d_tris;
  job.d_counters = dev_alloc<u32>(job.pixels);

  // Counting pass: per-pixel depth complexity, to size K as fragsim's `--k auto` does.
  const DepthCounts counts = depth_count(job);
  job.k = k_arg ? k_arg : std::max(counts.max, 1u);
  printf("SCENE {\"device\": \"%s\", \"triangles\": %u, \"mesh_triangles\": %u, \"width\": %u, \"height\": %u, "
         "\"fragments\": %llu, \"max_depth_complexity\": %u, \"k\": %u, \"count_pass_ms\": %.4f, \"scene\": %s}\n",
         job.device.c_str(), job.n, s.mesh_triangles, s.width, s.height, (unsigned long long)counts.fragments,
         counts.max, job.k, counts.ms, s.scene_json.c_str());

  // The order of the runs is fixed, whatever the order of --schemes.
  if (has(schemes, "mdts")) run_mdts(job);
  if (has(schemes, "kbuffer")) run_kbuffer(job);
  if (has(schemes, "mdts32")) run_mdts32(job);
  if (has(schemes, "abuffer")) run_abuffer(job);
  dev_free(job.d_counters);
  dev_free(d_tris);
  return 0;
}
