// SPDX-License-Identifier: BSD-3-Clause
// insitu/mpi/src/run_compositing.h -- sort-last compositing of the ranks' ray runs
#pragma once
#include <mpi.h>

#include "penumbra/render/image.h"
#include "penumbra/render/renderer.h"

namespace penumbra::insitu {

/// Merges every rank's runs of one view (direct send): the image's rows are cut into one band per
/// rank; after an MPI_Alltoall of the counts, each rank sends each rank whose band its runs reach
/// (and no other: sparse_alltoallv) its runs in that band (runs already lie in pixel order, so a
/// band's are one contiguous stretch) and, for the pixels that have runs only, their place and
/// run count; it puts the runs of each pixel of its own band in depth order and
/// composites them front to back ("over", premultiplied colour); rank 0 gathers the bands. Exact on any partition: runs of different ranks never overlap in depth, so their
/// order along a ray is the order of their entries. Returns the image on rank 0 and an empty one
/// elsewhere. Collective over `comm`.
render::Image composite_runs(MPI_Comm comm, const render::RayRuns& runs, int width, int height);

/// `count` runs of one pixel, front to back, composited into rgba (premultiplied colour and
/// opacity, as render::Image holds them).
void composite_in_order(const render::RayRun* runs, std::size_t count, float rgba[4]);

/// One pixel's runs, in any order: sorted in place by depth, then composited.
void composite_pixel(std::vector<render::RayRun>& runs, float rgba[4]);

}  // namespace penumbra::insitu
