// SPDX-License-Identifier: BSD-3-Clause
// bench/render/frame_report.h -- reference images and the JSON keys every frame benchmark shares
#pragma once
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "penumbra/render/tet_mesh.h"
#include "scene.h"

namespace penumbra::bench {

/// The scene's cached reference image (8-bit RGB at reference_path()). Throws naming `who` and
/// the path when it is missing (`writer` computes it) or has another size.
std::vector<unsigned char> cached_reference(const Scene& scene, const std::string& data_dir, const std::string& who,
                                            const std::string& writer);

/// The scene's reference image: rendered by render_reference and cached when missing (or when
/// `refresh`), else read from the cache. `render_ms` is the render time, -1 when it was read.
std::vector<unsigned char> reference_image(const Scene& scene, const render::TetMesh& mesh, const std::string& data_dir,
                                           bool refresh, double& render_ms);

/// Writes a benchmark's frame `rgb` to `image_path` and returns the keys every frame line has:
/// bench, scene, renderer, sizes, frames, ms_per_frame (median of `times`), ms_min, and, when
/// `reference` is not empty, rms_error_pct, max_abs_error and bad_pixels against it.
nlohmann::ordered_json frame_line(const std::string& bench, const std::string& renderer, const Scene& scene,
                                  const std::vector<double>& times, const std::vector<unsigned char>& rgb,
                                  const std::vector<unsigned char>& reference, const std::string& image_path);

}  // namespace penumbra::bench
