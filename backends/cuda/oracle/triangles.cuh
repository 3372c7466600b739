// Mirrors crates/dump/src/triangles.rs: reads the FRAGTRI1 triangle export that
// `fragsim export-scene` writes (docs/dump-format.md): the screen triangles after fragsim's vertex
// stage, and the scene's JSON, which every dump copies so that `fragsim compare` can rebuild the
// oracle from it.
#pragma once

#include <memory>

#include "device.cuh"
#include "raster/pipeline.cuh"

struct Scene {
  u32 width = 0, height = 0, mesh_triangles = 0;
  std::string scene_json;  // copied verbatim into each dump's "scene"
  std::vector<Tri> tris;
};

static u32 le32(const unsigned char* b) { return b[0] | b[1] << 8 | b[2] << 16 | (u32)b[3] << 24; }

static Scene read_scene(const char* path) {
  FILE* f = fopen(path, "rb");
  if (!f) fail(STATUS_INPUT, std::string("cannot open ") + path);
  unsigned char h[40];
  // Closes the file on every way out, a failure included (the server reads case after case).
  std::unique_ptr<FILE, int (*)(FILE*)> closer(f, fclose);
  if (fread(h, 1, 40, f) != 40 || memcmp(h, "FRAGTRI1", 8) != 0 || le32(h + 8) != 1)
    fail(STATUS_INPUT, std::string(path) + ": not a version-1 fragsim triangle export");
  Scene s;
  s.width = le32(h + 12);
  s.height = le32(h + 16);
  if (le32(h + 20) != (u32)SUBPIXEL_BITS || le32(h + 36) != sizeof(Tri))
    fail(STATUS_INPUT, std::string(path) + ": unexpected subpixel bits or record size");
  s.mesh_triangles = le32(h + 24);
  u32 count = le32(h + 28), json_len = le32(h + 32);
  u32 padded = (json_len + 7) / 8 * 8;
  std::vector<char> json(padded);
  s.tris.resize(count);
  if (fread(json.data(), 1, padded, f) != padded ||
      fread(s.tris.data(), sizeof(Tri), count, f) != count)
    fail(STATUS_INPUT, std::string(path) + ": truncated");
  s.scene_json.assign(json.data(), json_len);
  return s;
}
