// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/rank_group.h -- the processes one run spans: one (serial) or an MPI communicator's
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "penumbra/core/vec3.h"
#include "penumbra/render/image.h"
#include "penumbra/render/renderer.h"

namespace penumbra::insitu {

/// What a Context asks of the ranks it runs on. A serial run is one rank (serial_group()); an MPI
/// run's group lives in the MPI library (insitu/mpi), so that this library never links MPI. Every
/// call but rank() and size() is collective: all ranks make it, in the same order.
class RankGroup {
public:
  virtual ~RankGroup() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  /// Each rank's failure of a phase ("" when it succeeded), agreed: every rank gets, for each
  /// rank that failed, its number, error code and message (ranks in order); empty when none did.
  struct Failure {
    int rank = 0;
    int code = 0;
    std::string message;
  };
  virtual std::vector<Failure> failures(int code, const std::string& message) = 0;
  /// Element-wise minimum of `values` over the ranks, in place.
  virtual void minimum(double* values, int count) = 0;
  /// Element-wise maximum over the ranks, in place (`count` the same on every rank).
  virtual void maximum(float* values, std::size_t count) = 0;
  virtual void maximum(std::uint8_t* values, std::size_t count) = 0;
  /// Every rank's `mine`, rank after rank (the same size on every rank).
  virtual std::vector<double> all_gather(const std::vector<double>& mine) = 0;
  /// Sends `to_each[r]` to rank r (size() entries) and returns what each rank sent this one,
  /// indexed by the sender.
  virtual std::vector<std::vector<double>> exchange(const std::vector<std::vector<double>>& to_each) = 0;
  /// The ranks' runs of one view merged: every pixel's runs in depth order, composited front to
  /// back ("over"). Returns the whole image on rank 0 and an empty one elsewhere.
  virtual render::Image composite(const render::RayRuns& runs, int width, int height) = 0;
  /// Another group over the same ranks whose messages never meet this one's, so that two threads
  /// may each talk through one (an asynchronous run decides steps on the solver's thread while
  /// its worker renders them). Collective.
  virtual std::shared_ptr<RankGroup> duplicate() = 0;
  /// Empty when two threads may communicate at once (a serial group; MPI_THREAD_MULTIPLE), else
  /// the thread support the solver initialised MPI with ("MPI_THREAD_FUNNELED").
  virtual std::string threads_refused() const = 0;
};

/// The one rank of a process that renders alone.
std::shared_ptr<RankGroup> serial_group();

/// The union of every rank's bounds (collective).
Bounds global_bounds(RankGroup& group, const Bounds& mine);

/// The smallest `lo` and largest `hi` over the ranks (collective).
void global_range(RankGroup& group, double& lo, double& hi);

}  // namespace penumbra::insitu
