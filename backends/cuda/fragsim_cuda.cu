// fragsim_cuda: FreePipe's multi-fragment schemes (Liu et al., I3D 2010, §3-4) on a CUDA GPU,
// checked against fragsim's oracle through the dump format (docs/dump-format.md). Mirrors the
// command line's `render` (crates/cli/src/render.rs): read the scene, size K, run each scheme,
// report; the rest of the backend mirrors the Rust tree file for file (README.md lists the pairs).
// One case per process, or many in one (`--serve`, serve.cuh: one CUDA context for all of them,
// `--client` hands it a case); both run a case through run_request.
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
#include "serve.cuh"

static bool has(const std::string& list, const char* name) {
  return ("," + list + ",").find("," + std::string(name) + ",") != std::string::npos;
}

static const char* USAGE =
    "usage: fragsim_cuda TRIANGLES OUTDIR [--schemes mdts,mdts32,abuffer,kbuffer] [--k N] [--reps N] [--block N]\n"
    "       fragsim_cuda --serve DIR                 (one process, one CUDA context, many cases: serve.cuh)\n"
    "       fragsim_cuda --client DIR [--timeout SECONDS] TRIANGLES OUTDIR [options]";

// One case: the scene, where its dumps go, and the command line's options.
struct Request {
  std::string triangles, out;
  std::string schemes = "mdts,mdts32,abuffer,kbuffer";
  u32 k = 0;  // 0: the counting pass's maximum depth complexity
  int reps = 20, block = 64;
};

static Request parse_request(const std::vector<std::string>& args) {
  if (args.size() < 2) fail(STATUS_INPUT, USAGE);
  Request r;
  r.triangles = args[0];
  r.out = args[1];
  for (size_t i = 2; i < args.size(); i += 2) {
    const std::string& a = args[i];
    if (i + 1 == args.size()) fail(STATUS_INPUT, "option " + a + " needs a value");
    const char* value = args[i + 1].c_str();
    if (a == "--schemes") r.schemes = value;
    else if (a == "--k") r.k = (u32)atoi(value);
    else if (a == "--reps") r.reps = std::max(1, atoi(value));
    else if (a == "--block") r.block = std::max(32, atoi(value));
    else fail(STATUS_INPUT, "unknown option " + a);
  }
  return r;
}

// Runs one case: what a command line runs, and what the server runs for each request. Every
// device array is freed on return, a failure included (CaseError).
static void run_request(const Request& r, const std::string& device) {
  const Scene s = read_scene(r.triangles.c_str());
  Job job;
  job.out = r.out;
  job.reps = r.reps;
  job.block = r.block;
  job.device = device;
  job.scene = &s;
  job.n = (u32)s.tris.size();
  job.pixels = (uint64_t)s.width * s.height;
  const DeviceArray<Tri> tris(job.n);
  to_device(tris.get(), s.tris.data(), job.n);
  job.d_tris = tris.get();
  const DeviceArray<u32> counters(job.pixels);
  job.d_counters = counters.get();

  // Counting pass: per-pixel depth complexity, to size K as fragsim's `--k auto` does.
  const DepthCounts counts = depth_count(job);
  job.k = r.k ? r.k : std::max(counts.max, 1u);
  printf("SCENE {\"device\": \"%s\", \"triangles\": %u, \"mesh_triangles\": %u, \"width\": %u, \"height\": %u, "
         "\"fragments\": %llu, \"max_depth_complexity\": %u, \"k\": %u, \"count_pass_ms\": %.4f, \"scene\": %s}\n",
         job.device.c_str(), job.n, s.mesh_triangles, s.width, s.height, (unsigned long long)counts.fragments,
         counts.max, job.k, counts.ms, s.scene_json.c_str());

  // The order of the runs is fixed, whatever the order of --schemes.
  if (has(r.schemes, "mdts")) run_mdts(job);
  if (has(r.schemes, "kbuffer")) run_kbuffer(job);
  if (has(r.schemes, "mdts32")) run_mdts32(job);
  if (has(r.schemes, "abuffer")) run_abuffer(job);
  fflush(stdout);
}

// The device's name for the dumps; on CUDA the first call into the runtime, which creates the
// context (about a second on an H200: what the server pays once instead of once a case).
static std::string device_name() {
#ifdef __CUDACC__
  cudaDeviceProp prop;
  CK(cudaGetDeviceProperties(&prop, 0));
  return prop.name;
#else
  return "CPU emulation";
#endif
}

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (!args.empty() && args[0] == "--client") return client(args);
    if (!args.empty() && args[0] == "--serve") {
      if (args.size() != 2) fail(STATUS_INPUT, USAGE);
      const std::string device = device_name();
      return serve(args[1], [&](const std::vector<std::string>& case_args) {
        run_request(parse_request(case_args), device);
      });
    }
    const Request request = parse_request(args);  // before the device: a usage error costs no context
    run_request(request, device_name());
    return 0;
  } catch (const CaseError& e) {
    fprintf(stderr, "fragsim_cuda: %s\n", e.what());
    return e.status;
  }
}
