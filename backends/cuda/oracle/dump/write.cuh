// Mirrors crates/dump/src/write.rs: writes a scheme's memory as a dump directory
// (docs/dump-format.md): `dump.json`, the header naming the scene, the scheme, its parameters, the
// word encoding and the array files, plus the raw little-endian arrays themselves.
#pragma once

#include <filesystem>

#include "device.cuh"
#include "executors/frame.cuh"
#include "oracle/triangles.cuh"

static void write_file(const std::string& path, const void* data, size_t bytes) {
  FILE* f = fopen(path.c_str(), "wb");
  if (!f) fail(STATUS_INPUT, "cannot write " + path);
  const bool written = fwrite(data, 1, bytes, f) == bytes;
  if (fclose(f) != 0 || !written) fail(STATUS_INPUT, "cannot write " + path);
}

// The header's "k" parameter line.
static std::string k_param(u32 k) { return "  \"k\": " + std::to_string(k) + ",\n"; }

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
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) fail(STATUS_INPUT, "cannot create " + dir + ": " + error.message());
}
