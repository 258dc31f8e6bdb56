// SPDX-License-Identifier: BSD-3-Clause
// bench/render/scene.cpp -- benchmark scenes: meshes, analytic fields, transfer function, cameras
#include "scene.h"

#include <vtkCellArray.h>
#include <vtkCellTypes.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkUnstructuredGridReader.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "penumbra/core/error.h"

namespace penumbra::bench {
namespace {

constexpr double pi = 3.14159265358979323846;

// One node list for colour and extinction (see TfNode). Extinction stays moderate so that most
// rays cross the whole volume: errors anywhere along a ray then show in the image.
std::vector<TfNode> benchmark_tf() {
  return {
      {0.00, 0.10, 0.20, 0.80, 0.15},
      {0.30, 0.10, 0.70, 0.90, 0.80},
      {0.50, 0.20, 0.80, 0.30, 0.25},
      {0.70, 0.95, 0.85, 0.20, 1.60},
      {1.00, 0.90, 0.20, 0.10, 3.00},
  };
}

// Camera on a sphere around `center` at azimuth phi (from +x around +z) and elevation theta.
SceneCamera orbit_camera(Vec3d center, double distance, double phi_deg, double theta_deg, double fov_y_deg) {
  const double phi = phi_deg * pi / 180, theta = theta_deg * pi / 180;
  const Vec3d dir{std::cos(theta) * std::cos(phi), std::cos(theta) * std::sin(phi), std::sin(theta)};
  return {center + dir * distance, center, Vec3d{0, 0, 1}, fov_y_deg};
}

void read_legacy_tets(const std::string& path, Scene& scene) {
  if (!std::filesystem::exists(path))
    throw Error(ErrorCode::io_error, "load_scene: mesh file '" + path +
                                         "' does not exist (bench/run.sh generates it with gmsh)");
  vtkNew<vtkUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  if (!grid || grid->GetNumberOfCells() == 0)
    throw Error(ErrorCode::io_error, "load_scene: '" + path + "' holds no unstructured-grid cells");
  const vtkIdType np = grid->GetNumberOfPoints(), nc = grid->GetNumberOfCells();
  scene.points.resize(static_cast<std::size_t>(np) * 3);
  for (vtkIdType i = 0; i < np; ++i) grid->GetPoint(i, &scene.points[static_cast<std::size_t>(i) * 3]);
  scene.tets.reserve(static_cast<std::size_t>(nc) * 4);
  vtkCellArray* cells = grid->GetCells();
  vtkIdType npts = 0;
  const vtkIdType* ids = nullptr;
  for (vtkIdType c = 0; c < nc; ++c) {
    cells->GetCellAtId(c, npts, ids);
    if (grid->GetCellType(c) != VTK_TETRA || npts != 4)
      throw Error(ErrorCode::invalid_argument, "load_scene: '" + path + "' cell " + std::to_string(c) +
                                                   " has VTK type " + std::to_string(grid->GetCellType(c)) +
                                                   ", expected 10 (tetra)");
    scene.tets.insert(scene.tets.end(), ids, ids + 4);
  }
}

template <class F>
void sample_field(Scene& scene, F&& f) {
  scene.scalars.resize(scene.point_count());
  for (std::size_t i = 0; i < scene.point_count(); ++i) {
    const double* p = &scene.points[i * 3];
    scene.scalars[i] = static_cast<float>(f(p[0], p[1], p[2]));
  }
}

// Graded non-convex L-block with a through-hole and an internal void (MESHES.md, Route A,
// h = 0.156: about 1M tets), seen obliquely so that no family of faces lines up with the view.
// `name` is the file's stem: holeblock-1m, or holeblock-100k (the same domain at h = 0.34).
Scene holeblock(const std::string& data_dir, const std::string& name) {
  Scene s;
  s.name = name;
  s.kind = "graded-nonconvex";
  read_legacy_tets(data_dir + "/" + name + ".vtk", s);
  sample_field(s, [](double x, double y, double z) {
    return 0.5 + 0.3 * std::sin(1.7 * x + 0.4) * std::cos(2.3 * y) + 0.2 * std::cos(3.1 * z + 1.3 * x);
  });
  s.tf = benchmark_tf();
  s.camera = orbit_camera({2.0, 1.0, 0.5}, 9.0, -62.0, 33.0, 30.0);
  return s;
}

// n^3 cubes on [0,1]^3, each split into 6 tets around its main diagonal (Freudenthal/Kuhn, so
// neighbours share faces), seen straight down -z from above the centre. The grid plane x = 0.5
// contains the eye, so the rays of the image's middle column run inside tet faces.
Scene grid_aligned(int n) {
  Scene s;
  s.name = "grid-aligned";
  s.kind = "grid-aligned";
  const int m = n + 1;
  s.points.reserve(static_cast<std::size_t>(m) * m * m * 3);
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        s.points.push_back(static_cast<double>(i) / n);
        s.points.push_back(static_cast<double>(j) / n);
        s.points.push_back(static_cast<double>(k) / n);
      }
  auto id = [m](int i, int j, int k) { return (static_cast<std::int64_t>(k) * m + j) * m + i; };
  static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  s.tets.reserve(static_cast<std::size_t>(n) * n * n * 24);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& p : perms) {
          int c[3] = {i, j, k};
          std::int64_t v[4];
          v[0] = id(c[0], c[1], c[2]);
          for (int step = 0; step < 3; ++step) {
            ++c[p[step]];
            v[step + 1] = id(c[0], c[1], c[2]);
          }
          // VTK's positive orientation: the fourth point on the side the first face's normal
          // points to. Half of the Kuhn tets come out mirrored; swap two ids to fix them.
          auto pt = [&s](std::int64_t q) { return Vec3d{s.points[q * 3], s.points[q * 3 + 1], s.points[q * 3 + 2]}; };
          if (signed_volume6(pt(v[0]), pt(v[1]), pt(v[2]), pt(v[3])) < 0) std::swap(v[1], v[2]);
          s.tets.insert(s.tets.end(), v, v + 4);
        }
  sample_field(s, [](double x, double y, double z) {
    return 0.5 + 0.35 * std::sin(2 * pi * x) * std::sin(2 * pi * y) * std::cos(pi * z) + 0.15 * std::cos(4 * z);
  });
  s.tf = benchmark_tf();
  s.camera = {{0.5, 0.5, 3.0}, {0.5, 0.5, 0.5}, {0, 1, 0}, 30.0};
  return s;
}

