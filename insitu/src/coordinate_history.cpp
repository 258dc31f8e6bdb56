// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/coordinate_history.cpp -- a moving segment's coordinates, by step time
#include "coordinate_history.h"

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "coordinate_store.h"
#include "penumbra/core/error.h"
#include "steps_csv.h"

namespace penumbra::insitu {
namespace {

// `dir`/name.pnbf, or the .partial of a run that died.
std::shared_ptr<compression::CompressedField> open_axis(const std::string& dir, const std::string& name) {
  const std::string whole = dir + "/" + name + ".pnbf", partial = whole + ".partial";
  compression::OpenOptions options;
  if (std::filesystem::exists(whole)) return compression::CompressedField::open(whole, options);
  if (!std::filesystem::exists(partial))
    throw Error(ErrorCode::io_error, "coordinates '" + dir + "': " + name + ".pnbf is missing");
  options.recover_incomplete = true;
  return compression::CompressedField::open(partial, options);
}

}  // namespace

CoordinateHistory::CoordinateHistory(const std::string& segment_dir, std::uint64_t point_count)
    : m_dir(segment_dir + "/coordinates"), m_points(point_count) {
  const std::string first = m_dir + "/" + kFirstMovingStep;
  if (!std::filesystem::exists(first)) return;
  std::ifstream in(first);
  const auto steps = parse_steps_csv(in, "coordinates '" + first + "'");
  if (steps.size() != 1) throw Error(ErrorCode::io_error, "coordinates '" + first + "' must hold one step");
  m_first_time = steps.front().second;
  if (std::filesystem::exists(m_dir + "/" + kExactCoordinates))
    m_exact = std::make_unique<ExactCoordinateReader>(m_dir + "/" + kExactCoordinates, m_points);
  std::vector<std::string> epochs;
  for (const auto& e : std::filesystem::directory_iterator(m_dir))
    if (e.is_directory() && e.path().filename().string().rfind("epoch-", 0) == 0) epochs.push_back(e.path().string());
  std::sort(epochs.begin(), epochs.end());
  for (const std::string& dir : epochs) open_epoch(dir);
}

CoordinateHistory::~CoordinateHistory() = default;

void CoordinateHistory::open_epoch(const std::string& dir) {
  Epoch epoch;
  for (int a = 0; a < 3; ++a) {
    auto file = open_axis(dir, kAxisNames[a]);
    if (file->info().vertex_count != m_points)
      throw Error(ErrorCode::io_error, "coordinates '" + dir + "': " + kAxisNames[a] + " has " +
                                           std::to_string(file->info().vertex_count) + " values per step, the mesh " +
                                           std::to_string(m_points) + " points");
    epoch.pagers[static_cast<std::size_t>(a)] = std::make_unique<compression::Pager>(file);
    epoch.axes[static_cast<std::size_t>(a)] = std::move(file);
  }
  m_epochs.push_back(std::move(epoch));
}

std::int64_t CoordinateHistory::exact_index(double time) const {
  return m_exact ? index_of_time(m_exact->times(), time) : -1;
}

std::pair<int, std::int64_t> CoordinateHistory::epoch_step(double time) const {
  for (std::size_t e = 0; e < m_epochs.size(); ++e) {
    const auto& axes = m_epochs[e].axes;
    const std::int64_t step = index_of_time(axes[0]->times(), time);
    if (step >= 0 && index_of_time(axes[1]->times(), time) == step && index_of_time(axes[2]->times(), time) == step)
      return {static_cast<int>(e), step};
  }
  return {-1, -1};
}

bool CoordinateHistory::has(double time) const { return exact_index(time) >= 0 || epoch_step(time).first >= 0; }

void CoordinateHistory::read(double time, std::vector<double>& xyz) {
  if (const std::int64_t r = exact_index(time); r >= 0) return m_exact->read(static_cast<std::size_t>(r), xyz);
  const auto [e, step] = epoch_step(time);
  if (e < 0)
    throw Error(ErrorCode::invalid_argument, "coordinates '" + m_dir + "': none kept at time " + std::to_string(time));
  xyz.resize(3 * m_points);
  m_axis.resize(m_points);
  for (int a = 0; a < 3; ++a) {
    m_epochs[static_cast<std::size_t>(e)].pagers[static_cast<std::size_t>(a)]->read_step(static_cast<std::uint64_t>(step),
                                                                                       m_axis.data());
    for (std::size_t i = 0; i < m_points; ++i) xyz[3 * i + static_cast<std::size_t>(a)] = m_axis[i];
  }
}

}  // namespace penumbra::insitu
