// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/trigger.h -- decides which execute() calls render
#pragma once
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "config.h"

namespace penumbra::insitu {

/// Decides whether a step renders. Three independent rules, combined with "or":
/// - every_cycles = N: the step renders when cycle % N == 0 (cycle 0, N, 2N, ...). Depends on the
///   cycle alone, so a restarted run renders the same cycles as an uninterrupted one.
/// - every_time = T: the step renders when its time has entered a new interval [kT, (k+1)T)
///   since the last step that rendered by this rule, and on the first step seen. Solvers' time
///   steps rarely land on multiples of T; this renders the first step at or after each multiple.
///   A relative tolerance of 1e-9 keeps t = 0.3 in interval 3 for T = 0.1 despite rounding.
/// - when = EXPRESSION: the step renders when the expression holds for the statistics of the last
///   step observed (the step before: so that pnb_step_needs knows before the solver builds its
///   arrays, and pnb_execute decides the same); change() is measured from the statistics with
///   which it last fired. Before any step was observed it does not fire.
/// With max_share, a step these rules render is left out while the share of the solver's wall
/// time spent inside pnb_execute, as observed after the last step, exceeds it (an adaptive
/// cadence: renders resume as the share falls).
class Trigger {
public:
  explicit Trigger(const TriggerConfig& config) : m_config(config) {}

  /// True when the step (time, cycle) renders; records it for the time rule.
  bool fires(double time, std::int64_t cycle) {
    const bool fire = would_fire(time, cycle);
    // A step left out for the share is not recorded: the next one may take its place.
    if (fire && m_config.every_time > 0 && by_time(time)) m_last_interval = interval(time);
    if (fire && by_statistics()) m_at_last_fire = m_latest;
    return fire;
  }

  /// The statistics of a step's `when` fields, for the next decisions.
  void observe(StatsByField stats) { m_latest = std::move(stats); }
  /// The fields `when` reads (none without it).
  const std::vector<std::string>& watched_fields() const { return m_config.when ? m_config.when->fields() : m_none; }

  /// What fires() would answer for the step, recording nothing (pnb_step_needs asks it before
  /// the solver builds its arrays).
  bool would_fire(double time, std::int64_t cycle) const {
    bool fire = false;
    if (m_config.every_cycles > 0) {
      const std::int64_t n = m_config.every_cycles;
      fire = ((cycle % n) + n) % n == 0;
    }
    fire = fire || (m_config.every_time > 0 && by_time(time)) || by_statistics();
    return fire && !over_share();
  }

  /// The share of the solver's wall time spent inside pnb_execute so far, for the next decisions.
  void observe_share(double share) { m_share = share; }

private:
  double interval(double time) const { return std::floor(time / m_config.every_time + 1e-9); }
  bool by_time(double time) const { return !m_last_interval || interval(time) > *m_last_interval; }
  bool over_share() const { return m_config.max_share > 0 && m_share > m_config.max_share; }
  bool by_statistics() const {
    return m_config.when && m_latest && m_config.when->holds(*m_latest, m_at_last_fire ? &*m_at_last_fire : nullptr);
  }

  TriggerConfig m_config;
  std::optional<double> m_last_interval;
  std::optional<StatsByField> m_latest, m_at_last_fire;
  double m_share = 0;
  std::vector<std::string> m_none;
};

}  // namespace penumbra::insitu