// FNV-1a, 64 bit: a stable cache key, not a security measure.
struct Digest {
  std::uint64_t h = 1469598103934665603ull;
  void add(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  }
  template <class T>
  void add_vector(const std::vector<T>& v) { add(v.data(), v.size() * sizeof(T)); }
};

}  // namespace

std::vector<std::string> scene_names() { return {"holeblock-1m", "grid-aligned"}; }

Scene load_scene(const std::string& name, const std::string& data_dir) {
  if (name == "holeblock-1m" || name == "holeblock-100k") return holeblock(data_dir, name);
  if (name == "grid-aligned") return grid_aligned(56);
  throw Error(ErrorCode::invalid_argument,
              "load_scene: unknown scene '" + name + "', expected holeblock-1m, holeblock-100k or grid-aligned");
}

std::string scene_digest(const Scene& scene) {
  Digest d;
  d.add_vector(scene.points);
  d.add_vector(scene.tets);
  d.add_vector(scene.scalars);
  d.add_vector(scene.tf);
  d.add(&scene.camera, sizeof(scene.camera));
  d.add(&scene.width, sizeof(scene.width));
  d.add(&scene.height, sizeof(scene.height));
  d.add(scene.background, sizeof(scene.background));
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(d.h));
  return text;
}

std::string reference_path(const Scene& scene, const std::string& data_dir) {
  return data_dir + "/reference/" + scene.name + "-" + std::to_string(scene.width) + "x" +
         std::to_string(scene.height) + "-" + scene_digest(scene) + ".png";
}

}  // namespace penumbra::bench
