// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/store_view.cpp
#include "store_view.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

#include "config.h"
#include "field_stages.h"
#include "penumbra/core/elapsed.h"
#include "penumbra/core/error.h"
#include "penumbra/core/field_view.h"
#include "penumbra/core/local_frame.h"
#include "penumbra/render/camera.h"
#include "penumbra/render/cpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "penumbra/render/light_volume.h"
#include "penumbra/render/occlusion.h"
#include "step_stages.h"
#include "stored_segment.h"

namespace penumbra::viewer {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();


// A transfer function as text, to tell whether the lighting was solved for this one.
std::string key_of(const render::TransferFunction& tf) {
  std::ostringstream s;
  s.precision(17);
  for (const auto& c : tf.colors) s << c.x << ' ' << c.r << ' ' << c.g << ' ' << c.b << ';';
  s << '|';
  for (const auto& o : tf.opacities) s << o.x << ' ' << o.a << ';';
  return s.str();
}

// The piece's mesh as the library's view of it (float64 points, int64 connectivity).
MeshView mesh_view(const replay::StorePiece& piece) {
  MeshView v;
  v.points = {reinterpret_cast<const std::byte*>(piece.xyz().data()), piece.point_count(), 3 * sizeof(double)};
  v.point_type = ScalarType::float64;
  v.connectivity = {piece.connectivity().data(), piece.connectivity().size(), ScalarType::int64};
  v.offsets = {piece.offsets().data(), piece.offsets().size(), ScalarType::int64};
  v.cell_types = piece.cell_types().data();
  v.cell_type_count = piece.cell_types().size();
  return v;
}

// The tets of `view` in the frame of their own bounds, as a serial run prepares them.
std::shared_ptr<const render::TetMesh> framed(render::TetMesh tets) {
  tets.frame = LocalFrame::of(tets.bounds);
  return std::make_shared<const render::TetMesh>(std::move(tets));
}

}  // namespace

struct StoreView::Impl {
  insitu::Config config;
  StoreInfo info;
  std::vector<std::unique_ptr<replay::StoredSegment>> segments;
  std::vector<std::size_t> first_step;  ///< per segment, counted through the store

  // The segment in use, its mesh at `points_step` (a segment whose points move).
  std::size_t segment = kNone, points_step = kNone;
  std::unique_ptr<replay::StorePiece> piece;
  std::shared_ptr<const render::TetMesh> tets;
  std::unique_ptr<render::CpuRayCaster> renderer;

  // The field values in use.
  std::size_t values_step = kNone, values_field = kNone;
  std::vector<double> values;
  double lo = 0, hi = 1;
  std::vector<float> normalized;

  // Each field entry's lighting, and the step and transfer function it was solved for.
  std::vector<std::unique_ptr<render::LightVolume>> light_volumes;
  std::vector<std::unique_ptr<render::OcclusionLighting>> occlusions;
  std::vector<std::string> light_keys;

  void open_store(const std::string& store);
  std::pair<std::size_t, std::size_t> locate(std::size_t step) const;
  void use_segment(std::size_t s);
  void move_points_to(std::size_t local_step);
  void load(std::size_t step, std::size_t field);
  render::TransferFunction transfer_function(const ViewRequest& r) const;
  render::Camera camera(const ViewRequest& r) const;
  render::RenderOptions lighting(std::size_t field, const render::TransferFunction& tf, const render::Camera& cam,
                                 RenderedView& out);
  void drop_lighting();
};

void StoreView::Impl::open_store(const std::string& store) {
  for (const std::string& dir : replay::store_segments(store)) {
    first_step.push_back(info.times.size());
    auto& seg = *segments.emplace_back(std::make_unique<replay::StoredSegment>(dir));
    for (std::size_t s = 0; s < seg.step_count(); ++s) {
      info.times.push_back(seg.time(s));
      info.cycles.push_back(seg.cycle(s));
    }
  }
  if (info.times.empty()) throw Error(ErrorCode::io_error, "penumbra-view: the store '" + store + "' holds no step");
}

