// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/async_runner.h -- "async": a context's steps rendered on a worker thread
#pragma once
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "context.h"

namespace penumbra::insitu {

/// Runs a Context's steps on a worker thread. On the solver's thread, execute() decides the step
/// (the trigger, as Context::decide_step) and, when it renders or stores, copies the fields it
/// reads into buffers reused across steps and hands them to the worker, which records, renders,
/// writes and commits them (Context::run_step) while the solver goes on. One step at a time: a
/// step that needs the worker while it is busy waits for it, or with skip_when_busy is skipped
/// and counted (the database and the store never see it). A worker's failure is thrown by the
/// next execute() (after that step is handed over) or by finalize(). The mesh is published with
/// the worker idle. Every method is called from one thread (the solver's); the Context is used
/// by the worker only between a hand-over and its completion. Over MPI ranks (which needs
/// MPI_THREAD_MULTIPLE) the solver's thread decides steps through a duplicate of the context's
/// communicator while the worker composites through the context's own, and a busy worker on any
/// rank makes every rank skip or wait alike.
class AsyncRunner {
public:
  AsyncRunner(std::unique_ptr<Context> context, bool skip_when_busy);
  /// Drains the worker (its failure, if any, is lost: call finalize() to see it) and joins it.
  ~AsyncRunner();
  AsyncRunner(const AsyncRunner&) = delete;
  AsyncRunner& operator=(const AsyncRunner&) = delete;

  /// A new topology (or points that break the prepared mesh's welds, or any mesh over several
  /// ranks or with ghost cells) waits for the worker and is prepared here. Points that moved under
  /// the prepared topology are copied and handed to the worker with the next step it takes, which
  /// moves the geometry there; their errors (a tet the motion inverted) are that step's.
  void publish_mesh(const MeshView& mesh);
  /// Context::agree_arguments, on the solver's thread while the worker may run.
  void agree_arguments(const char* call, const std::function<void()>& check) { m_context->agree_arguments(call, check); }
  /// Checked now (Context::check_field); borrowed fields are read by the next execute(), copied
  /// ones kept until replaced or the topology changes, as with a Context.
  void publish_field(const FieldView& field, bool copy);
  /// Returns whether the step renders (handed to the worker, which renders it; false for a step
  /// skipped because the worker was busy).
  bool execute(double time, std::int64_t cycle);
  StepNeeds step_needs(double time, std::int64_t cycle) const;
  /// The last step the worker completed.
  StepStats last_step() const;
  std::int64_t skipped_steps() const { return m_skipped; }
  /// Waits for the worker, throws its failure if it had one, and finalizes the context.
  void finalize();
  bool finalized() const { return m_context->finalized(); }

private:
  /// A field as the worker reads it: its values packed into a buffer kept across steps.
  struct FieldCopy {
    FieldView view;
    std::vector<std::byte> bytes;
  };
  /// A failure as it crosses threads: a plain string, since std::runtime_error's message is a
  /// reference-counted string whose count the solver's and the worker's copies would share.
  struct Failure {
    ErrorCode code;
    std::string message;
  };
  struct Job {
    double time = 0;
    std::int64_t cycle = 0;
    StepDecision decision;
    std::vector<FieldCopy> fields;
    std::optional<std::vector<Vec3d>> points;  ///< the mesh's points moved since the last step
  };
  /// How a mesh is published: prepared here with the worker idle, the prepared mesh as the last
  /// step left it, or its points moved (handed to the worker with the next step, as copied into
  /// `points` on the way).
  enum class Publication { here, unchanged, moved };
  Publication publication_of(const MeshView& mesh, std::vector<Vec3d>& points) const;
  /// The prepared mesh's counts and tets, after a publication here or a step the worker completed.
  void note_prepared_mesh();
  /// execute() without its accounting: the decision, and the hand-over to the worker.
  bool hand_over(double time, std::int64_t cycle);
  void run();
  void wait_idle();
  bool busy();
  /// The worker's failure not yet reported, taken.
  std::optional<Error> take_failure();
  /// Copies of the `names` that were published, in the last job's buffers where there are some.
  std::vector<FieldCopy> copies_of(const std::vector<std::string>& names, const std::map<std::string, FieldView>& published);

  std::unique_ptr<Context> m_context;
  bool m_skip_when_busy;
  std::map<std::string, FieldCopy> m_copied;     ///< published with copy = true
  std::map<std::string, FieldView> m_borrowed;   ///< published with copy = false, for the next step
  std::int64_t m_skipped = 0;
  std::optional<std::vector<Vec3d>> m_moved_points;  ///< published, for the next step handed over
  std::shared_ptr<const render::TetMesh> m_prepared;  ///< the prepared mesh as the last step left it

  mutable std::mutex m_mutex;
  std::condition_variable m_wake;
  std::optional<Job> m_job;        ///< handed over, not yet completed
  std::vector<FieldCopy> m_spare;  ///< buffers of the last completed job, reused
  std::vector<Vec3d> m_spare_points;
  std::optional<Failure> m_failure;  ///< the worker's, not yet thrown
  StepStats m_last_step;
  bool m_stopping = false;
  std::thread m_worker;
};

}  // namespace penumbra::insitu
