// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/render_routes.cpp
#include "render_routes.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>

#include "penumbra/core/error.h"

namespace penumbra::viewer {
namespace {

using nlohmann::json;

std::string param(const httplib::Params& params, const std::string& name, const std::string& fallback) {
  const auto it = params.find(name);
  return it == params.end() ? fallback : it->second;
}

double number(const httplib::Params& params, const std::string& name, const std::string& fallback) {
  const std::string text = param(params, name, fallback);
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (text.empty() || used != text.size() || !std::isfinite(v))
    throw Error(ErrorCode::invalid_argument, "parameter '" + name + "' must be a finite number, not '" + text + "'");
  return v;
}

std::size_t index(const httplib::Params& params, const std::string& name) {
  const double v = number(params, name, "0");
  if (v < 0 || v != std::floor(v) || v > 1e15)
    throw Error(ErrorCode::invalid_argument, "parameter '" + name + "' must be a whole number >= 0");
  return static_cast<std::size_t>(v);
}

render::TransferFunction transfer_function(const std::string& text) {
  const json j = json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("colors") || !j.contains("opacities"))
    throw Error(ErrorCode::invalid_argument, "parameter 'tf' must be JSON {\"colors\": [[x, r, g, b], ...], "
                                             "\"opacities\": [[x, a], ...]}");
  render::TransferFunction tf;
  try {
    for (const auto& c : j.at("colors")) tf.colors.push_back({c.at(0).get<double>(), c.at(1).get<double>(), c.at(2).get<double>(), c.at(3).get<double>()});
    for (const auto& o : j.at("opacities")) tf.opacities.push_back({o.at(0).get<double>(), o.at(1).get<double>()});
  } catch (const json::exception& e) {
    throw Error(ErrorCode::invalid_argument, std::string("parameter 'tf': ") + e.what());
  }
  tf.validate();
  return tf;
}

json transfer_function_json(const render::TransferFunction& tf) {
  json colors = json::array(), opacities = json::array();
  for (const auto& c : tf.colors) colors.push_back({c.x, c.r, c.g, c.b});
  for (const auto& o : tf.opacities) opacities.push_back({o.x, o.a});
  return {{"colors", colors}, {"opacities", opacities}};
}

int status_of(RenderResult::Outcome outcome) {
  switch (outcome) {
    case RenderResult::Outcome::rendered: return 200;
    case RenderResult::Outcome::superseded: return 409;
    case RenderResult::Outcome::busy: return 503;
    case RenderResult::Outcome::bad_request: return 400;
    case RenderResult::Outcome::failed: return 500;
  }
  return 500;
}

std::string milliseconds(double ms) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", ms);
  return text;
}

void answer_render(RenderQueue& queue, const httplib::Request& req, httplib::Response& res) {
  ViewRequest request;
  try {
    request = view_request(req.params);
  } catch (const Error& e) {
    res.status = 400;
    res.set_content(std::string("penumbra-view: ") + e.what() + "\n", "text/plain");
    return;
  }
  RenderResult result = queue.submit(param(req.params, "client", ""), request).get();
  res.status = status_of(result.outcome);
  if (result.outcome != RenderResult::Outcome::rendered) {
    res.set_content("penumbra-view: " + result.message + "\n", "text/plain");
    return;
  }
  res.set_header("X-Penumbra-Load-Ms", milliseconds(result.view.load_ms));
  res.set_header("X-Penumbra-Light-Ms", milliseconds(result.view.light_ms));
  res.set_header("X-Penumbra-Render-Ms", milliseconds(result.view.render_ms));
  if (!result.view.light_converged) res.set_header("X-Penumbra-Light", "not converged");
  res.set_content(std::string(result.view.png.begin(), result.view.png.end()), "image/png");
}

}  // namespace

ViewRequest view_request(const httplib::Params& params) {
  ViewRequest r;
  r.step = index(params, "step");
  r.field = index(params, "field");
  r.phi = number(params, "phi", "0");
  r.theta = number(params, "theta", "0");
  r.zoom = number(params, "zoom", "1");
  const std::string lit = param(params, "lit", "1");
  if (lit != "0" && lit != "1") throw Error(ErrorCode::invalid_argument, "parameter 'lit' must be 0 or 1");
  r.lit = lit == "1";
  const std::string tf = param(params, "tf", "");
  if (!tf.empty()) r.transfer_function = transfer_function(tf);
  return r;
}

std::string store_info_json(const StoreInfo& info) {
  json tfs = json::array();
  for (const auto& tf : info.transfer_functions) tfs.push_back(transfer_function_json(tf));
  return json{{"times", info.times},         {"cycles", info.cycles},     {"fields", info.fields},
              {"transfer_functions", tfs},   {"lighting", info.lighting}, {"width", info.width},
              {"height", info.height},       {"fov_y_deg", info.fov_y_deg}}
      .dump();
}

void add_render_routes(httplib::Server& server, RenderQueue& queue) {
  server.Get("/api/store", [&queue](const httplib::Request&, httplib::Response& res) {
    res.set_content(store_info_json(queue.info()), "application/json");
  });
  server.Get("/api/render", [&queue](const httplib::Request& req, httplib::Response& res) {
    answer_render(queue, req, res);
  });
}

}  // namespace penumbra::viewer