std::pair<std::size_t, std::size_t> StoreView::Impl::locate(std::size_t step) const {
  if (step >= info.times.size())
    throw Error(ErrorCode::invalid_argument, "step " + std::to_string(step) + " is not stored (the store holds " +
                                                 std::to_string(info.times.size()) + ")");
  std::size_t s = segments.size() - 1;
  while (first_step[s] > step) --s;
  return {s, step - first_step[s]};
}

void StoreView::Impl::use_segment(std::size_t s) {
  if (segment == s) return;
  piece.reset();
  renderer.reset();
  drop_lighting();
  values_step = values_field = points_step = kNone;
  const replay::StoredSegment& seg = *segments[s];
  piece = std::make_unique<replay::StorePiece>(seg, 0, seg.cell_count());
  tets = framed(render::prepare_tet_mesh(mesh_view(*piece), "penumbra-view"));
  renderer = std::make_unique<render::CpuRayCaster>(tets);
  segment = s;
}

void StoreView::Impl::move_points_to(std::size_t local_step) {
  if (!segments[segment]->points_move() || points_step == local_step) return;
  piece->move_to(local_step);
  tets = framed(render::move_tet_mesh(*tets, mesh_view(*piece), "penumbra-view"));
  renderer->move_points(tets);
  for (auto& lv : light_volumes)
    if (lv) lv->move_points(tets);
  for (auto& occ : occlusions) occ.reset();  // made again for the moved points
  light_keys.assign(light_keys.size(), "");
  points_step = local_step;
}

void StoreView::Impl::load(std::size_t step, std::size_t field) {
  const auto [s, local] = locate(step);
  use_segment(s);
  move_points_to(local);
  if (values_step == step && values_field == field) return;
  piece->read(info.fields[field], local, values);
  const insitu::FieldConfig& f = config.fields[field];
  const auto [local_lo, local_hi] = insitu::local_range(f, values);
  std::tie(lo, hi) = insitu::usable_range(local_lo, local_hi);
  normalized = normalize_values(values, lo, hi);
  values_step = step;
  values_field = field;
}

render::TransferFunction StoreView::Impl::transfer_function(const ViewRequest& r) const {
  insitu::FieldConfig f = config.fields[r.field];
  if (r.transfer_function) {
    r.transfer_function->validate();
    f.transfer_function = *r.transfer_function;
  }
  return insitu::resolve_transfer_function(f, lo, hi, tets->bounds.diagonal());
}

render::Camera StoreView::Impl::camera(const ViewRequest& r) const {
  if (!(std::isfinite(r.phi) && std::isfinite(r.theta) && r.theta >= -90 && r.theta <= 90))
    throw Error(ErrorCode::invalid_argument, "phi must be finite and theta within [-90, 90]");
  if (!(std::isfinite(r.zoom) && r.zoom >= 0.05 && r.zoom <= 100))
    throw Error(ErrorCode::invalid_argument, "zoom must be within [0.05, 100]");
  // The run's own orbit camera at (phi, theta), as view_cameras makes it, so that a stored angle
  // gives the stored picture; zoom narrows its field of view around the same eye.
  const double half = std::atan(std::tan(info.fov_y_deg * M_PI / 360) / r.zoom);
  return render::Camera::orbit(tets->bounds, r.phi, r.theta, half * 360 / M_PI, config.width, config.height);
}

render::RenderOptions StoreView::Impl::lighting(std::size_t field, const render::TransferFunction& tf,
                                                const render::Camera& cam, RenderedView& out) {
  render::RenderOptions options;
  if (!insitu::lit(config)) return options;
  const insitu::LightingConfig& l = *config.lighting;
  const auto t0 = Clock::now();
  const std::string key = std::to_string(values_step) + "/" + key_of(tf);
  const bool fresh = light_keys[field] != key;
  const std::vector<float>* light_rgb = nullptr;
  if (l.occlusion_model) {
    auto& occ = occlusions[field];
    if (!occ) occ = std::make_unique<render::OcclusionLighting>(tets, l.occlusion, l.lights, nullptr);
    if (fresh) {
      occ->resample_field(normalized, tf);
      occ->finish_field();
    }
    // Occlusion looks towards the viewer: its light depends on the eye.
    if (l.occlusion.space == render::OcclusionSpace::image) options.shading.light_at = occ->light_at(cam.eye);
    else light_rgb = &occ->light_rgb(cam.eye);
  } else if (l.model == render::LightingModel::light_volume) {
    auto& lv = light_volumes[field];
    if (!lv) {
      render::LightVolumeOptions lo;
      lo.level0_resolution = l.level0_resolution;
      lo.sigma_a = l.absorption;
      lo.sigma_s = l.scattering;
      lv = std::make_unique<render::LightVolume>(tets, lo);
      lv->set_lights(l.lights);
    }
    if (fresh) {
      lv->set_field(normalized, tf);
      // Solved to convergence (no budget): a browsed view shows the settled light, warm-started
      // from the field's last solution.
      out.light_converged = lv->update(render::LightBudget{}).converged;
    }
    light_rgb = &lv->light_rgb();
  }
  light_keys[field] = key;
  const auto light_at = options.shading.light_at;
  options.shading = insitu::shading_of(l, light_rgb);
  options.shading.light_at = light_at;
  out.light_ms = ms_since(t0);
  return options;
}

