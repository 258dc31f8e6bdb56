// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/progress_log.cpp
#include "progress_log.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>

#include "penumbra/core/error.h"

namespace penumbra::insitu {
namespace {

double ms(double v) { return std::round(v * 1000) / 1000; }

[[noreturn]] void fail(const std::string& what, const std::string& path, int err) {
  throw Error(ErrorCode::io_error, "progress log: " + what + " '" + path + "': " + std::strerror(err));
}

}  // namespace

ProgressLog::ProgressLog(const ProgressConfig& config) : m_config(config) {
  if (m_config.log.empty()) return;
  m_fd = ::open(m_config.log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (m_fd < 0) fail("cannot open", m_config.log, errno);
}

ProgressLog::~ProgressLog() {
  if (m_fd >= 0) ::close(m_fd);
}

std::string ProgressLog::json_line(const StepReport& step) {
  const StepStats& s = *step.stats;
  nlohmann::ordered_json j;
  j["cycle"] = s.cycle;
  j["time"] = step.time;
  j["images"] = s.images;
  j["fields"] = step.fields;
  j["ms"] = {{"total", ms(s.total_ms)},         {"store", ms(s.store_ms)},   {"gather", ms(s.gather_ms)},
             {"light", ms(s.light_ms)},         {"render", ms(s.render_ms)}, {"composite", ms(s.composite_ms)},
             {"write", ms(s.write_ms)},         {"other", ms(s.other_ms)}};
  if (s.light_ms > 0) j["light"] = {{"converged", s.light.converged}, {"residual", s.light.residual}};
  if (s.budget_ms > 0) j["budget_ms"] = ms(s.budget_ms);
  j["degraded"] = s.degradation.text();
  j["bytes_written"] = step.bytes_written;
  j["failure"] = step.failure.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(step.failure);
  return j.dump();
}

void ProgressLog::step(const StepReport& step) {
  ++m_steps;
  const StepStats& s = *step.stats;
  if (m_config.stderr_every > 0 && m_steps % m_config.stderr_every == 0)
    std::fprintf(stderr, "penumbra: cycle %lld, time %g: %d image(s) in %.0f ms (render %.0f, light %.0f, write %.0f)%s%s\n",
                 static_cast<long long>(s.cycle), step.time, s.images, s.total_ms, s.render_ms, s.light_ms, s.write_ms,
                 s.degradation.any() ? ("; degraded " + s.degradation.text()).c_str() : "",
                 step.failure.empty() ? "" : "; failed");
  if (m_fd < 0) return;
  const std::string line = json_line(step) + "\n";
  const off_t before = ::lseek(m_fd, 0, SEEK_END);
  const ssize_t n = ::write(m_fd, line.data(), line.size());
  if (n >= 0 && static_cast<std::size_t>(n) == line.size()) return;
  const int err = n < 0 ? errno : ENOSPC;
  // A line the disk could not hold is taken back, so that the log holds whole lines only.
  if (before >= 0 && ::ftruncate(m_fd, before) != 0) {
    // The partial line stays; the error below still names the log.
  }
  fail("cannot write", m_config.log, err);
}

}  // namespace penumbra::insitu
