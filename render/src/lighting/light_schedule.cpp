// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/light_schedule.cpp -- one update's budget, spent over pieces of work
#include "light_schedule.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "penumbra/core/elapsed.h"

namespace penumbra::render::lighting {

LightSchedule::LightSchedule(const LightBudget& budget) : m_budget(budget), m_start(Clock::now()) {}

bool LightSchedule::allows(double expected_ms) const {
  if (m_budget.max_work_units >= 0 && m_units >= m_budget.max_work_units) return false;
  if (expected_ms < 0) return !m_ran_any || !has_time_limit();
  return !m_ran_any || elapsed_ms() + expected_ms + m_end_ms < m_budget.max_ms;
}

void LightSchedule::ran_piece(int units) {
  m_units += units;
  m_ran_any = true;
}

int LightSchedule::units_left() const {
  if (m_budget.max_work_units < 0) return std::numeric_limits<int>::max();
  return m_budget.max_work_units - m_units;
}

bool LightSchedule::has_time_limit() const { return std::isfinite(m_budget.max_ms); }

std::size_t LightSchedule::pieces_that_fit(double piece_ms) const {
  const double room = m_budget.max_ms - elapsed_ms() - m_end_ms;
  return static_cast<std::size_t>(std::max(0.0, room / piece_ms));
}

Clock::time_point LightSchedule::deadline(double after_ms) const {
  if (!has_time_limit()) return Clock::time_point::max();
  return m_start + std::chrono::duration_cast<Clock::duration>(
                       std::chrono::duration<double, std::milli>(m_budget.max_ms - after_ms));
}

double LightSchedule::elapsed_ms() const { return ms_since(m_start); }

}  // namespace penumbra::render::lighting
