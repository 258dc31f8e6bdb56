// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/stored_run.cpp -- a store segment opened for re-rendering
#include "penumbra/insitu/stored_run.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "penumbra/compression/field_file.h"
#include "penumbra/compression/pager.h"
#include "penumbra/core/error.h"
#include "coordinate_history.h"
#include "steps_csv.h"
#include "stored_mesh.h"

namespace penumbra::insitu {

struct StoredRun::Impl {
  StoredMesh mesh;
  MeshView view;
  std::vector<std::string> names;
  struct Field {
    std::shared_ptr<compression::CompressedField> file;
    std::unique_ptr<compression::Pager> pager;
  };
  std::map<std::string, Field> fields;
  std::vector<std::pair<std::int64_t, double>> steps;
  std::unique_ptr<CoordinateHistory> coordinates;
};

StoredRun::StoredRun() : m_impl(std::make_unique<Impl>()) {}
StoredRun::~StoredRun() = default;

std::unique_ptr<StoredRun> StoredRun::open(const std::string& dir) {
  std::unique_ptr<StoredRun> run(new StoredRun());
  Impl& im = *run->m_impl;
  if (!std::filesystem::is_directory(dir))
    throw Error(ErrorCode::io_error, "stored run '" + dir + "' is not a directory (expected a store's segment-NNN)");
  im.mesh = read_stored_mesh(dir + "/mesh.pnbm");
  im.view = im.mesh.view();
  {
    std::ifstream in(dir + "/steps.csv");
    if (!in) throw Error(ErrorCode::io_error, "stored run '" + dir + "': steps.csv is missing");
    im.steps = parse_steps_csv(in, "stored run '" + dir + "': steps.csv");
  }
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    const bool partial = name.size() > 13 && name.compare(name.size() - 13, 13, ".pnbf.partial") == 0;
    const bool whole = name.size() > 5 && name.compare(name.size() - 5, 5, ".pnbf") == 0;
    if (!partial && !whole) continue;
    // A run that died before its first window was written left the file empty: no step of it.
    std::error_code ec;
    if (partial && std::filesystem::file_size(e.path(), ec) == 0 && !ec) {
      im.steps.clear();
      continue;
    }
    compression::OpenOptions oo;
    oo.recover_incomplete = partial;  // a run that died: its finished windows
    auto file = compression::CompressedField::open(e.path().string(), oo);
    if (file->info().vertex_count != im.view.point_count())
      throw Error(ErrorCode::io_error, "stored run '" + dir + "': '" + name + "' has " +
                                           std::to_string(file->info().vertex_count) + " values per step, the mesh " +
                                           std::to_string(im.view.point_count()) + " points");
    Impl::Field f;
    f.file = file;
    f.pager = std::make_unique<compression::Pager>(file);
    im.names.push_back(file->info().name);
    im.fields[file->info().name] = std::move(f);
  }
  std::sort(im.names.begin(), im.names.end());
  im.coordinates = std::make_unique<CoordinateHistory>(dir, im.view.point_count());
  // Steps every field can give (a run that died keeps only whole windows), and where the points
  // moved, whose coordinates are kept.
  std::size_t usable = im.steps.size();
  for (const auto& [name, f] : im.fields) usable = std::min<std::size_t>(usable, f.file->step_count());
  const CoordinateHistory& c = *im.coordinates;
  while (usable > 0 && c.moving() && im.steps[usable - 1].second >= c.first_time() && !c.has(im.steps[usable - 1].second))
    --usable;
  im.steps.resize(usable);
  return run;
}

const MeshView& StoredRun::mesh() const { return m_impl->view; }
const std::vector<std::string>& StoredRun::fields() const { return m_impl->names; }
bool StoredRun::points_move() const { return m_impl->coordinates->moving(); }

void StoredRun::read_points(std::size_t step, std::vector<double>& xyz) {
  require(step < step_count(), "stored run: step " + std::to_string(step) + " is beyond the " +
                                   std::to_string(step_count()) + " stored steps");
  const CoordinateHistory& c = *m_impl->coordinates;
  if (c.moving() && time(step) >= c.first_time()) return m_impl->coordinates->read(time(step), xyz);
  xyz = m_impl->mesh.xyz;
}
std::size_t StoredRun::step_count() const { return m_impl->steps.size(); }
double StoredRun::time(std::size_t step) const { return m_impl->steps.at(step).second; }
std::int64_t StoredRun::cycle(std::size_t step) const { return m_impl->steps.at(step).first; }


void StoredRun::start_at(std::size_t step) {
  if (step >= step_count()) return;
  for (auto& [name, f] : m_impl->fields) {
    const std::int64_t own = index_of_time(f.file->times(), time(step));
    if (own >= 0) f.pager->start_at(static_cast<std::uint64_t>(own));
  }
}

template <class T>
void StoredRun::read_values(const std::string& field, std::size_t step, std::vector<T>& out) {
  auto it = m_impl->fields.find(field);
  if (it == m_impl->fields.end()) throw Error(ErrorCode::invalid_argument, "stored run: no field '" + field + "'");
  require(step < step_count(), "stored run: step " + std::to_string(step) + " is beyond the " +
                                   std::to_string(step_count()) + " stored steps");
  const std::int64_t own = index_of_time(it->second.file->times(), time(step));
  if (own < 0)
    throw Error(ErrorCode::invalid_argument, "stored run: field '" + field + "' has no values at time " +
                                                 std::to_string(time(step)));
  out.resize(m_impl->view.point_count());
  it->second.pager->read_step(static_cast<std::uint64_t>(own), out.data());
}

void StoredRun::read(const std::string& field, std::size_t step, std::vector<float>& out) {
  read_values(field, step, out);
}

void StoredRun::read(const std::string& field, std::size_t step, std::vector<double>& out) {
  read_values(field, step, out);
}

}  // namespace penumbra::insitu
