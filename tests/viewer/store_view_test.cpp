// SPDX-License-Identifier: BSD-3-Clause
// tests/viewer/store_view_test.cpp -- views rendered from a run's store against the images the
// run wrote, the queue in front of them, and their HTTP interface
#include <gtest/gtest.h>
#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <string>
#include <thread>
#include <vector>

#include "context.h"
#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "penumbra/render/image.h"
#include "render_queue.h"
#include "render_routes.h"
#include "store_view.h"
#include "test_util.h"
#include "view_server.h"

namespace penumbra::viewer {
namespace {

namespace fs = std::filesystem;

using insitu::testing::TempDir;

// A field moving through the block over time.
std::vector<double> wave(const fixtures::OwnedMesh& mesh, double t) {
  return fixtures::sample(mesh, [t](double x, double y, double z) { return x + 0.3 * std::sin(t + 2 * y) + 0.5 * z; });
}

// The run's config: two orbit cameras, a store whose values are within 1e-6 of the field's (so
// that a stored view differs from the run's image by the rounding of a pixel at most), and
// `lighting` (a JSON member, or empty).
std::string run_config(const fs::path& dir, const std::string& lighting) {
  return R"({"output": {"directory": ")" + (dir / "db").string() + R"("}, "image": {"width": 48, "height": 40},
             "cameras": {"phi": [0, 90], "theta": [30]},
             "fields": [{"name": "T", "transfer_function": {
                "colors": [[0, 0.1, 0.2, 0.9], [1, 0.9, 0.3, 0.1]], "opacities": [[0, 0.5], [1, 4]]}}],
             "store": {"directory": ")" + (dir / "store").string() + R"(", "window": 8,
                       "error_bound": {"absolute": 1e-6}})" + lighting + "}";
}

// Runs 6 steps of the wave on a tet block, writing the database and the store.
void run(const fs::path& dir, const std::string& config) {
  const auto mesh = fixtures::block(fixtures::BlockCells::tets, 6, 5, 4, {0, 0, 0}, {1.2, 1, 0.8});
  insitu::Context ctx(insitu::parse_config(config));
  ctx.publish_mesh(mesh.view());
  for (int step = 0; step < 6; ++step) {
    const auto v = wave(mesh, 0.4 * step);
    ctx.publish_field(fixtures::point_field("T", v), false);
    ctx.execute(0.4 * step, step);
  }
  ctx.finalize();
}

// The run's image of `cycle` from the camera at `phi` (theta 30).
std::vector<unsigned char> run_image(const fs::path& dir, int cycle, int phi) {
  char prefix[32];
  std::snprintf(prefix, sizeof prefix, "c%06d_", cycle);
  for (const auto& e : fs::recursive_directory_iterator(dir / "db")) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) == 0 && name.find("phi" + std::to_string(phi) + "_") != std::string::npos) {
      int w = 0, h = 0;
      return render::read_png_rgb(e.path().string(), w, h);
    }
  }
  ADD_FAILURE() << "no image of cycle " << cycle << " at phi " << phi << " in " << dir / "db";
  return {};
}

std::vector<unsigned char> decoded(const std::vector<unsigned char>& png, const fs::path& scratch) {
  const fs::path file = scratch / "decoded.png";
  std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(png.data()), png.size());
  int w = 0, h = 0;
  return render::read_png_rgb(file.string(), w, h);
}

struct StoredRun {
  TempDir tmp;
  std::string config;
  explicit StoredRun(const std::string& lighting = "") : config(run_config(dir(), lighting)) { run(dir(), config); }
  fs::path dir() const { return tmp.path(); }
  std::string store() const { return (dir() / "store").string(); }
};

ViewRequest at(std::size_t step, double phi, double theta = 30) {
  ViewRequest r;
  r.step = step;
  r.phi = phi;
  r.theta = theta;
  return r;
}

TEST(StoreView, StoredCamerasGiveTheRunsImages) {
  const StoredRun r;
  // The config the store keeps (config.json, written by the run) is the run's.
  StoreView view(r.store(), "");
  ASSERT_EQ(view.info().times.size(), 6u);
  EXPECT_EQ(view.info().fields, std::vector<std::string>{"T"});
  EXPECT_EQ(view.info().lighting, "none");
  for (int step : {0, 3, 5})
    for (int phi : {0, 90}) {
      const auto png = view.render(at(step, phi)).png;
      // Stored values within 1e-6 of the run's: a pixel may round to the next level, no more.
      EXPECT_LT(render::rms_difference_pct(decoded(png, r.dir()), run_image(r.dir(), step, phi)), 0.2)
          << "step " << step << " phi " << phi;
    }
}

