// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/image_writer.h -- the last stage of a step: images into the Cinema database
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cinema_database.h"
#include "config.h"
#include "step_stages.h"

namespace penumbra::insitu {

/// The database values of one image besides the file: the view's camera and field, the step's
/// time and the lighting.
struct ImageLabels {
  std::string time, phi, theta;
  std::string camera;    ///< the `camera` column (configs with look_at cameras)
  std::string field;     ///< the `field` column, also the image's folder
  std::string lighting;  ///< the `lighting` column (configs with lighting)
  std::string degraded;  ///< the `degraded` column (configs with a budget)
  std::string stem;      ///< the image file name without its extension
};

/// Writes composed images as PNGs (atomically) and lists them in the run's Cinema database
/// (spec D), whose columns follow from the config. Opening it opens the database: an output
/// directory that is not empty needs "if_exists": "resume" (CinemaDatabase).
class ImageWriter {
public:
  explicit ImageWriter(const Config& config);
  /// Writes `image`; returns its database row, listed once commit() takes it.
  CinemaDatabase::Row write(const ComposedImage& image, const ImageLabels& labels);
  /// Lists the rows of written images in data.csv (atomically).
  void commit(const std::vector<CinemaDatabase::Row>& rows);
  /// Bytes of the PNG files written since the writer opened.
  std::uint64_t bytes_written() const { return m_bytes; }

private:
  bool m_camera_column, m_lighting_column, m_degraded_column;
  std::uint64_t m_bytes = 0;
  std::unique_ptr<CinemaDatabase> m_database;
};

}  // namespace penumbra::insitu
