// Mirrors crates/raster/src/pipeline/scan.rs (View::scan_in, bounding_box, pixel_span, edge,
// is_top_left): the exact scan of docs/semantics.md §4-6. The bounding box from the snapped
// vertices, clamped to the viewport; the three edge functions in 64-bit integers with the top-left
// rule; depth (E0*z0 + E1*z1 + E2*z2) / area in f64, evaluated left to right, rounded once to f32,
// and the depth key. Every arithmetic step that rounds is an explicit round-to-nearest intrinsic,
// so that nvcc cannot contract it into an FMA and change the last bit.
#pragma once

#include "device.cuh"
#include "raster/pipeline.cuh"

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
