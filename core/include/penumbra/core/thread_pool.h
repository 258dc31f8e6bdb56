// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/thread_pool.h
#pragma once
#include <cstddef>
#include <functional>

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra {

/// Number of worker threads Penumbra uses: PNB_NUM_THREADS if set, else hardware concurrency.
unsigned worker_count();

/// Runs body(begin, end) over [0, n) split into chunks of `grain`, on up to worker_count()
/// threads (the caller and workers kept between calls), chunks handed out dynamically. Returns
/// after all chunks ran. The first exception thrown by a chunk is rethrown on the caller's
/// thread after the others finish. Safe to call from several threads at once and from inside a
/// body: a call that finds the kept workers busy starts threads of its own.
void parallel_for(std::size_t n, std::size_t grain, const std::function<void(std::size_t, std::size_t)>& body);

/// While one lives, parallel_for calls made on its thread run every chunk on that thread, in
/// order (the first exception ends the call). For a thread that must leave the other cores to a
/// background job it waits on, such as a page load its next reads need.
class SerialScope {
public:
  SerialScope();
  ~SerialScope();
  SerialScope(const SerialScope&) = delete;
  SerialScope& operator=(const SerialScope&) = delete;
};

}  // namespace penumbra

PNB_PUBLIC_END