TEST(StoreView, TheLightVolumeIsSolvedAgainAsTheRunSolvedIt) {
  const StoredRun r(R"(, "lighting": {"model": "light-volume", "level0_resolution": 24,
                       "lights": [{"type": "directional", "direction": [-1, -0.5, -1]}]})");
  StoreView view(r.store(), r.config);
  EXPECT_EQ(view.info().lighting, "light-volume");
  // Out of order: each step's light starts from another step's solution and converges alike.
  for (int step : {4, 1, 5}) {
    const RenderedView v = view.render(at(step, 90));
    EXPECT_TRUE(v.light_converged);
    // Both converged to the light volume's tolerance from different starts.
    EXPECT_LT(render::rms_difference_pct(decoded(v.png, r.dir()), run_image(r.dir(), step, 90)), 0.5)
        << "step " << step;
  }
  ViewRequest unlit = at(5, 90);
  unlit.lit = false;
  EXPECT_GT(render::rms_difference_pct(decoded(view.render(unlit).png, r.dir()), run_image(r.dir(), 5, 90)), 0.5);
}

// A mesh whose points move, lit by occlusion: each step's coordinates are read back, the
// occlusion made again for them, and the stored cameras still give the run's images.
TEST(StoreView, MovingPointsWithOcclusionFollowEachStep) {
  TempDir tmp;
  const fs::path dir = tmp.path();
  const std::string config = run_config(dir, R"(, "lighting": {"model": "occlusion", "occlusion": {"grid": 24}})");
  {
    auto mesh = fixtures::block(fixtures::BlockCells::tets, 6, 5, 4, {0, 0, 0}, {1.2, 1, 0.8});
    insitu::Context ctx(insitu::parse_config(config));
    for (int step = 0; step < 4; ++step) {
      if (step > 0) fixtures::swirl(mesh, {0.6, 0.5, 0}, 0.6, 0.05);
      ctx.publish_mesh(mesh.view());
      const auto v = wave(mesh, 0.4 * step);
      ctx.publish_field(fixtures::point_field("T", v), false);
      ctx.execute(0.4 * step, step);
    }
    ctx.finalize();
  }
  StoreView view((dir / "store").string(), config);
  for (int step : {0, 3, 1}) {
    const auto png = view.render(at(step, 90)).png;
    // Coordinates kept within 1/64 of the thinnest altitude: a level or two on silhouettes.
    EXPECT_LT(render::rms_difference_pct(decoded(png, dir), run_image(dir, step, 90)), 0.5) << "step " << step;
  }
}

TEST(StoreView, FreeCameraZoomAndTransferFunction) {
  const StoredRun r;
  StoreView view(r.store(), r.config);
  const auto stored = decoded(view.render(at(2, 0)).png, r.dir());
  const auto between = decoded(view.render(at(2, 45, 10)).png, r.dir());
  EXPECT_GT(render::rms_difference_pct(stored, between), 1.0);
  ViewRequest closer = at(2, 0);
  closer.zoom = 2;
  EXPECT_GT(render::rms_difference_pct(stored, decoded(view.render(closer).png, r.dir())), 1.0);
  // A transparent transfer function leaves the background (white) everywhere.
  ViewRequest clear = at(2, 0);
  clear.transfer_function = render::TransferFunction{{{0, 1, 0, 0}}, {{0, 0}}};
  const auto blank = decoded(view.render(clear).png, r.dir());
  for (unsigned char c : blank) ASSERT_EQ(c, 255);
}

