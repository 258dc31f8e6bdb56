// SPDX-License-Identifier: BSD-3-Clause
// core/src/thread_pool.cpp
#include "penumbra/core/thread_pool.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

#include <pthread.h>
#include <unistd.h>

namespace penumbra {

namespace {

// Set in the child of a fork (pthread_atfork, registered with the pool): the child has none of the
// parent's workers. A flag rather than comparing getpid() per call, which would put a system
// call in every parallel_for. A child made by a
// raw clone() runs no fork handlers and is not detected: it would find the pool busy or wait on
// workers it does not have.
std::atomic<bool> g_forked_child{false};

// Threads kept between calls: starting a thread costs a good part of what a one-step decode or a
// light-volume piece of a frame budget takes (docs/pager.md, "The thread pool"). One job
// at a time; a call that finds the pool busy (another thread's job, or a parallel_for inside a
// body) starts its own threads as before, so nothing waits on the pool and nesting cannot
// deadlock.
class WorkerPool {
public:
  // Never destroyed: a parallel_for from another static's destructor, or from a thread still
  // running at exit, must not meet a destroyed pool. The idle workers end with the process.
  static WorkerPool& instance() {
    static WorkerPool* pool = new WorkerPool(worker_count() > 1 ? worker_count() - 1 : 0);
    return *pool;
  }

  /// Runs `work` on the caller and on up to `helpers` workers; false (nothing run) when the
  /// pool is busy or too small, or in a forked child, which has none of the workers (and whose
  /// copy of the mutex may have been held by another parent thread at the fork).
  bool try_run(unsigned helpers, const std::function<void()>& work) {
    if (g_forked_child.load(std::memory_order_relaxed)) return false;
    if (!m_fork_handler && ::getpid() != m_pid) return false;
    {
      std::lock_guard<std::mutex> lock(m_mutex);
      if (m_busy || helpers > m_threads.size()) return false;
      m_busy = true;
      m_job = &work;
      m_wanted = helpers;
      m_joined = 0;
      m_generation.fetch_add(1, std::memory_order_release);
    }
    m_wake.notify_all();
    work();
    {
      // No worker may join after this: `work` refers to the caller's frame.
      std::lock_guard<std::mutex> lock(m_mutex);
      m_job = nullptr;
    }
    spin_while([&] { return m_running.load(std::memory_order_acquire) != 0; });
    std::unique_lock<std::mutex> lock(m_mutex);
    m_done.wait(lock, [&] { return m_running.load(std::memory_order_relaxed) == 0; });
    m_busy = false;
    return true;
  }

private:
  explicit WorkerPool(unsigned threads)
      : m_fork_handler(pthread_atfork(nullptr, nullptr, [] { g_forked_child.store(true, std::memory_order_relaxed); }) == 0),
        m_pid(::getpid()) {
    // Fewer workers if the system refuses threads (a container's limit): never an abort.
    for (unsigned i = 0; i < threads; ++i) {
      try {
        m_threads.emplace_back([this] { serve(); });
      } catch (const std::system_error&) {
        break;
      }
      m_threads.back().detach();
    }
  }

  // Waking a thread blocked on a condition variable can take a sizeable part of a short job (a
  // light-volume pass runs one job per slab of vertices, hundreds per pass). So a worker that has
  // just finished, and a caller waiting for its helpers, first poll for up to kSpin before they
  // block: jobs that follow each other closely then start at once.
  static constexpr auto kSpin = std::chrono::microseconds(100);
  template <class Pending>
  static void spin_while(const Pending& pending) {
    const auto until = std::chrono::steady_clock::now() + kSpin;
    for (int polls = 1; pending(); ++polls) {
#if defined(__x86_64__) || defined(__i386__)
      __builtin_ia32_pause();
#endif
      if (polls % 64 == 0 && std::chrono::steady_clock::now() >= until) return;
    }
  }

  void serve() {
    std::uint64_t seen = 0;
    for (;;) {
      spin_while([&] { return m_generation.load(std::memory_order_acquire) == seen; });
      std::unique_lock<std::mutex> lock(m_mutex);
      m_wake.wait(lock, [&] { return m_generation.load(std::memory_order_relaxed) != seen; });
      seen = m_generation.load(std::memory_order_relaxed);
      if (m_job == nullptr || m_joined >= m_wanted) continue;
      ++m_joined;
      m_running.fetch_add(1, std::memory_order_relaxed);
      const std::function<void()>* job = m_job;
      lock.unlock();
      (*job)();
      lock.lock();
      if (m_running.fetch_sub(1, std::memory_order_release) == 1) m_done.notify_all();
    }
  }

  std::mutex m_mutex;
  std::condition_variable m_wake, m_done;
  std::vector<std::thread> m_threads;
  const std::function<void()>* m_job = nullptr;
  unsigned m_wanted = 0, m_joined = 0;
  std::atomic<unsigned> m_running{0};            // changed under m_mutex; polled without it
  std::atomic<std::uint64_t> m_generation{0};    // likewise
  bool m_busy = false;
  const bool m_fork_handler;  // false: pthread_atfork refused, so compare the pid instead
  const pid_t m_pid;
};

}  // namespace

unsigned worker_count() {
  if (const char* env = std::getenv("PNB_NUM_THREADS")) {
    const int n = std::atoi(env);
    if (n > 0) return static_cast<unsigned>(n);
  }
  // Read once: glibc counts the online CPUs from /sys at every call (open, read, close), and
  // every parallel_for asks.
  static const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
  return hardware;
}

namespace {
thread_local unsigned t_serial_scopes = 0;
}  // namespace

SerialScope::SerialScope() { ++t_serial_scopes; }
SerialScope::~SerialScope() { --t_serial_scopes; }

void parallel_for(std::size_t n, std::size_t grain, const std::function<void(std::size_t, std::size_t)>& body) {
  if (n == 0) return;
  grain = std::max<std::size_t>(grain, 1);
  const std::size_t chunks = (n + grain - 1) / grain;
  const unsigned threads =
      t_serial_scopes ? 1u : static_cast<unsigned>(std::min<std::size_t>(worker_count(), chunks));
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  const std::function<void()> work = [&] {
    for (;;) {
      const std::size_t c = next.fetch_add(1);
      if (c >= chunks) return;
      try {
        body(c * grain, std::min(n, (c + 1) * grain));
      } catch (...) {
        std::lock_guard<std::mutex> lock(failure_mutex);
        if (!failure) failure = std::current_exception();
        next = chunks;  // stop handing out work
      }
    }
  };
  if (threads <= 1) {
    work();
  } else if (!WorkerPool::instance().try_run(threads - 1, work)) {
    std::vector<std::thread> pool;
    try {
      for (unsigned t = 1; t < threads; ++t) pool.emplace_back(work);
    } catch (const std::system_error&) {
      // No more threads to be had: the caller and those started share the chunks.
    }
    work();
    for (auto& t : pool) t.join();
  }
  if (failure) std::rethrow_exception(failure);
}

}  // namespace penumbra
