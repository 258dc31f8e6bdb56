// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/config.cpp -- JSON config parsing; every error names the offending key path
#include "config.h"

#include <cctype>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "penumbra/core/error.h"

namespace penumbra::insitu {
namespace {

using json = nlohmann::json;

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw Error(ErrorCode::invalid_argument, "config: " + path + " " + what);
}

std::string child(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }
std::string item(const std::string& path, std::size_t i) { return path + "[" + std::to_string(i) + "]"; }

/// Rejects keys of object `j` (at `path`) that are not in `allowed`.
void only_keys(const json& j, const std::string& path, std::initializer_list<const char*> allowed) {
  if (!j.is_object()) fail(path.empty() ? "top level" : path, "must be an object");
  for (auto it = j.begin(); it != j.end(); ++it) {
    bool known = false;
    for (const char* a : allowed) known = known || it.key() == a;
    if (!known) {
      std::string list;
      for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      fail(child(path, it.key()), "is not a known key (expected one of: " + list + ")");
    }
  }
}

const json* find(const json& j, const char* key) {
  auto it = j.find(key);
  return it == j.end() ? nullptr : &*it;
}

double number(const json& j, const std::string& path) {
  if (!j.is_number()) fail(path, "must be a number");
  const double v = j.get<double>();
  if (!std::isfinite(v)) fail(path, "must be finite");
  return v;
}

std::int64_t integer(const json& j, const std::string& path, std::int64_t lo, std::int64_t hi) {
  if (!j.is_number_integer()) fail(path, "must be an integer");
  // Above the largest int64 (JSON integers up to 2^64 - 1 parse as unsigned): not cast to a negative.
  if (j.is_number_unsigned() && j.get<std::uint64_t>() > std::uint64_t(hi))
    fail(path, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                   std::to_string(j.get<std::uint64_t>()));
  const std::int64_t v = j.get<std::int64_t>();
  if (v < lo || v > hi) fail(path, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + std::to_string(v));
  return v;
}

std::string string(const json& j, const std::string& path) {
  if (!j.is_string()) fail(path, "must be a string");
  return j.get<std::string>();
}

std::string choice(const json& j, const std::string& path, std::initializer_list<const char*> options) {
  const std::string s = string(j, path);
  std::string list;
  for (const char* o : options) {
    if (s == o) return s;
    list += (list.empty() ? "\"" : ", \"") + std::string(o) + "\"";
  }
  fail(path, "must be one of " + list + ", got \"" + s + "\"");
}

/// A fixed-length array of finite numbers; `shape` names the expected form in the message.
std::vector<double> tuple(const json& j, const std::string& path, std::size_t n, const char* shape) {
  if (!j.is_array() || j.size() != n) fail(path, std::string("must be ") + shape);
  std::vector<double> v;
  for (std::size_t i = 0; i < n; ++i) {
    if (!j[i].is_number() || !std::isfinite(j[i].get<double>())) fail(path, std::string("must be ") + shape);
    v.push_back(j[i].get<double>());
  }
  return v;
}

Vec3d vec3(const json& j, const std::string& path) {
  const auto v = tuple(j, path, 3, "[x,y,z]");
  return {v[0], v[1], v[2]};
}

std::vector<double> number_list(const json& j, const std::string& path) {
  if (!j.is_array() || j.empty()) fail(path, "must be a non-empty array of numbers");
  std::vector<double> v;
  for (std::size_t i = 0; i < j.size(); ++i) v.push_back(number(j[i], item(path, i)));
  return v;
}

void parse_output(const json& j, const std::string& path, Config& c) {
  only_keys(j, path, {"directory", "if_exists"});
  const json* dir = find(j, "directory");
  if (!dir) fail(child(path, "directory"), "is required");
  c.output_directory = string(*dir, child(path, "directory"));
  if (c.output_directory.empty()) fail(child(path, "directory"), "must not be empty");
  if (const json* e = find(j, "if_exists"))
    c.if_exists = choice(*e, child(path, "if_exists"), {"error", "resume"}) == "resume" ? IfExists::resume : IfExists::error;
}

void parse_image(const json& j, const std::string& path, Config& c) {
  only_keys(j, path, {"width", "height", "background"});
  // 16384 bounds a frame to 1 GiB of RGBA floats: bigger is almost certainly a typo.
  if (const json* w = find(j, "width")) c.width = static_cast<int>(integer(*w, child(path, "width"), 1, 16384));
  if (const json* h = find(j, "height")) c.height = static_cast<int>(integer(*h, child(path, "height"), 1, 16384));
  if (const json* b = find(j, "background")) {
    const auto v = tuple(*b, child(path, "background"), 3, "[r,g,b] with components in [0,1]");
    for (int k = 0; k < 3; ++k) {
      if (v[k] < 0 || v[k] > 1) fail(child(path, "background"), "must be [r,g,b] with components in [0,1]");
      c.background[k] = static_cast<float>(v[k]);
    }
  }
}

double fov(const json& j, const std::string& path) {
  const double f = number(j, path);
  if (f <= 0 || f >= 180) fail(path, "must be in (0, 180) degrees");
  return f;
}

void parse_cameras(const json& j, const std::string& path, Config& c) {
  only_keys(j, path, {"phi", "theta", "fov", "look_at"});
  const json* phi = find(j, "phi");
  const json* theta = find(j, "theta");
  if ((phi != nullptr) != (theta != nullptr)) fail(path, "needs both \"phi\" and \"theta\" for Cinema orbit cameras");
  if (phi) {
    OrbitCameras o;
    o.phi = number_list(*phi, child(path, "phi"));
    o.theta = number_list(*theta, child(path, "theta"));
    for (std::size_t i = 0; i < o.theta.size(); ++i)
      if (o.theta[i] < -90 || o.theta[i] > 90) fail(item(child(path, "theta"), i), "must be in [-90, 90] degrees");
    if (const json* f = find(j, "fov")) o.fov_y_deg = fov(*f, child(path, "fov"));
    c.orbit = o;
  } else if (find(j, "fov")) {
    fail(child(path, "fov"), "applies to orbit cameras only (give phi and theta, or a fov per look_at camera)");
  }
  if (const json* la = find(j, "look_at")) {
    const std::string lp = child(path, "look_at");
    if (!la->is_array() || la->empty()) fail(lp, "must be a non-empty array of cameras");
    for (std::size_t i = 0; i < la->size(); ++i) {
      const std::string p = item(lp, i);
      const json& e = (*la)[i];
      only_keys(e, p, {"name", "eye", "target", "up", "fov"});
      LookAtCamera cam;
      cam.name = "camera" + std::to_string(i);
      if (const json* n = find(e, "name")) cam.name = string(*n, child(p, "name"));
      for (const char* k : {"eye", "target"})
        if (!find(e, k)) fail(child(p, k), "is required");
      cam.eye = vec3(e["eye"], child(p, "eye"));
      cam.target = vec3(e["target"], child(p, "target"));
      if (const json* u = find(e, "up")) cam.up = vec3(*u, child(p, "up"));
      if (const json* f = find(e, "fov")) cam.fov_y_deg = fov(*f, child(p, "fov"));
      const Vec3d d = cam.target - cam.eye;
      if (length(d) == 0) fail(p, "has eye == target");
      if (length(cross(d, cam.up)) <= 1e-9 * length(d) * length(cam.up)) fail(child(p, "up"), "must not be parallel to target - eye");
      for (const auto& other : c.look_at)
        if (other.name == cam.name) fail(child(p, "name"), "\"" + cam.name + "\" is used twice");
      c.look_at.push_back(cam);
    }
  }
  if (!c.orbit && c.look_at.empty()) fail(path, "must define orbit cameras (phi, theta) or look_at cameras");
}

/// A cool-to-warm colour map with opacity rising linearly from 0 to 4 per diagonal.
render::TransferFunction default_transfer_function() {
  render::TransferFunction tf;
  tf.colors = {{0.0, 0.230, 0.299, 0.754}, {0.5, 0.865, 0.865, 0.865}, {1.0, 0.706, 0.016, 0.150}};
  tf.opacities = {{0.0, 0.0}, {1.0, 4.0}};
  return tf;
}

void parse_transfer_function(const json& j, const std::string& path, FieldConfig& f) {
  only_keys(j, path, {"x", "opacity_unit", "colors", "opacities"});
  if (const json* x = find(j, "x"))
    f.x_units = choice(*x, child(path, "x"), {"normalized", "data"}) == "data" ? XUnits::data : XUnits::normalized;
  if (const json* u = find(j, "opacity_unit"))
    f.opacity_unit = choice(*u, child(path, "opacity_unit"), {"diagonal", "world"}) == "world" ? OpacityUnit::world
                                                                                             : OpacityUnit::diagonal;
  render::TransferFunction tf = default_transfer_function();
  if (const json* cs = find(j, "colors")) {
    const std::string cp = child(path, "colors");
    if (!cs->is_array() || cs->empty()) fail(cp, "must be a non-empty array of [x,r,g,b]");
    tf.colors.clear();
    for (std::size_t i = 0; i < cs->size(); ++i) {
      const auto v = tuple((*cs)[i], item(cp, i), 4, "[x,r,g,b]");
      for (int k = 1; k < 4; ++k)
        if (v[k] < 0 || v[k] > 1) fail(item(cp, i), "must be [x,r,g,b] with r, g, b in [0,1]");
      if (i > 0 && v[0] < tf.colors.back().x) fail(item(cp, i), "x must not decrease");
      tf.colors.push_back({v[0], v[1], v[2], v[3]});
    }
  }
  if (const json* os = find(j, "opacities")) {
    const std::string op = child(path, "opacities");
    if (!os->is_array() || os->empty()) fail(op, "must be a non-empty array of [x,a]");
    tf.opacities.clear();
    for (std::size_t i = 0; i < os->size(); ++i) {
      const auto v = tuple((*os)[i], item(op, i), 2, "[x,a]");
      if (v[1] < 0) fail(item(op, i), "must be [x,a] with a >= 0");
      if (i > 0 && v[0] < tf.opacities.back().x) fail(item(op, i), "x must not decrease");
      tf.opacities.push_back({v[0], v[1]});
    }
  }
  f.transfer_function = tf;
}

FieldConfig parse_field(const json& j, const std::string& path) {
  only_keys(j, path, {"name", "component", "range", "transfer_function"});
  FieldConfig f;
  const json* n = find(j, "name");
  if (!n) fail(child(path, "name"), "is required");
  f.name = string(*n, child(path, "name"));
  if (f.name.empty()) fail(child(path, "name"), "must not be empty");
  if (const json* c = find(j, "component")) {
    if (c->is_string()) {
      choice(*c, child(path, "component"), {"magnitude"});
    } else if (c->is_number_integer()) {
      f.mode = ComponentMode::component;
      f.component = static_cast<int>(integer(*c, child(path, "component"), 0, 63));
    } else {
      fail(child(path, "component"), "must be \"magnitude\" or a component index");
    }
  }
  f.transfer_function = default_transfer_function();
  if (const json* tf = find(j, "transfer_function")) parse_transfer_function(*tf, child(path, "transfer_function"), f);
  if (const json* r = find(j, "range")) {
    const std::string rp = child(path, "range");
    if (r->is_string()) {
      choice(*r, rp, {"auto"});
    } else {
      const auto v = tuple(*r, rp, 2, "\"auto\" or [lo,hi]");
      if (!(v[0] < v[1])) fail(rp, "must have lo < hi");
      f.range = std::make_pair(v[0], v[1]);
    }
    if (f.x_units == XUnits::data) fail(rp, "does not apply when transfer_function.x is \"data\"");
  }
  return f;
}

void parse_trigger(const json& j, const std::string& path, Config& c) {
  only_keys(j, path, {"every_cycles", "every_time", "when", "max_share"});
  c.trigger = {};
  if (const json* n = find(j, "every_cycles"))
    c.trigger.every_cycles = integer(*n, child(path, "every_cycles"), 1, std::numeric_limits<std::int64_t>::max());
  if (const json* t = find(j, "every_time")) {
    c.trigger.every_time = number(*t, child(path, "every_time"));
    if (c.trigger.every_time <= 0) fail(child(path, "every_time"), "must be > 0");
  }
  if (const json* w = find(j, "when")) c.trigger.when = TriggerExpression(string(*w, child(path, "when")), child(path, "when"));
  if (const json* m = find(j, "max_share")) {
    c.trigger.max_share = number(*m, child(path, "max_share"));
    if (!(c.trigger.max_share > 0 && c.trigger.max_share <= 1)) fail(child(path, "max_share"), "must be in (0, 1]");
  }
  if (c.trigger.every_cycles == 0 && c.trigger.every_time == 0 && !c.trigger.when)
    fail(path, "needs every_cycles, every_time and/or when");
}

render::Light parse_light(const json& j, const std::string& path) {
  only_keys(j, path, {"type", "direction", "position", "color"});
  render::Light l;
  const json* t = find(j, "type");
  if (!t) fail(child(path, "type"), "is required (\"directional\" or \"point\")");
  const bool directional = choice(*t, child(path, "type"), {"directional", "point"}) == "directional";
  l.kind = directional ? render::Light::Kind::directional : render::Light::Kind::point;
  const char* key = directional ? "direction" : "position";
  const char* other = directional ? "position" : "direction";
  if (find(j, other)) fail(child(path, other), std::string("does not apply to a ") + (directional ? "directional" : "point") + " light");
  const json* v = find(j, key);
  if (!v) fail(child(path, key), "is required");
  l.vector = vec3(*v, child(path, key));
  if (directional && length(l.vector) == 0) fail(child(path, key), "must not be the zero vector");
  if (const json* c = find(j, "color")) {
    const auto rgb = tuple(*c, child(path, "color"), 3, "[r,g,b] with components >= 0");
    for (int k = 0; k < 3; ++k) {
      if (rgb[k] < 0) fail(child(path, "color"), "must be [r,g,b] with components >= 0");
      l.color[static_cast<std::size_t>(k)] = rgb[k];
    }
  }
  return l;
}

double non_negative(const json& j, const std::string& path) {
  const double v = number(j, path);
  if (v < 0) fail(path, "must be >= 0");
  return v;
}

LightingConfig parse_lighting(const json& j, const std::string& path) {
  only_keys(j, path,
            {"model", "lights", "absorption", "scattering", "level0_resolution", "phong", "budget", "occlusion"});
  LightingConfig l;
  if (const json* m = find(j, "model")) {
    const std::string s = choice(*m, child(path, "model"), {"none", "phong", "light-volume", "occlusion"});
    l.model = s == "none" ? render::LightingModel::none
                          : (s == "phong" ? render::LightingModel::phong : render::LightingModel::light_volume);
    l.occlusion_model = s == "occlusion";
  }
  if (const json* o = find(j, "occlusion")) {
    const std::string op = child(path, "occlusion");
    only_keys(*o, op, {"aperture", "splits", "grid", "attenuation", "space", "volume_resolution", "shadows",
                       "shadow_aperture", "shadow_splits", "level"});
    OcclusionConfig& oc = l.occlusion;
    auto angle = [&](const char* key, double& out) {
      if (const json* a = find(*o, key)) {
        out = number(*a, child(op, key));
        if (out <= 0 || out >= 90) fail(child(op, key), "must be in (0, 90) degrees");
      }
    };
    auto splits = [&](const char* key, int& out) {
      if (const json* n = find(*o, key)) {
        out = static_cast<int>(integer(*n, child(op, key), 1, 7));
        if (out != 1 && out != 3 && out != 7) fail(child(op, key), "must be 1, 3 or 7");
      }
    };
    angle("aperture", oc.aperture_deg);
    angle("shadow_aperture", oc.shadow_aperture_deg);
    splits("splits", oc.splits);
    splits("shadow_splits", oc.shadow_splits);
    if (const json* g = find(*o, "grid")) oc.grid_resolution = static_cast<int>(integer(*g, child(op, "grid"), 4, 1024));
    if (const json* a = find(*o, "attenuation")) {
      oc.attenuation = number(*a, child(op, "attenuation"));
      if (oc.attenuation <= 0) fail(child(op, "attenuation"), "must be > 0");
    }
    if (const json* sp = find(*o, "space")) {
      const std::string v = choice(*sp, child(op, "space"), {"points", "volume", "image"});
      oc.space = v == "volume" ? OcclusionSpace::volume : (v == "image" ? OcclusionSpace::image : OcclusionSpace::points);
    }
    if (const json* r = find(*o, "volume_resolution"))
      oc.volume_resolution = static_cast<int>(integer(*r, child(op, "volume_resolution"), 2, 1024));
    if (const json* lv = find(*o, "level")) {
      const std::string v = choice(*lv, child(op, "level"), {"continuous", "thesis"});
      oc.level = v == "thesis" ? render::LevelSelection::thesis : render::LevelSelection::continuous;
    }
    if (const json* sh = find(*o, "shadows")) {
      if (!sh->is_boolean()) fail(child(op, "shadows"), "must be true or false");
      oc.shadows = sh->get<bool>();
    }
  }
  if (const json* ls = find(j, "lights")) {
    const std::string lp = child(path, "lights");
    if (!ls->is_array()) fail(lp, "must be an array of lights");
    for (std::size_t i = 0; i < ls->size(); ++i) l.lights.push_back(parse_light((*ls)[i], item(lp, i)));
  }
  if (l.model == render::LightingModel::light_volume && !l.occlusion_model && l.lights.empty())
    fail(child(path, "lights"), "needs at least one light for model \"light-volume\"");
  if (const json* a = find(j, "absorption")) l.absorption = non_negative(*a, child(path, "absorption"));
  if (const json* sc = find(j, "scattering")) {
    const std::string sp = child(path, "scattering");
    if (sc->is_number()) {
      l.scattering.fill(non_negative(*sc, sp));
    } else {
      const auto v = tuple(*sc, sp, 3, "a number or [r,g,b], each >= 0");
      for (int k = 0; k < 3; ++k) {
        if (v[k] < 0) fail(sp, "must be a number or [r,g,b], each >= 0");
        l.scattering[static_cast<std::size_t>(k)] = v[k];
      }
    }
  }
  if (const json* r = find(j, "level0_resolution"))
    l.level0_resolution = static_cast<int>(integer(*r, child(path, "level0_resolution"), 4, 1024));
  if (const json* ph = find(j, "phong")) {
    const std::string pp = child(path, "phong");
    only_keys(*ph, pp, {"ambient", "diffuse", "specular", "shininess"});
    if (const json* v = find(*ph, "ambient")) l.ambient = non_negative(*v, child(pp, "ambient"));
    if (const json* v = find(*ph, "diffuse")) l.diffuse = non_negative(*v, child(pp, "diffuse"));
    if (const json* v = find(*ph, "specular")) l.specular = non_negative(*v, child(pp, "specular"));
    if (const json* v = find(*ph, "shininess")) l.shininess = non_negative(*v, child(pp, "shininess"));
  }
  if (const json* b = find(j, "budget")) {
    const std::string bp = child(path, "budget");
    only_keys(*b, bp, {"iterations", "ms"});
    if (const json* n = find(*b, "iterations"))
      l.budget.max_work_units = static_cast<int>(integer(*n, child(bp, "iterations"), 1, 1 << 30));
    if (const json* ms = find(*b, "ms")) {
      l.budget.max_ms = number(*ms, child(bp, "ms"));
      if (l.budget.max_ms <= 0) fail(child(bp, "ms"), "must be > 0");
    }
  }
  return l;
}

// "lossless", or {"altitude_fraction": f}: how a moving mesh's coordinates are kept.
CoordinateStoreConfig parse_coordinates(const json& j, const std::string& path) {
  CoordinateStoreConfig c;
  if (j.is_string()) {
    if (j.get<std::string>() != "lossless") fail(path, "must be \"lossless\" or {\"altitude_fraction\": f}");
    c.lossless = true;
    return c;
  }
  if (!j.is_object()) fail(path, "must be \"lossless\" or {\"altitude_fraction\": f}");
  only_keys(j, path, {"altitude_fraction"});
  if (const json* f = find(j, "altitude_fraction")) {
    c.altitude_fraction = number(*f, child(path, "altitude_fraction"));
    if (!(c.altitude_fraction > 0 && c.altitude_fraction <= 0.125))
      fail(child(path, "altitude_fraction"), "must be in (0, 0.125]: a point moved by a quarter of the thinnest altitude can invert a cell");
  }
  return c;
}

StoreConfig parse_store(const json& j, const std::string& path) {
  only_keys(j, path,
            {"directory", "every_cycles", "window", "codebook_size", "error_bound", "entropy_level", "memory_budget_mb",
             "coordinates"});
  StoreConfig s;
  const json* dir = find(j, "directory");
  if (!dir) fail(child(path, "directory"), "is required");
  s.directory = string(*dir, child(path, "directory"));
  if (s.directory.empty()) fail(child(path, "directory"), "must not be empty");
  if (const json* n = find(j, "every_cycles"))
    s.every_cycles = integer(*n, child(path, "every_cycles"), 1, std::numeric_limits<std::int64_t>::max());
  if (const json* w = find(j, "window")) {
    s.codec.window = static_cast<std::uint32_t>(integer(*w, child(path, "window"), 8, 1024));
    if (s.codec.window % 8 != 0) fail(child(path, "window"), "must be a multiple of 8");
  }
  if (const json* c = find(j, "codebook_size"))
    s.codec.codebook_size = static_cast<std::uint32_t>(integer(*c, child(path, "codebook_size"), 2, 256));
  if (const json* b = find(j, "error_bound")) {
    const std::string bp = child(path, "error_bound");
    only_keys(*b, bp, {"absolute", "relative"});
    if (b->size() != 1) fail(bp, "must have exactly one of \"absolute\" (data units) or \"relative\" (of the value range)");
    const bool absolute = find(*b, "absolute") != nullptr;
    const std::string vp = child(bp, absolute ? "absolute" : "relative");
    s.codec.bound.kind = absolute ? compression::BoundKind::absolute : compression::BoundKind::range_relative;
    s.codec.bound.value = number(*(absolute ? find(*b, "absolute") : find(*b, "relative")), vp);
    if (!(s.codec.bound.value > 0)) fail(vp, "must be > 0");
  }
  if (const json* e = find(j, "entropy_level"))
    s.codec.entropy_level = static_cast<int>(integer(*e, child(path, "entropy_level"), 0, compression::kMaxEntropyLevel));
  if (const json* m = find(j, "memory_budget_mb"))
    s.memory_budget_bytes = static_cast<std::uint64_t>(integer(*m, child(path, "memory_budget_mb"), 1, 1 << 24)) << 20;
  if (const json* c = find(j, "coordinates")) s.coordinates = parse_coordinates(*c, child(path, "coordinates"));
  return s;
}

void parse_compositing(const json& j, const std::string& path, Config& c) {
  only_keys(j, path, {"runs_memory_mb"});
  if (const json* m = find(j, "runs_memory_mb")) {
    const double mb = number(*m, child(path, "runs_memory_mb"));
    if (!(mb > 0 && mb <= 1 << 24)) fail(child(path, "runs_memory_mb"), "must be in (0, 16777216]");
    c.runs_memory_bytes = static_cast<std::size_t>(mb * (1 << 20));
  }
}

void parse_progress(const json& j, const std::string& path, Config& c) {
  only_keys(j, path, {"log", "stderr_every"});
  if (const json* l = find(j, "log")) {
    c.progress.log = string(*l, child(path, "log"));
    if (c.progress.log.empty()) fail(child(path, "log"), "must not be empty (leave the key out for no log)");
  }
  if (const json* e = find(j, "stderr_every"))
    c.progress.stderr_every = static_cast<int>(integer(*e, child(path, "stderr_every"), 0, 1 << 30));
}

void parse_async(const json& j, const std::string& path, Config& c) {
  if (j.is_boolean()) {
    c.async.enabled = j.get<bool>();
    return;
  }
  if (!j.is_object()) fail(path, "must be true, false or an object {\"backpressure\": \"wait\" | \"skip\"}");
  only_keys(j, path, {"backpressure"});
  c.async.enabled = true;
  if (const json* b = find(j, "backpressure"))
    c.async.skip_when_busy = choice(*b, child(path, "backpressure"), {"wait", "skip"}) == "skip";
}

void parse_budget(const json& j, const std::string& path, Config& c) {
  only_keys(j, path, {"ms", "share"});
  BudgetConfig b;
  if (const json* ms = find(j, "ms")) {
    b.ms = number(*ms, child(path, "ms"));
    if (!(b.ms > 0)) fail(child(path, "ms"), "must be > 0");
  }
  if (const json* share = find(j, "share")) {
    b.share = number(*share, child(path, "share"));
    if (!(b.share > 0)) fail(child(path, "share"), "must be > 0 (a share of the solver's time per step)");
  }
  if (b.ms == 0 && b.share == 0) fail(path, "needs ms and/or share");
  c.budget = b;
}

Config parse_document(const json& j) {
  only_keys(j, "", {"output", "image", "cameras", "fields", "trigger", "backend", "lighting", "store", "compositing",
                    "progress", "async", "budget"});
  Config c;
  c.trigger.every_cycles = 1;
  const json* out = find(j, "output");
  if (!out) fail("output", "is required");
  parse_output(*out, "output", c);
  if (const json* im = find(j, "image")) parse_image(*im, "image", c);
  const json* cams = find(j, "cameras");
  if (!cams) fail("cameras", "is required");
  parse_cameras(*cams, "cameras", c);
  const json* fields = find(j, "fields");
  if (!fields) fail("fields", "is required");
  if (!fields->is_array() || fields->empty()) fail("fields", "must be a non-empty array");
  for (std::size_t i = 0; i < fields->size(); ++i) {
    FieldConfig f = parse_field((*fields)[i], item("fields", i));
    for (const auto& other : c.fields)
      if (other.name == f.name && other.mode == f.mode && (f.mode == ComponentMode::magnitude || other.component == f.component))
        fail(item("fields", i), "renders field '" + f.name + "' with the same component as an earlier entry");
    c.fields.push_back(std::move(f));
  }
  if (const json* t = find(j, "trigger")) parse_trigger(*t, "trigger", c);
  if (const json* b = find(j, "backend")) {
    const std::string s = choice(*b, "backend", {"cpu", "gpu", "auto"});
    c.backend = s == "cpu" ? Backend::cpu : (s == "gpu" ? Backend::gpu : Backend::automatic);
  }
  if (const json* l = find(j, "lighting")) c.lighting = parse_lighting(*l, "lighting");
  if (const json* st = find(j, "store")) c.store = parse_store(*st, "store");
  if (const json* cm = find(j, "compositing")) parse_compositing(*cm, "compositing", c);
  if (const json* pr = find(j, "progress")) parse_progress(*pr, "progress", c);
  if (const json* as = find(j, "async")) parse_async(*as, "async", c);
  if (const json* bu = find(j, "budget")) parse_budget(*bu, "budget", c);
  return c;
}

}  // namespace

