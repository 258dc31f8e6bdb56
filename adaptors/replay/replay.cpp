// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/replay.cpp -- penumbra-replay's driver: files -> adaptor -> C API
#include "replay.h"

#include <vtkUnstructuredGrid.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>

#include "input_series.h"
#include "step_range.h"
#include "store_replay.h"
#include "penumbra/core/elapsed.h"
#include "penumbra/core/error.h"
#include "penumbra/penumbra.h"
#include "penumbra/vtk/unstructured_grid_adaptor.h"

namespace penumbra::replay {
namespace {

struct Options {
  std::string config;
  std::string input;
  std::string steps;  // "a:b" as given, or empty for all
  bool quiet = false;
};


Options parse_args(const std::vector<std::string>& args) {
  Options o;
  std::vector<std::string> positional;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--quiet" || a == "-q") {
      o.quiet = true;
    } else if (a == "--steps") {
      if (i + 1 >= args.size()) throw UsageError("--steps needs a value a:b");
      o.steps = args[++i];
    } else if (a.rfind("--steps=", 0) == 0) {
      o.steps = a.substr(8);
    } else if (a.size() > 1 && a[0] == '-') {
      throw UsageError("unknown option '" + a + "'");
    } else {
      positional.push_back(a);
    }
  }
  if (positional.size() != 2) throw UsageError("expected CONFIG and INPUT, got " + std::to_string(positional.size()) + " argument(s)");
  o.config = positional[0];
  o.input = positional[1];
  return o;
}

