// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/light_combination.cpp -- the lights summed into one colour field and copied out
#include "light_combination.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "penumbra/core/elapsed.h"
#include "penumbra/core/thread_pool.h"

namespace penumbra::render::lighting {
namespace {

// Points per task when the points a level-1 piece changed are combined or copied out: a few
// percent of the mesh per piece, so tasks are kept small enough to spread over the cores.
constexpr std::size_t kPointsPerTask = 4096;
// The smallest scattering tolerance (relative to max |L|) that float iterates can meet: an
// iteration that reads only the previous iterate settles within a few units in the last place,
// not on an exact fixed point, so the tolerance is at least 16 of them.
constexpr double kScatterToleranceFloor = 16.0 / (1 << 24);

// The lights' sum at point p, channel c (a light without a solution yet adds nothing).
float light_sum(const std::vector<LightState>& lights, std::size_t p, int c) {
  float v = 0.0f;
  for (const auto& l : lights)
    if (l.has_solution) v += static_cast<float>(l.rho1[p] * l.light.color[c]);
  return v;
}

}  // namespace

LightCombination::LightCombination(std::size_t points)
    : m_points(points), m_colour(3 * points, 0.0f), m_published(m_colour) {}

void LightCombination::mark_changed(const std::vector<std::int32_t>& points) {
  // Listed once, however many passes and lights changed a point in this call, so that the
  // combination and the copy out can work on the points in parallel.
  if (m_listed.size() != m_points) m_listed.assign(m_points, 0);
  for (std::int32_t point : points) {
    std::uint8_t& mark = m_listed[static_cast<std::size_t>(point)];
    if (!mark) m_changed.push_back(point);
    mark = 1;
  }
}

bool LightCombination::combine_is_full() const {
  const std::size_t n = 3 * m_points;
  return m_combine_all || !m_has_colour || m_source.size() != n || m_colour.size() != n;
}

bool LightCombination::publish_is_full() const {
  return combine_is_full() || m_publish_all || m_published.size() != 3 * m_points;
}

void LightCombination::combine(const std::vector<LightState>& lights, bool warm_scatter) {
  const auto start = std::chrono::steady_clock::now();
  const bool full = combine_is_full();
  if (full)
    combine_every_point(lights, warm_scatter);
  else
    combine_changed(lights, warm_scatter);
  m_has_colour = true;
  m_source_scale_stale = true;
  m_combine_all = false;
  (full ? m_full_combine_ms : m_partial_combine_ms) = ms_since(start);
}

// Point value i of the source becomes v. Warm: the colour (the previous scattered field) follows
// the change of its source (exact when the source changed by a constant; `before` is the source
// it was scattered from); otherwise the colour is the unscattered source.
void LightCombination::set_source(std::size_t i, float v, float before, bool warm) {
  m_source[i] = v;
  if (!warm) {
    m_colour[i] = v;
  } else {
    const float delta = v - before;
    if (std::isfinite(delta)) m_colour[i] += delta;
  }
}

void LightCombination::combine_changed(const std::vector<LightState>& lights, bool warm_scatter) {
  parallel_for(m_changed.size(), kPointsPerTask, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      const auto p = static_cast<std::size_t>(m_changed[k]);
      for (int c = 0; c < 3; ++c) set_source(3 * p + c, light_sum(lights, p, c), m_source[3 * p + c], warm_scatter);
      m_listed[p] = 0;
    }
  });
  m_to_publish.insert(m_to_publish.end(), m_changed.begin(), m_changed.end());
  m_changed.clear();
}

void LightCombination::combine_every_point(const std::vector<LightState>& lights, bool warm_scatter) {
  // Runs inside a frame's budget: parallel, and into kept buffers, so that no call pays for
  // fresh pages of a 12-byte-per-point vector.
  for (std::int32_t point : m_changed) m_listed[static_cast<std::size_t>(point)] = 0;
  m_changed.clear();
  m_publish_all = true;
  m_previous_source.swap(m_source);
  m_source.resize(3 * m_points);
  const bool warm = warm_scatter && m_has_colour && m_previous_source.size() == m_source.size();
  if (!warm) m_colour.resize(3 * m_points);
  parallel_for(m_points, 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p)
      for (int c = 0; c < 3; ++c) {
        const std::size_t i = 3 * p + c;
        set_source(i, light_sum(lights, p, c), warm ? m_previous_source[i] : 0.0f, warm);
      }
  });
}

void LightCombination::publish(const std::vector<std::int32_t>& point_order) {
  const auto start = std::chrono::steady_clock::now();
  auto copy_out = [&](std::size_t i) {
    const auto p = static_cast<std::size_t>(point_order[i]);
    for (int c = 0; c < 3; ++c) m_published[3 * p + c] = m_colour[3 * i + c];
  };
  const bool all = m_publish_all || m_published.size() != 3 * m_points;
  if (all) {
    m_published.resize(3 * m_points);
    parallel_for(m_points, 1 << 14, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) copy_out(i);
    });
  } else {
    parallel_for(m_to_publish.size(), kPointsPerTask, [&](std::size_t b, std::size_t e) {
      for (std::size_t k = b; k < e; ++k) copy_out(static_cast<std::size_t>(m_to_publish[k]));
    });
  }
  m_publish_all = false;
  m_to_publish.clear();
  (all ? m_full_publish_ms : m_partial_publish_ms) = ms_since(start);
}

double LightCombination::source_scale() {
  if (m_source_scale_stale) {
    constexpr std::size_t kChunk = 1 << 16;
    std::vector<double> scale((m_source.size() + kChunk - 1) / kChunk, 0.0);
    parallel_for(m_source.size(), kChunk, [&](std::size_t b, std::size_t e) {
      double m = 0;
      for (std::size_t i = b; i < e; ++i)
        if (std::isfinite(m_source[i])) m = std::max(m, static_cast<double>(std::fabs(m_source[i])));
      scale[b / kChunk] = m;
    });
    m_source_scale = scale.empty() ? 0.0 : *std::max_element(scale.begin(), scale.end());
    m_source_scale_stale = false;
  }
  return m_source_scale;
}

double LightCombination::scatter_tolerance(double relative) {
  return std::max(relative, kScatterToleranceFloor) * std::max(source_scale(), 1e-300);
}

void LightCombination::zero_source() {
  m_source.assign(m_colour.size(), 0.0f);
  m_source_scale_stale = true;
}

}  // namespace penumbra::render::lighting