void StoreView::Impl::drop_lighting() {
  light_volumes.clear();
  light_volumes.resize(config.fields.size());
  occlusions.clear();
  occlusions.resize(config.fields.size());
  light_keys.assign(config.fields.size(), "");
}

namespace {

// The config a store keeps beside its segments (a segment's own folder is inside the store).
std::string kept_config(const std::string& store) {
  for (const auto& dir : {std::filesystem::path(store), std::filesystem::path(store).parent_path()})
    if (std::filesystem::is_regular_file(dir / "config.json")) return (dir / "config.json").string();
  throw Error(ErrorCode::io_error, "penumbra-view: the store '" + store +
                                       "' keeps no config.json (a run's store writes one); pass the run's config with --config");
}

}  // namespace

StoreView::StoreView(const std::string& store, const std::string& config) : m_impl(std::make_unique<Impl>()) {
  Impl& im = *m_impl;
  if (!std::filesystem::is_directory(store))
    throw Error(ErrorCode::io_error, "penumbra-view: the store '" + store + "' is not a directory");
  im.config = insitu::parse_config(config.empty() ? kept_config(store) : config);
  insitu::check_config_rules(im.config);
  im.open_store(store);
  im.info.fields = insitu::field_labels(im.config);
  for (const auto& f : im.config.fields) im.info.transfer_functions.push_back(f.transfer_function);
  im.info.lighting = im.config.lighting ? insitu::lighting_label(*im.config.lighting) : "none";
  im.info.width = im.config.width;
  im.info.height = im.config.height;
  im.info.fov_y_deg = im.config.orbit ? im.config.orbit->fov_y_deg : 30.0;
  const auto& stored = im.segments.front()->fields();
  for (const std::string& name : im.info.fields)
    if (std::find(stored.begin(), stored.end(), name) == stored.end())
      throw Error(ErrorCode::invalid_argument, "penumbra-view: the config renders field '" + name +
                                                   "', which the store does not hold: pass the run's own config");
  im.drop_lighting();
}

StoreView::~StoreView() = default;

const StoreInfo& StoreView::info() const { return m_impl->info; }

RenderedView StoreView::render(const ViewRequest& request) {
  Impl& im = *m_impl;
  if (request.field >= im.info.fields.size())
    throw Error(ErrorCode::invalid_argument, "field " + std::to_string(request.field) + " is not one of the run's " +
                                                 std::to_string(im.info.fields.size()));
  RenderedView out;
  const auto t0 = Clock::now();
  im.load(request.step, request.field);
  out.load_ms = ms_since(t0);
  const render::TransferFunction tf = im.transfer_function(request);
  const render::Camera cam = im.camera(request);
  const render::RenderOptions options =
      request.lit ? im.lighting(request.field, tf, cam, out) : render::RenderOptions{};
  const auto t1 = Clock::now();
  insitu::RenderedView view;
  im.renderer->render(im.normalized, tf, cam, options, view.output);
  const insitu::ComposedImage image = insitu::composite_view(std::move(view), im.config.background);
  out.png = render::encode_png(image.rgb, image.width, image.height);
  out.render_ms = ms_since(t1);
  return out;
}

}  // namespace penumbra::viewer
