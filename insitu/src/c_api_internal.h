// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/c_api_internal.h -- what the MPI library's C API shares with the serial one
#pragma once
#include <memory>
#include <string>

#include "penumbra/penumbra.h"
#include "rank_group.h"

namespace penumbra::insitu {

/// pnb_create on the ranks of `group` (collective when it has several): a failure on any rank
/// fails every rank's call, naming the rank. `call` names the C function in errors.
pnb_status create_context(const char* call, const char* config, std::shared_ptr<RankGroup> group, pnb_context* out);

/// Records `message` as the failure of a creation (pnb_last_error(NULL)) and returns `status`.
pnb_status creation_failed(pnb_status status, const std::string& message);

}  // namespace penumbra::insitu
