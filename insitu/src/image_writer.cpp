// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/image_writer.cpp -- PNGs and database rows
#include "image_writer.h"

#include <filesystem>
#include <utility>

#include "penumbra/render/image.h"

namespace penumbra::insitu {
namespace {

std::vector<std::string> database_parameters(const Config& c) {
  std::vector<std::string> p{"time", "phi", "theta"};
  if (!c.look_at.empty()) p.push_back("camera");
  p.push_back("field");
  if (c.lighting) p.push_back("lighting");
  if (c.budget) p.push_back("degraded");
  return p;
}

}  // namespace

ImageWriter::ImageWriter(const Config& config)
    : m_camera_column(!config.look_at.empty()),
      m_lighting_column(config.lighting.has_value()),
      m_degraded_column(config.budget.has_value()),
      m_database(std::make_unique<CinemaDatabase>(config.output_directory, database_parameters(config), config.if_exists,
                                                  config.budget ? 1 : 0)) {}

CinemaDatabase::Row ImageWriter::write(const ComposedImage& image, const ImageLabels& labels) {
  const std::string rel = m_database->new_image_path(labels.field, labels.stem);
  const std::string path = m_database->path_of(rel);
  render::write_png(path, image.rgb, image.width, image.height);
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec) m_bytes += size;
  CinemaDatabase::Row row;
  row.values = {labels.time, labels.phi, labels.theta};
  if (m_camera_column) row.values.push_back(labels.camera);
  row.values.push_back(labels.field);
  if (m_lighting_column) row.values.push_back(labels.lighting);
  if (m_degraded_column) row.values.push_back(labels.degraded);
  row.file = rel;
  return row;
}

void ImageWriter::commit(const std::vector<CinemaDatabase::Row>& rows) {
  if (!rows.empty()) m_database->commit(rows);
}

}  // namespace penumbra::insitu
