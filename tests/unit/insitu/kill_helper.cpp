// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/kill_helper.cpp -- a "solver" that renders steps until it is killed.
// Usage: penumbra_insitu_kill_helper OUTPUT_DIR FIRST_CYCLE STEPS IF_EXISTS [STORE_DIR] [moving] [async]
// With STORE_DIR the run also keeps its compressed history there (windows of 8 steps); with
// "moving" its points move every step (fixtures::swirl by 0.01 per cycle) under one topology;
// with "async" its steps render on Penumbra's worker thread.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fixtures/meshes.h"
#include "penumbra/penumbra.h"

int main(int argc, char** argv) {
  if (argc < 5 || argc > 8) return 2;
  bool moving = false, async = false;
  std::string store;
  for (int a = 5; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "moving") moving = true;
    else if (arg == "async") async = true;
    else store = R"(, "store": {"directory": ")" + arg + R"(", "window": 8})";
  }
  const std::string config = R"({"output": {"directory": ")" + std::string(argv[1]) + R"(", "if_exists": ")" +
                             argv[4] + R"("}, "image": {"width": 32, "height": 32},
      "cameras": {"phi": [0, 120, 240], "theta": [20]}, "fields": [{"name": "T"}, {"name": "T2"}])" + store +
                             (async ? R"(, "async": true)" : "") + "}";
  pnb_context ctx = nullptr;
  if (pnb_create(config.c_str(), &ctx) != PNB_OK) {
    std::fprintf(stderr, "%s\n", pnb_last_error(nullptr));
    return 1;
  }
  const auto base = penumbra::fixtures::block(penumbra::fixtures::BlockCells::tets, 6, 6, 6, {0, 0, 0}, {1, 1, 1});
  auto mesh = base;
  pnb_mesh_desc m{sizeof(pnb_mesh_desc), mesh.xyz.data(), static_cast<int64_t>(mesh.point_count()), 0, PNB_FLOAT64,
                  mesh.connectivity.data(), static_cast<int64_t>(mesh.connectivity.size()), mesh.offsets.data(),
                  PNB_INT64, mesh.types.data(), static_cast<int64_t>(mesh.types.size()), 1};
  if (pnb_publish_mesh(ctx, &m, PNB_BORROW) != PNB_OK) {
    std::fprintf(stderr, "%s\n", pnb_last_error(ctx));
    return 1;
  }
  const long first = std::atol(argv[2]), steps = std::atol(argv[3]);
  for (long c = first; c < first + steps; ++c) {
    const double t = 0.01 * static_cast<double>(c);
    if (moving) {
      mesh = base;
      penumbra::fixtures::swirl(mesh, {0.5, 0.5, 0}, 0.6, t);
      m.points = mesh.xyz.data();
      if (pnb_publish_mesh(ctx, &m, PNB_BORROW) != PNB_OK) {
        std::fprintf(stderr, "%s\n", pnb_last_error(ctx));
        return 1;
      }
    }
    const auto values = penumbra::fixtures::sample(mesh, [t](double x, double y, double z) {
      return std::sin(6 * x + t) * std::cos(4 * y) + z;
    });
    pnb_field_desc f{sizeof(pnb_field_desc), "T", PNB_POINT_FIELD, values.data(), static_cast<int64_t>(values.size()), 1, 0, PNB_FLOAT64};
    pnb_field_desc f2 = f;
    f2.name = "T2";
    if (pnb_publish_field(ctx, &f, PNB_BORROW) != PNB_OK || pnb_publish_field(ctx, &f2, PNB_BORROW) != PNB_OK ||
        pnb_execute(ctx, t, c) != PNB_OK) {
      std::fprintf(stderr, "%s\n", pnb_last_error(ctx));
      return 1;
    }
  }
  pnb_destroy(ctx);
  return 0;
}
