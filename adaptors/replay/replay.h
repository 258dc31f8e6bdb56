// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/replay.h -- penumbra-replay: drive the C API from files as if a solver ran
#pragma once
#include <iosfwd>
#include <string>
#include <vector>

namespace penumbra::replay {

/// Runs `penumbra-replay CONFIG INPUT [--steps a:b] [--quiet]` with `args` (without the
/// program name), writing progress to `out` and errors to `err`. Returns the exit status:
/// 0 success, 1 a read, publish or execute failure (the run continues past failed steps, as
/// the runtime does, and reports them at the end), 2 a usage error. Never throws.
///
/// The mesh is published once with topology_version 1 and republished, with the version
/// bumped, only when a step's points or cells differ from the last published ones. Every
/// float/double point and cell array is published each step as a view (the runtime ignores
/// those the config does not render); arrays that would need a conversion (integer ids,
/// materials) are converted only when the config renders them. TIME/CYCLE come from the data
/// when present.
int run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

/// The usage text.
std::string usage();

}  // namespace penumbra::replay
