// Mirrors crates/raster/src/pipeline.rs: the fixed-point grid and the screen triangle. The vertex
// stage (transform, clipping, snapping, orientation) is not here: fragsim ran it once and the
// triangle export carries its result, so that this backend tests the scan and the atomics alone.
#pragma once

#include "device.cuh"

constexpr int SUBPIXEL_BITS = 8;
constexpr int64_t ONE = 1 << SUBPIXEL_BITS, HALF = ONE / 2;

// pipeline.rs's ScreenTriangle as one record of the triangle export (56 bytes, little-endian,
// docs/dump-format.md).
struct Tri {
  u32 prim;
  int32_t xy[6];  // x0 y0 x1 y1 x2 y2 in 1/256 pixel, y down, oriented: doubled area > 0
  u32 reserved;
  double z[3];    // window depth z/w of each vertex
};
static_assert(sizeof(Tri) == 56, "triangle record is 56 bytes");
