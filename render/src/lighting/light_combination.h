// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/light_combination.h -- the lights summed into one colour field and copied out
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "light_state.h"

namespace penumbra::render::lighting {

/// The lights' sum per point (eq. 9), which is the scattering's source, the light colour L
/// (the source, or its scattered field), and L copied out in the caller's point order. After a
/// level-1 piece only the points it changed are combined and copied out; a change of the lights,
/// of their colours or of the scattering combines every point. Combining and copying out end an
/// update, outside its pieces, so their expected durations are kept for the budget.
class LightCombination {
public:
  /// Zero light at `points` points.
  explicit LightCombination(std::size_t points);

  /// The next combine() and publish() take every point.
  void recombine_all() { m_combine_all = true; }
  /// These points' level-1 values changed: the next combine() takes them, each once however
  /// often it is listed.
  void mark_changed(const std::vector<std::int32_t>& points);
  bool has_changes() const { return m_combine_all || !m_changed.empty(); }
  /// Sums the lights at the points that changed (every point after recombine_all). With
  /// `warm_scatter` the colour follows its source's change, so that the previous scattering is
  /// a warm start for the next; otherwise the colour is the source.
  void combine(const std::vector<LightState>& lights, bool warm_scatter);
  /// Copies the colour out to the caller's order (point i is the caller's point_order[i]): every
  /// point after a full combine or a scattering, else those of the last combine.
  void publish(const std::vector<std::int32_t>& point_order);
  /// The scattering replaced the colour at every point: the next publish takes them all.
  void publish_all_next() { m_publish_all = true; }

  /// The next combine's and publish's expected durations (ms): the last of the same kind, all
  /// points or the few a level-1 piece changed.
  double expected_combine_ms() const { return combine_is_full() ? m_full_combine_ms : m_partial_combine_ms; }
  double expected_publish_ms() const { return publish_is_full() ? m_full_publish_ms : m_partial_publish_ms; }
  /// The last publish of every point (ms): what a call that scatters keeps room for.
  double full_publish_ms() const { return m_full_publish_ms; }

  /// The scattering's source, 3 floats per point.
  const std::vector<float>& source() const { return m_source; }
  /// The light colour, 3 floats per point: the scattering's start and result.
  std::vector<float>& colour() { return m_colour; }
  /// light_rgb(): the colour in the caller's point order.
  const std::vector<float>& published() const { return m_published; }
  /// The largest finite |source|: the scale of the scattering's tolerance, recomputed after each
  /// combine when first asked for.
  double source_scale();
  /// The scattering's stopping change: `relative` (raised to what float iterates can meet) times
  /// source_scale().
  double scatter_tolerance(double relative);
  /// A zero source at every point, its scale to be recomputed: what the scattering's set-up is
  /// timed on before there is a source.
  void zero_source();

private:
  bool combine_is_full() const;
  bool publish_is_full() const;
  void combine_changed(const std::vector<LightState>& lights, bool warm_scatter);
  void combine_every_point(const std::vector<LightState>& lights, bool warm_scatter);
  void set_source(std::size_t i, float v, float before, bool warm);

  std::size_t m_points;
  std::vector<float> m_source, m_previous_source, m_colour, m_published;
  bool m_has_colour = false;
  // Whether the next combine takes every point (else the listed ones), and whether the next
  // publish does (else those of the last combine).
  bool m_combine_all = true, m_publish_all = true;
  std::vector<std::int32_t> m_changed, m_to_publish;
  std::vector<std::uint8_t> m_listed;  // per point: in m_changed
  double m_source_scale = 0;
  bool m_source_scale_stale = true;
  double m_full_combine_ms = 0, m_partial_combine_ms = 0, m_full_publish_ms = 0, m_partial_publish_ms = 0;
};

}  // namespace penumbra::render::lighting