bool Config::uses_field(const std::string& name) const {
  for (const auto& f : fields)
    if (f.name == name) return true;
  if (trigger.when)
    for (const auto& f : trigger.when->fields())
      if (f == name) return true;
  return false;
}

void check_config_rules(const Config& c) {
  if (c.lighting && c.lighting->occlusion_model && c.lighting->occlusion.space == OcclusionSpace::image &&
      c.backend == Backend::gpu)
    throw Error(ErrorCode::backend_unavailable,
                "config: lighting.occlusion.space \"image\" is evaluated by the CPU backend only; use backend "
                "\"cpu\" or \"auto\", or space \"points\" or \"volume\"");
}

Config parse_config(const std::string& text_or_path) {
  std::size_t first = 0;
  while (first < text_or_path.size() && std::isspace(static_cast<unsigned char>(text_or_path[first]))) ++first;
  std::string text = text_or_path;
  std::string source = "config text";
  if (first >= text_or_path.size() || text_or_path[first] != '{') {
    if (text_or_path.empty()) throw Error(ErrorCode::invalid_argument, "config: empty (expected a file path or JSON text)");
    std::ifstream in(text_or_path, std::ios::binary);
    if (!in) throw Error(ErrorCode::io_error, "config: cannot read file '" + text_or_path + "'");
    std::ostringstream ss;
    ss << in.rdbuf();
    text = ss.str();
    source = "config file '" + text_or_path + "'";
  }
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {  // parse_error, or out_of_range for a number too large for a double
    throw Error(ErrorCode::invalid_argument, "config: " + source + " is not valid JSON: " + e.what());
  }
  Config config = parse_document(j);
  config.text = std::move(text);
  return config;
}

}  // namespace penumbra::insitu
