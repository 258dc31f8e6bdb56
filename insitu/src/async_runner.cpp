// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/async_runner.cpp
#include "async_runner.h"

#include <cmath>
#include <exception>
#include <new>
#include <utility>

namespace penumbra::insitu {

AsyncRunner::AsyncRunner(std::unique_ptr<Context> context, bool skip_when_busy)
    : m_context(std::move(context)), m_skip_when_busy(skip_when_busy) {
  // Over ranks the solver's thread decides through a group of its own while the worker renders.
  if (m_context->ranks().size() > 1) m_context->decide_on_own_group();
  m_worker = std::thread([this] { run(); });
}

AsyncRunner::~AsyncRunner() {
  {
    std::unique_lock<std::mutex> lock(m_mutex);
    m_wake.wait(lock, [this] { return !m_job; });
    m_stopping = true;
  }
  m_wake.notify_all();
  m_worker.join();
}

void AsyncRunner::publish_mesh(const MeshView& mesh) {
  std::vector<Vec3d> points;
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    points = std::move(m_spare_points);
  }
  const Publication how = publication_of(mesh, points);
  if (how == Publication::moved) {
    m_moved_points = std::move(points);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_spare_points = std::move(points);
  }
  if (how == Publication::unchanged) {
    m_moved_points.reset();  // back where the last step left them
    return;
  }
  wait_idle();
  m_moved_points.reset();  // this publication replaces them
  const std::size_t before = m_context->mesh_preparations();
  m_context->publish_mesh(mesh);
  note_prepared_mesh();
  // Fields were sized for the old mesh.
  if (m_context->mesh_preparations() != before) {
    m_copied.clear();
    m_borrowed.clear();
  }
}

AsyncRunner::Publication AsyncRunner::publication_of(const MeshView& mesh, std::vector<Vec3d>& points) const {
  std::shared_ptr<const render::TetMesh> prepared;
  bool moving = false;  // a step in the worker's hands moves the points: "unchanged" is relative to that
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    prepared = m_prepared;
    moving = m_job && m_job->points;
  }
  if (!prepared || m_context->ranks().size() > 1 || mesh.ghost_cells) return Publication::here;
  // Counts that differ under the same version are the preparation's error to report, here.
  if (mesh.topology_version != prepared->topology_version || mesh.point_count() != prepared->points.size() ||
      mesh.cell_count() != m_context->prepared_cell_count())
    return Publication::here;
  bool moved = false;
  points.resize(mesh.point_count());
  // One pass: the copy taken while the points are compared with the prepared ones.
  for (std::size_t i = 0; i < mesh.point_count(); ++i) {
    const Vec3d p = mesh.point(i);
    points[i] = p;
    // Coordinates the prepared mesh refuses (NaN, infinite) are refused here, at once.
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) return Publication::here;
    moved = moved || !(p == prepared->points[i]);
  }
  if (!moved) return moving ? Publication::moved : Publication::unchanged;
  return render::keeps_welds(*prepared, mesh) ? Publication::moved : Publication::here;
}

void AsyncRunner::note_prepared_mesh() {
  std::shared_ptr<const render::TetMesh> tets = m_context->prepared_tets();
  std::lock_guard<std::mutex> lock(m_mutex);
  m_prepared = std::move(tets);
}

void AsyncRunner::publish_field(const FieldView& field, bool copy) {
  if (!m_context->check_field(field)) return;
  if (copy) {
    FieldCopy& copy = m_copied[field.name];
    copy.view = packed_copy(field, copy.bytes);
    m_borrowed.erase(field.name);
  } else {
    m_borrowed[field.name] = field;
    m_copied.erase(field.name);
  }
}

StepNeeds AsyncRunner::step_needs(double time, std::int64_t cycle) const { return m_context->step_needs(time, cycle); }

bool AsyncRunner::execute(double time, std::int64_t cycle) {
  // The solver's time inside the call, for the adaptive cadence: what it waits, not the worker's.
  return m_context->accounted([&] { return hand_over(time, cycle); });
}

