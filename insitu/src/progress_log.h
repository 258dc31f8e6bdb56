// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/progress_log.h -- what each rendered step did, for people and for tools
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "config.h"
#include "context.h"

namespace penumbra::insitu {

/// One rendered step as the progress log reports it.
struct StepReport {
  double time = 0;
  const StepStats* stats = nullptr;
  std::vector<std::string> fields;  ///< the database's `field` values rendered
  std::uint64_t bytes_written = 0;  ///< the step's PNG files
  std::string failure;              ///< the step's error message; empty when it succeeded
};

/// "progress": one JSON line per rendered step appended to the log file (each line one write of
/// an O_APPEND descriptor; a line the disk cannot hold is truncated away), and a short line on
/// stderr every `stderr_every` rendered steps. Not thread-safe: the context's thread writes it.
class ProgressLog {
public:
  /// Opens (or creates) the log; throws Error(io_error) naming it when it cannot.
  explicit ProgressLog(const ProgressConfig& config);
  ~ProgressLog();
  ProgressLog(const ProgressLog&) = delete;
  ProgressLog& operator=(const ProgressLog&) = delete;

  /// Reports `step`; throws Error(io_error) naming the log when its line cannot be written
  /// (a full disk), after the stderr line.
  void step(const StepReport& step);

  /// The step's JSON line (without the newline).
  static std::string json_line(const StepReport& step);

private:
  ProgressConfig m_config;
  int m_fd = -1;
  std::int64_t m_steps = 0;
};

}  // namespace penumbra::insitu