/// Field names the config renders, or nullopt when the config cannot be read here (the C API
/// then reports the problem itself).
std::optional<std::set<std::string>> configured_fields(const std::string& config) {
  try {
    std::string text = config;
    if (config.find_first_not_of(" \t\r\n") == std::string::npos || config[config.find_first_not_of(" \t\r\n")] != '{') {
      std::ifstream in(config);
      if (!in) return std::nullopt;
      std::ostringstream s;
      s << in.rdbuf();
      text = s.str();
    }
    const auto j = nlohmann::json::parse(text);
    std::set<std::string> names;
    for (const auto& f : j.at("fields")) names.insert(f.at("name").get<std::string>());
    return names;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

bool same_bytes(const void* a, const void* b, std::size_t n) { return a == b || std::memcmp(a, b, n) == 0; }

std::size_t index_size(pnb_type t) { return t == PNB_INT32 ? 4 : 8; }

/// True when two meshes have identical points and cells (so the topology version can stay).
bool same_mesh(const pnb_mesh_desc& a, const pnb_mesh_desc& b) {
  if (a.point_count != b.point_count || a.point_type != b.point_type || a.index_type != b.index_type ||
      a.connectivity_count != b.connectivity_count || a.cell_types_count != b.cell_types_count)
    return false;
  const std::size_t real = a.point_type == PNB_FLOAT32 ? 4 : 8;
  const std::size_t idx = index_size(a.index_type);
  const auto cells = static_cast<std::size_t>(a.cell_types_count);
  return same_bytes(a.points, b.points, static_cast<std::size_t>(a.point_count) * 3 * real) &&
         same_bytes(a.connectivity, b.connectivity, static_cast<std::size_t>(a.connectivity_count) * idx) &&
         same_bytes(a.offsets, b.offsets, (cells + 1) * idx) && same_bytes(a.cell_types, b.cell_types, cells);
}

/// `text` as one stderr line starting with "penumbra-replay: " (added only where missing).
std::string prefixed(const std::string& text) {
  const std::string prefix = "penumbra-replay: ";
  return (text.rfind(prefix, 0) == 0 ? text : prefix + text) + "\n";
}


class Replay {
public:
  Replay(const Options& o, std::ostream& out, std::ostream& err) : m_opt(o), m_out(out), m_err(err) {}
  ~Replay() { pnb_destroy(m_ctx); }

  int run() {
    // A run's compressed history (config "store") replays without VTK readers.
    if (is_store(m_opt.input)) return replay_store(m_opt.config, m_opt.input, m_opt.steps, m_opt.quiet, m_out, m_err);
    auto input = InputSeries::open(m_opt.input);
    const auto [first, last] = step_range(m_opt.steps, input->size());
    if (!m_opt.quiet) m_out << "penumbra-replay: " << input->describe() << ", replaying steps " << first << ".." << last - 1 << "\n";

    // The first step is read and checked before the context exists, so an unreadable input, a
    // surface mesh or a config naming fields the input lacks fails before any database is made.
    auto t0 = std::chrono::steady_clock::now();
    std::optional<Step> step = load(*input, first);
    m_read_ms = ms_since(t0);
    if (!step || !check_first_step(*step)) return 1;
    if (pnb_create(m_opt.config.c_str(), &m_ctx) != PNB_OK) {
      m_err << "penumbra-replay: " << pnb_last_error(nullptr) << "\n";
      return 1;
    }
    for (std::size_t i = first; i < last; ++i) {
      if (i != first) {
        t0 = std::chrono::steady_clock::now();
        step = load(*input, i);
        m_read_ms = ms_since(t0);
      }
      if (step) replay_step(*step, i);
    }
    if (pnb_finalize(m_ctx) != PNB_OK) fail(std::string("finalize: ") + pnb_last_error(m_ctx));
    if (!m_opt.quiet)
      m_out << "penumbra-replay: " << m_executed << " step(s) executed, mesh published " << m_mesh_publications
            << " time(s), " << m_failures << " failure(s)\n";
    return m_failures == 0 ? 0 : 1;
  }

private:
  void fail(const std::string& message) {
    ++m_failures;
    m_err << prefixed(message);
  }

  std::optional<Step> load(InputSeries& input, std::size_t i) {
    try {
      return input.load(i);
    } catch (const Error& e) {
      fail(std::string("step ") + std::to_string(i) + ": " + e.what());
      return std::nullopt;
    }
  }

  bool check_first_step(const Step& step) {
    std::optional<vtk::UnstructuredGridAdaptor> probe;
    try {
      probe.emplace(step.grid);
    } catch (const Error& e) {
      fail("INPUT '" + m_opt.input + "': " + e.what());
      return false;
    }
    m_wanted = configured_fields(m_opt.config);
    const auto& wanted = m_wanted;
    if (!wanted) return true;
    std::string missing, available;
    for (const auto& f : probe->fields()) available += (available.empty() ? "" : ", ") + std::string(f.name);
    for (const auto& name : *wanted)
      if (!probe->find_field(name, PNB_POINT_FIELD) && !probe->find_field(name, PNB_CELL_FIELD))
        missing += (missing.empty() ? "'" : ", '") + name + "'";
    if (missing.empty()) return true;
    fail("CONFIG renders field(s) " + missing + " that INPUT '" + m_opt.input + "' does not have; available: " +
         (available.empty() ? "none (the input is a bare mesh)" : available));
    return false;
  }

  void replay_step(const Step& step, std::size_t index) {
    const auto t0 = std::chrono::steady_clock::now();
    std::optional<vtk::UnstructuredGridAdaptor> adaptor;
    try {
      // Arrays that need a conversion (ids, integer materials) are converted only when the
      // config renders them; the runtime would ignore them anyway.
      vtk::UnstructuredGridAdaptor::CopyFilter filter;
      if (m_wanted) filter = [this](std::string_view name) { return m_wanted->count(std::string(name)) > 0; };
      adaptor.emplace(step.grid, m_version, filter);
    } catch (const Error& e) {
      fail("step " + std::to_string(index) + ": " + e.what());
      return;
    }
    if (!m_published || !same_mesh(m_published->mesh(), adaptor->mesh())) {
      if (m_published) ++m_version;
      pnb_mesh_desc mesh = adaptor->mesh();
      mesh.topology_version = m_version;
      if (!m_opt.quiet) m_out << "  mesh v" << m_version << ": " << adaptor->report().summary() << "\n";
      if (pnb_publish_mesh(m_ctx, &mesh, PNB_BORROW) != PNB_OK) {
        fail("step " + std::to_string(index) + ": publish mesh: " + pnb_last_error(m_ctx));
        return;
      }
      ++m_mesh_publications;
      m_published = std::move(adaptor);
      adaptor.reset();
    }
    // Fields come from this step's grid; its cells match the published mesh (same bytes).
    const vtk::UnstructuredGridAdaptor& fields = adaptor ? *adaptor : *m_published;
    for (const auto& f : fields.fields())
      if (pnb_publish_field(m_ctx, &f, PNB_BORROW) != PNB_OK)
        fail("step " + std::to_string(index) + ": publish field '" + f.name + "': " + pnb_last_error(m_ctx));
    const double publish_ms = ms_since(t0);
    const auto t1 = std::chrono::steady_clock::now();
    const pnb_status status = pnb_execute(m_ctx, step.time, step.cycle);
    const double execute_ms = ms_since(t1);
    ++m_executed;
    if (status != PNB_OK) fail("step " + std::to_string(index) + ": execute: " + pnb_last_error(m_ctx));
    if (!m_opt.quiet)
      m_out << "  step " << index << " time " << step.time << " cycle " << step.cycle << ": "
            << fields.fields().size() << " field(s); read " << m_read_ms << " ms, adapt+publish " << publish_ms
            << " ms, execute " << execute_ms << " ms\n";
  }

  const Options& m_opt;
  std::ostream& m_out;
  std::ostream& m_err;
  pnb_context m_ctx = nullptr;
  std::optional<vtk::UnstructuredGridAdaptor> m_published;
  std::optional<std::set<std::string>> m_wanted;  // field names the config renders, when known
  std::uint64_t m_version = 1;
  double m_read_ms = 0;  // time to read the current step
  std::size_t m_mesh_publications = 0, m_executed = 0, m_failures = 0;
};

}  // namespace

std::string usage() {
  return "usage: penumbra-replay CONFIG INPUT [--steps a:b] [--quiet]\n"
         "  Replays a saved simulation through Penumbra's C API as if the solver were running.\n"
         "  CONFIG  Penumbra JSON config (file path or JSON text)\n"
         "  INPUT   .vtu | legacy .vtk | .pvd | ParaView .series JSON | Exodus II (.e .ex2 .exo)\n"
         "          | a run's compressed history: a store directory (config \"store\") or one of its\n"
         "            segment-NNN folders, re-rendered with CONFIG's cameras and transfer functions\n"
         "  --steps a:b  replay step indices a..b-1 (0-based, half-open; 'a:', ':b' and 'a' work too)\n"
         "  --quiet      print errors only\n"
         "  The mesh is published once (republished with a new topology_version only when points or\n"
         "  cells change); every float/double point and cell array is published each step (arrays\n"
         "  needing conversion, e.g. integer ids, only when the config renders them); TIME/CYCLE\n"
         "  come from the data when present. Exit status: 0 ok, 1 read/render failure, 2 usage error.\n";
}

int run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  try {
    for (const auto& a : args)
      if (a == "--help" || a == "-h") {
        out << usage();
        return 0;
      }
    const Options options = parse_args(args);
    Replay replay(options, out, err);
    return replay.run();
  } catch (const UsageError& e) {
    err << "penumbra-replay: " << e.what() << "\n" << usage();
    return 2;
  } catch (const std::bad_alloc&) {
    err << "penumbra-replay: out of memory\n";
  } catch (const std::exception& e) {
    err << prefixed(e.what());
  } catch (...) {
    err << "penumbra-replay: unknown error\n";
  }
  return 1;
}

}  // namespace penumbra::replay