bool AsyncRunner::hand_over(double time, std::int64_t cycle) {
  struct ForgetBorrowed {
    std::map<std::string, FieldView>& fields;
    ~ForgetBorrowed() { fields.clear(); }
  } forget{m_borrowed};
  std::map<std::string, FieldView> published = m_borrowed;
  for (const auto& [name, copy] : m_copied) published.emplace(name, copy.view);
  const StepNeeds needs = m_context->step_needs(time, cycle);
  const StepDecision decision = m_context->decide_step(time, cycle, published);
  const bool work = decision.renders || needs.stores;
  bool handed_over = false;
  std::optional<Error> earlier;  // an earlier step's failure: this step's own is the next call's
  // Over ranks every rank skips when any rank's worker is busy, so that all render the same steps.
  if (work && m_skip_when_busy && m_context->on_any_rank(busy())) {
    ++m_skipped;
  } else if (work) {
    handed_over = true;
    wait_idle();
    earlier = take_failure();
    Job job{time, cycle, decision, {}, std::move(m_moved_points)};
    try {
      job.fields = copies_of(needs.fields, published);
    } catch (const std::exception& e) {
      // This rank's worker still takes the step, so that it meets the other ranks' collectives:
      // without its fields, and with the failure, which the step's report agrees on every rank.
      job.fields.clear();
      const bool memory = dynamic_cast<const std::bad_alloc*>(&e) != nullptr;
      job.decision.failure += (job.decision.failure.empty() ? "" : "; ") + std::string("pnb_execute: copying the step's fields for the worker: ") +
                              (memory ? "out of memory" : e.what());
      job.decision.code = memory ? ErrorCode::out_of_memory : ErrorCode::internal_error;
    }
    m_moved_points.reset();
    {
      std::lock_guard<std::mutex> lock(m_mutex);
      m_job = std::move(job);
    }
    m_wake.notify_all();
  }
  // Over ranks a failure is taken only by a call that waited for the worker (a step handed over,
  // or finalize), which is the same call on every rank; one rank's worker may finish sooner.
  if (!handed_over && m_context->ranks().size() == 1) earlier = take_failure();
  if (earlier) throw *earlier;
  if (!work && !decision.failure.empty()) throw Error(decision.code, decision.failure);
  return handed_over && decision.renders;
}

std::vector<AsyncRunner::FieldCopy> AsyncRunner::copies_of(const std::vector<std::string>& names,
                                                             const std::map<std::string, FieldView>& published) {
  std::vector<FieldCopy> buffers, copies;
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    buffers = std::move(m_spare);
  }
  // A field the step reads but nobody published is the worker's to report, as execute() does.
  for (const std::string& name : names) {
    const auto it = published.find(name);
    if (it == published.end()) continue;
    FieldCopy& copy = copies.emplace_back();
    if (!buffers.empty()) {
      copy = std::move(buffers.back());
      buffers.pop_back();
    }
    copy.view = packed_copy(it->second, copy.bytes);
  }
  return copies;
}

StepStats AsyncRunner::last_step() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_last_step;
}

void AsyncRunner::finalize() {
  wait_idle();
  m_context->finalize();
  if (std::optional<Error> failure = take_failure()) throw *failure;
}

void AsyncRunner::run() {
  for (;;) {
    std::unique_lock<std::mutex> lock(m_mutex);
    m_wake.wait(lock, [this] { return m_stopping || m_job; });
    if (!m_job) return;
    Job& job = *m_job;  // the solver's thread leaves it alone until it is reset
    lock.unlock();
    std::optional<Failure> failure;
    const std::string where = " (cycle " + std::to_string(job.cycle) + ", rendered asynchronously)";
    try {
      if (job.points) m_context->publish_mesh(m_context->moved_view(*job.points));
      for (const FieldCopy& f : job.fields) m_context->publish_field(f.view, false);
      m_context->run_step(job.time, job.cycle, job.decision);
    } catch (const Error& e) {
      failure = Failure{e.code(), e.what() + where};
    } catch (const std::bad_alloc&) {
      failure = Failure{ErrorCode::out_of_memory, "out of memory" + where};
    } catch (const std::exception& e) {
      failure = Failure{ErrorCode::internal_error, e.what() + where};
    }
    m_context->drop_borrowed_fields();
    const StepStats stats = m_context->last_step();
    std::shared_ptr<const render::TetMesh> tets = m_context->prepared_tets();
    lock.lock();
    m_prepared = std::move(tets);
    if (job.points) m_spare_points = std::move(*job.points);
    if (failure) m_failure = std::move(failure);  // the latest: the next call reports one, naming its cycle
    m_last_step = stats;
    m_spare = std::move(job.fields);
    m_job.reset();
    lock.unlock();
    m_wake.notify_all();
  }
}

void AsyncRunner::wait_idle() {
  std::unique_lock<std::mutex> lock(m_mutex);
  m_wake.wait(lock, [this] { return !m_job; });
}

bool AsyncRunner::busy() {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_job.has_value();
}

std::optional<Error> AsyncRunner::take_failure() {
  std::optional<Failure> failure;
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    failure.swap(m_failure);
  }
  if (!failure) return std::nullopt;
  return Error(failure->code, failure->message);
}

}  // namespace penumbra::insitu
