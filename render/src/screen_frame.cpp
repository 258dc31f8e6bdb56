// SPDX-License-Identifier: BSD-3-Clause
// render/src/screen_frame.cpp -- screen-space points and boundary-face bins of one frame
#include "screen_frame.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "penumbra/core/thread_pool.h"

namespace penumbra::render::detail {

ScreenBasis screen_basis(const Camera& camera) {
  const Camera::Frame f = camera.frame();
  ScreenBasis basis;
  basis.eye = camera.eye;
  basis.forward = f.forward;
  basis.right = f.right;
  basis.down = -f.up;  // right x down = forward, as RayFrame's u x v = d
  return basis;
}

std::vector<ScreenPoint> project_to_screen(const ScreenBasis& basis, const std::vector<Vec3d>& pts,
                                          const std::int32_t* point_ids, const float* scalars, const Bounds& bounds) {
  std::vector<ScreenPoint> out(pts.size());
  // A point at (or behind) the eye plane has no screen position; a margin of 1e-9 of the mesh
  // size keeps 1/z finite and well away from overflow.
  const double min_depth = 1e-9 * std::max(bounds.diagonal(), 1e-300);
  std::atomic<bool> all_in_front{true};
  parallel_for(pts.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    bool ok = true;
    for (std::size_t i = b; i < e; ++i) {
      ok = ok && dot(pts[i] - basis.eye, basis.forward) > min_depth;
      out[i] = basis.project(pts[i], scalars[point_ids[i]]);
    }
    if (!ok) all_in_front = false;
  });
  if (!all_in_front) out.clear();
  return out;
}

ScreenBins bin_boundary_faces(const std::vector<BoundaryTriangle>& triangles, const std::vector<ScreenPoint>& screen,
                              const Camera& camera, int tile) {
  const int tiles_x = (camera.width + tile - 1) / tile, tiles_y = (camera.height + tile - 1) / tile;
  // Pixel (px, py) looks through image-plane point X = (2 (px + 0.5) / W - 1) half_w, and
  // likewise for Y (down the screen): invert that for each face's corners.
  const Camera::Frame frame = camera.frame();
  const double half_h = frame.half_height, half_w = frame.half_width;
  const double to_px_x = 0.5 * camera.width / half_w, offset_x = 0.5 * camera.width - 0.5;
  const double to_px_y = 0.5 * camera.height / half_h, offset_y = 0.5 * camera.height - 0.5;
  struct TileRange {
    int x0, x1, y0, y1;  // inclusive; x0 > x1 when off screen or never entered
  };
  constexpr TileRange kNowhere{0, -1, 0, -1};
  std::vector<TileRange> ranges(triangles.size());
  parallel_for(triangles.size(), 1 << 12, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      TileRange& r = ranges[i];
      // A ray enters only through a face it sees clockwise: every edge value e(v_j, v_j+1)
      // negative. The three sum to twice the face's signed area on the image plane whatever the
      // ray, so a face whose area is clearly positive (anticlockwise, facing away) can never be
      // entered and is listed nowhere: about half of a closed surface. A face seen nearly edge
      // on, within a margin far above the rounding of the edge values, is kept.
      const ScreenPoint& a = screen[static_cast<std::size_t>(triangles[i].v[0])];
      const ScreenPoint& b1 = screen[static_cast<std::size_t>(triangles[i].v[1])];
      const ScreenPoint& c = screen[static_cast<std::size_t>(triangles[i].v[2])];
      const double area2 = (b1.x - a.x) * (c.y - a.y) - (b1.y - a.y) * (c.x - a.x);
      const double scale = a.x * a.x + a.y * a.y + b1.x * b1.x + b1.y * b1.y + c.x * c.x + c.y * c.y;
      if (area2 > 1e-9 * scale) {
        r = kNowhere;
        continue;
      }
      double lo_x = HUGE_VAL, hi_x = -HUGE_VAL, lo_y = HUGE_VAL, hi_y = -HUGE_VAL;
      for (const ScreenPoint* p : {&a, &b1, &c}) {
        const double px = p->x * to_px_x + offset_x, py = p->y * to_px_y + offset_y;
        lo_x = std::min(lo_x, px);
        hi_x = std::max(hi_x, px);
        lo_y = std::min(lo_y, py);
        hi_y = std::max(hi_y, py);
      }
      // Only pixel centres matter: a ray passes through pixel (px, py) exactly, so a face is
      // listed in the tiles of the pixel centres its bounding box holds, and a face smaller
      // than a pixel that holds none (most faces of a finely meshed surface) is listed nowhere.
      // The margin of 1/256 pixel covers the rounding of this estimate (about 1e-13 pixel; the
      // entry test itself is exact).
      constexpr double kMargin = 1.0 / 256;
      auto first_centre = [](double lo, int count) {
        return static_cast<int>(std::clamp(std::ceil(lo - kMargin), 0.0, static_cast<double>(count)));
      };
      auto last_centre = [](double hi, int count) {
        return static_cast<int>(std::clamp(std::floor(hi + kMargin), -1.0, static_cast<double>(count - 1)));
      };
      const int cx0 = first_centre(lo_x, camera.width), cx1 = last_centre(hi_x, camera.width);
      const int cy0 = first_centre(lo_y, camera.height), cy1 = last_centre(hi_y, camera.height);
      if (cx0 > cx1 || cy0 > cy1) {
        r = kNowhere;
        continue;
      }
      r = {cx0 / tile, cx1 / tile, cy0 / tile, cy1 / tile};
    }
  });
  ScreenBins bins;
  bins.start.assign(static_cast<std::size_t>(tiles_x) * tiles_y + 1, 0);
  for (const TileRange& r : ranges)
    for (int ty = r.y0; ty <= r.y1; ++ty)
      for (int tx = r.x0; tx <= r.x1; ++tx) ++bins.start[static_cast<std::size_t>(ty) * tiles_x + tx + 1];
  for (std::size_t i = 1; i < bins.start.size(); ++i) bins.start[i] += bins.start[i - 1];
  bins.faces.resize(static_cast<std::size_t>(bins.start.back()));
  std::vector<std::int32_t> fill(bins.start.begin(), bins.start.end() - 1);
  for (std::size_t i = 0; i < ranges.size(); ++i)
    for (int ty = ranges[i].y0; ty <= ranges[i].y1; ++ty)
      for (int tx = ranges[i].x0; tx <= ranges[i].x1; ++tx)
        bins.faces[static_cast<std::size_t>(fill[static_cast<std::size_t>(ty) * tiles_x + tx]++)] =
            static_cast<std::int32_t>(i);
  return bins;
}

}  // namespace penumbra::render::detail
