// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/light_schedule.h -- one update's budget, spent over pieces of work
#pragma once
#include <chrono>
#include <cstddef>

#include "penumbra/core/elapsed.h"
#include "penumbra/render/light_volume.h"

namespace penumbra::render::lighting {

using Clock = std::chrono::steady_clock;

/// Spends one update's LightBudget (work units and milliseconds) over pieces of work whose
/// costs are expected from their last durations. A piece starts only if it is expected to end
/// within the time budget with room left for what ends the call (copying the results out);
/// the first piece of a call always starts, so that every call makes progress and an overrun is
/// at most one piece. The clock starts with the schedule.
class LightSchedule {
public:
  explicit LightSchedule(const LightBudget& budget);

  /// Whether a piece expected to take `expected_ms` may start: the work-unit cap is not reached
  /// and the piece fits. A piece never timed (expected_ms < 0) starts only as the call's first
  /// or without a time budget.
  bool allows(double expected_ms) const;
  /// A piece ran and finished `units` work units: later pieces must fit beside it.
  void ran_piece(int units);
  /// Whether any piece ran in this call.
  bool ran_any() const { return m_ran_any; }
  int units_spent() const { return m_units; }
  /// Work units the cap leaves (a large number without a cap).
  int units_left() const;

  /// The room kept for what ends the call (ms), in place of the room kept so far.
  void keep_for_end(double ms) { m_end_ms = ms; }
  bool has_time_limit() const;
  /// How many pieces of `piece_ms` each fit in the time left beside the room kept (0 if none).
  std::size_t pieces_that_fit(double piece_ms) const;
  /// When a piece that stops by itself must stop, for `after_ms` of work to follow it within
  /// the budget (never, without a time budget).
  Clock::time_point deadline(double after_ms) const;
  double elapsed_ms() const;

private:
  LightBudget m_budget;
  Clock::time_point m_start;
  double m_end_ms = 0;
  int m_units = 0;
  bool m_ran_any = false;
};

/// Runs f and returns how long it took (ms).
template <class F>
double timed_ms(F&& f) {
  const auto start = Clock::now();
  f();
  return ms_since(start);
}

}  // namespace penumbra::render::lighting