TEST(StoreView, BadRequestsAndStoresAreClearErrors) {
  const StoredRun r;
  StoreView view(r.store(), r.config);
  EXPECT_THROW(view.render(at(6, 0)), Error);
  EXPECT_THROW(view.render(at(0, std::nan(""))), Error);
  EXPECT_THROW(view.render(at(0, 0, 95)), Error);
  ViewRequest field = at(0, 0);
  field.field = 1;
  EXPECT_THROW(view.render(field), Error);
  ViewRequest bad_tf = at(0, 0);
  bad_tf.transfer_function = render::TransferFunction{{{1, 1, 0, 0}, {0, 1, 0, 0}}, {{0, -1}}};
  EXPECT_THROW(view.render(bad_tf), Error);
  EXPECT_NO_THROW(view.render(at(0, 0)));  // still serving after the refusals
  EXPECT_THROW(StoreView((r.dir() / "nowhere").string(), r.config), Error);
  fs::remove(r.dir() / "store" / "config.json");
  try {
    StoreView kept(r.store(), "");
    ADD_FAILURE() << "a store without config.json was opened without a config";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--config"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(StoreView((r.dir() / "store" / "segment-000").string(), r.config));
  std::string other = r.config;
  other.replace(other.find(R"("name": "T")"), 11, R"("name": "P")");
  EXPECT_THROW(StoreView(r.store(), other), Error);
}

TEST(RenderQueue, SupersedesAPagesWaitingRequestAndRefusesBeyondItsBound) {
  const StoredRun r;
  RenderQueue queue(std::make_unique<StoreView>(r.store(), r.config), 2);
  // While the worker renders the first, the same page's second request waits and the third
  // replaces it.
  auto first = queue.submit("a", at(0, 0));
  auto second = queue.submit("b", at(1, 0));
  auto third = queue.submit("b", at(2, 0));
  EXPECT_EQ(second.get().outcome, RenderResult::Outcome::superseded);
  EXPECT_EQ(third.get().outcome, RenderResult::Outcome::rendered);
  EXPECT_EQ(first.get().outcome, RenderResult::Outcome::rendered);
  // Four pages at once against room for two waiting: at least one is told the queue is full.
  std::vector<std::future<RenderResult>> burst;
  for (const char* page : {"p", "q", "s", "t"}) burst.push_back(queue.submit(page, at(3, 90)));
  int busy = 0, rendered = 0;
  for (auto& f : burst) {
    const RenderResult res = f.get();
    busy += res.outcome == RenderResult::Outcome::busy;
    rendered += res.outcome == RenderResult::Outcome::rendered;
  }
  EXPECT_GE(busy, 1);
  EXPECT_EQ(busy + rendered, 4);
  EXPECT_EQ(queue.submit("x", at(9, 0)).get().outcome, RenderResult::Outcome::bad_request);
}

TEST(RenderRoutes, ParametersAreReadOrRefusedByName) {
  const ViewRequest r = view_request({{"step", "3"}, {"phi", "12.5"}, {"theta", "-20"}, {"zoom", "1.5"}, {"lit", "0"},
                                      {"tf", R"({"colors": [[0, 1, 0, 0]], "opacities": [[0, 2], [1, 3]]})"}});
  EXPECT_EQ(r.step, 3u);
  EXPECT_DOUBLE_EQ(r.phi, 12.5);
  EXPECT_DOUBLE_EQ(r.theta, -20);
  EXPECT_DOUBLE_EQ(r.zoom, 1.5);
  EXPECT_FALSE(r.lit);
  ASSERT_TRUE(r.transfer_function);
  EXPECT_EQ(r.transfer_function->opacities.size(), 2u);
  for (const httplib::Params& bad : std::vector<httplib::Params>{{{"step", "-1"}},
                                                                 {{"step", "1.5"}},
                                                                 {{"phi", "nan"}},
                                                                 {{"phi", "12x"}},
                                                                 {{"lit", "yes"}},
                                                                 {{"tf", "{"}},
                                                                 {{"tf", R"({"colors": [[0, 1]], "opacities": [[0, 1]]})"}},
                                                                 {{"tf", R"({"colors": [], "opacities": [[0, 1]]})"}}}) {
    try {
      view_request(bad);
      ADD_FAILURE() << bad.begin()->first << "=" << bad.begin()->second << " was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    }
  }
}

TEST(RenderRoutes, TheServerRendersWhatTheLibraryRenders) {
  const StoredRun r;
  ViewOptions options{r.dir() / "db", "127.0.0.1", 0, ""};
  options.store = r.store();
  options.config = r.config;
  ViewServer server(options);
  std::thread serving([&] { server.run(); });
  httplib::Client c("127.0.0.1", server.port());
  const std::string token = "token=" + server.token();
  for (int i = 0; i < 200 && !c.Get("/"); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  const auto info = c.Get("/api/store?" + token);
  ASSERT_TRUE(info);
  EXPECT_EQ(info->status, 200);
  EXPECT_NE(info->body.find(R"("fields":["T"])"), std::string::npos) << info->body;
  const auto png = c.Get("/api/render?" + token + "&step=4&phi=90&theta=30&client=t");
  ASSERT_TRUE(png);
  ASSERT_EQ(png->status, 200) << png->body;
  EXPECT_EQ(png->get_header_value("Content-Type"), "image/png");
  EXPECT_FALSE(png->get_header_value("X-Penumbra-Render-Ms").empty());
  StoreView library(r.store(), r.config);
  EXPECT_EQ(decoded(std::vector<unsigned char>(png->body.begin(), png->body.end()), r.dir()),
            decoded(library.render(at(4, 90)).png, r.dir()));
  EXPECT_EQ(c.Get("/api/render?" + token + "&step=99")->status, 400);
  EXPECT_EQ(c.Get("/api/render?" + token + "&phi=abc")->status, 400);
  EXPECT_EQ(c.Get("/api/render?step=0")->status, 403);
  server.stop();
  serving.join();
}

// 50 clients for 10 s mixing data.csv, an image, renders of new views and a refused path: every
// answer is one the route may give (a render: the PNG, 409 when the same client's next request
// superseded it, 503 when the queue is full), none is lost, and the latencies are printed (in the
// sanitizer build: no leak, no race).
TEST(RenderRoutes, FiftyClientsMixingFilesAndRenders) {
  const StoredRun r;
  ViewOptions options;
  options.database = r.dir() / "db";
  options.store = r.store();
  ViewServer server(options);
  std::thread serving([&] { server.run(); });
  const std::string token = "token=" + server.token();
  std::string image;
  for (const auto& e : fs::recursive_directory_iterator(r.dir() / "db"))
    if (e.path().extension() == ".png") image = fs::relative(e.path(), r.dir() / "db").string();
  ASSERT_FALSE(image.empty());
  std::atomic<int> wrong{0}, renders{0}, busy{0};
  std::vector<std::vector<double>> latency(50);
  std::vector<std::thread> clients;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  for (int i = 0; i < 50; ++i)
    clients.emplace_back([&, i] {
      httplib::Client c("127.0.0.1", server.port());
      c.set_read_timeout(60, 0);
      for (int k = 0; std::chrono::steady_clock::now() < until; ++k) {
        const int kind = (i + k) % 4;
        const std::string path = kind == 0   ? "/db/data.csv?" + token
                                 : kind == 1 ? "/db/" + image + "?" + token
                                 : kind == 2 ? "/api/render?" + token + "&step=" + std::to_string(k % 6) + "&phi=" +
                                                   std::to_string(7 * k % 360) + "&client=c" + std::to_string(i % 10)
                                             : "/db/%2e%2e/x?" + token;
        const auto t0 = std::chrono::steady_clock::now();
        const auto res = c.Get(path);
        latency[i].push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        const int status = res ? res->status : -1;
        const bool right = kind == 3 ? status == 404 : kind < 2 ? status == 200 : status == 200 || status == 409 || status == 503;
        if (kind == 2) renders += status == 200, busy += status == 503;
        if (!right) {
          ++wrong;
          std::fprintf(stderr, "client %d request %d (%s): %d\n", i, k, path.c_str(), status);
        }
      }
    });
  for (auto& t : clients) t.join();
  server.stop();
  serving.join();
  std::vector<double> all;
  for (const auto& l : latency) all.insert(all.end(), l.begin(), l.end());
  std::sort(all.begin(), all.end());
  ASSERT_FALSE(all.empty());
  std::printf("%zu requests from 50 clients in 10 s (%d views rendered, %d told the queue was full): median %.2f ms, "
              "99th percentile %.2f ms\n",
              all.size(), renders.load(), busy.load(), all[all.size() / 2], all[all.size() * 99 / 100]);
  EXPECT_EQ(wrong.load(), 0);
  EXPECT_GT(renders.load(), 0);
}

}  // namespace
}  // namespace penumbra::viewer
