// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/input_series.cpp -- readers for the formats penumbra-replay accepts
#include "input_series.h"

#include <vtkDataArray.h>
#include <vtkExodusIIReader.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkLogger.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkOutputWindow.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkUnstructuredGrid.h>
#include <vtkUnstructuredGridReader.h>
#include <vtkXMLDataElement.h>
#include <vtkXMLDataParser.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "grid_merge.h"
#include "netcdf_size.h"
#include "penumbra/core/error.h"

namespace penumbra::replay {
namespace fs = std::filesystem;
namespace {

/// Collects VTK's error and warning text instead of printing it, so a bad file becomes one
/// clear message on our side rather than a page of VTK internals on stderr.
class CapturingOutputWindow : public vtkOutputWindow {
public:
  static CapturingOutputWindow* New();
  vtkTypeMacro(CapturingOutputWindow, vtkOutputWindow);
  void DisplayText(const char*) override {}
  void DisplayErrorText(const char* text) override { m_errors += text ? text : ""; }
  void DisplayWarningText(const char*) override {}
  void DisplayGenericWarningText(const char*) override {}
  std::string take() { return std::exchange(m_errors, {}); }

private:
  std::string m_errors;
};
vtkStandardNewMacro(CapturingOutputWindow);

CapturingOutputWindow& output_window() {
  static vtkSmartPointer<CapturingOutputWindow> window = [] {
    auto w = vtkSmartPointer<CapturingOutputWindow>::New();
    vtkOutputWindow::SetInstance(w);
    // VTK also logs errors to stderr through vtkLogger; the captured text reaches the user
    // inside our own message instead.
    vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
    return w;
  }();
  return *window;
}

/// The last meaningful line of captured VTK error text ("" when none).
std::string vtk_errors() {
  std::string text = output_window().take();
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  const auto nl = text.rfind('\n');
  std::string line = nl == std::string::npos ? text : text.substr(nl + 1);
  const auto colon = line.find("): ");  // drop "vtkXMLReader (0x55...): "
  return colon == std::string::npos ? line : line.substr(colon + 3);
}

std::string lower_extension(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

void require_file(const fs::path& p, const std::string& context) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec))
    throw Error(ErrorCode::io_error, "penumbra-replay: " + context + "'" + p.string() + "' does not exist or is not a file");
  std::ifstream probe(p, std::ios::binary);
  if (!probe) throw Error(ErrorCode::io_error, "penumbra-replay: cannot open '" + p.string() + "' for reading");
}

[[noreturn]] void unreadable(const std::string& path, const std::string& what) {
  const std::string detail = vtk_errors();
  throw Error(ErrorCode::io_error, "penumbra-replay: cannot read '" + path + "': " + what +
                                       (detail.empty() ? "" : " (" + detail + ")"));
}

std::optional<double> field_value(vtkUnstructuredGrid* grid, std::initializer_list<const char*> names) {
  vtkFieldData* fd = grid->GetFieldData();
  if (!fd) return std::nullopt;
  for (const char* n : names) {
    vtkDataArray* a = fd->GetArray(n);
    if (a && a->GetNumberOfTuples() > 0 && std::isfinite(a->GetComponent(0, 0))) return a->GetComponent(0, 0);
  }
  return std::nullopt;
}

/// Time and cycle from the data, falling back to `time` and `index`.
Step with_time(vtkSmartPointer<vtkUnstructuredGrid> grid, double time, std::size_t index) {
  Step s;
  s.time = field_value(grid, {"TIME", "TimeValue"}).value_or(time);
  s.cycle = static_cast<std::int64_t>(field_value(grid, {"CYCLE", "CycleIndex"}).value_or(static_cast<double>(index)));
  s.grid = std::move(grid);
  return s;
}

/// Files listed by an index (.pvd, .series): one or more parts per step.
class FileSeries : public InputSeries {
public:
  struct Entry { std::vector<std::string> parts; double time; };
  FileSeries(std::string label, std::vector<Entry> entries) : m_label(std::move(label)), m_entries(std::move(entries)) {}
  std::size_t size() const override { return m_entries.size(); }
  std::string describe() const override { return m_label + ", " + std::to_string(size()) + " step(s)"; }
  Step load(std::size_t index) override {
    const Entry& e = m_entries.at(index);
    if (e.parts.size() == 1) return with_time(read_grid_file(e.parts[0]), e.time, index);
    vtkNew<vtkMultiBlockDataSet> parts;
    parts->SetNumberOfBlocks(static_cast<unsigned>(e.parts.size()));
    for (std::size_t i = 0; i < e.parts.size(); ++i) parts->SetBlock(static_cast<unsigned>(i), read_grid_file(e.parts[i]));
    return with_time(merge_to_grid(parts, e.parts[0].c_str()), e.time, index);
  }

private:
  std::string m_label;
  std::vector<Entry> m_entries;
};

std::unique_ptr<InputSeries> open_pvd(const fs::path& path) {
  vtkNew<vtkXMLDataParser> parser;
  parser->SetFileName(path.string().c_str());
  if (!parser->Parse()) unreadable(path.string(), "not a valid XML .pvd collection");
  vtkXMLDataElement* root = parser->GetRootElement();
  vtkXMLDataElement* collection = root ? root->FindNestedElementWithName("Collection") : nullptr;
  if (!collection)
    throw Error(ErrorCode::invalid_argument, "penumbra-replay: '" + path.string() + "' has no <Collection> element");
  std::map<double, FileSeries::Entry> by_time;  // parts sharing a timestep form one step
  for (int i = 0; i < collection->GetNumberOfNestedElements(); ++i) {
    vtkXMLDataElement* ds = collection->GetNestedElement(i);
    const char* file = ds->GetAttribute("file");
    if (std::string(ds->GetName()) != "DataSet" || !file) continue;
    double t = static_cast<double>(i);
    if (const char* ts = ds->GetAttribute("timestep")) t = std::strtod(ts, nullptr);
    const fs::path part = path.parent_path() / file;
    require_file(part, "file listed in '" + path.filename().string() + "', ");
    auto& entry = by_time[t];
    entry.time = t;
    entry.parts.push_back(part.string());
  }
  if (by_time.empty())
    throw Error(ErrorCode::invalid_argument, "penumbra-replay: '" + path.string() + "' lists no DataSet files");
  std::vector<FileSeries::Entry> entries;
  for (auto& [t, e] : by_time) entries.push_back(std::move(e));
  return std::make_unique<FileSeries>("ParaView collection '" + path.filename().string() + "'", std::move(entries));
}

std::unique_ptr<InputSeries> open_json_series(const fs::path& path) {
  std::ifstream in(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw Error(ErrorCode::invalid_argument, "penumbra-replay: '" + path.string() + "' is not valid JSON: " + e.what());
  }
  const std::string bad = "penumbra-replay: '" + path.string() + "' ";
  if (!j.is_object() || !j.contains("files") || !j["files"].is_array() || j["files"].empty())
    throw Error(ErrorCode::invalid_argument, bad + "needs a non-empty \"files\" array (ParaView .series format)");
  std::vector<FileSeries::Entry> entries;
  for (std::size_t i = 0; i < j["files"].size(); ++i) {
    const auto& f = j["files"][i];
    if (!f.is_object() || !f.contains("name") || !f["name"].is_string())
      throw Error(ErrorCode::invalid_argument, bad + "files[" + std::to_string(i) + "] needs a string \"name\"");
    const double t = f.contains("time") && f["time"].is_number() ? f["time"].get<double>() : static_cast<double>(i);
    const fs::path part = path.parent_path() / f["name"].get<std::string>();
    require_file(part, "file listed in '" + path.filename().string() + "', ");
    entries.push_back({{part.string()}, t});
  }
  return std::make_unique<FileSeries>("file series '" + path.filename().string() + "'", std::move(entries));
}

/// Exodus II files are netCDF: classic "CDF\1", 64-bit offset "CDF\2", CDF-5 "CDF\5" or HDF5.
bool has_netcdf_signature(const std::string& path) {
  char head[8] = {};
  std::ifstream(path, std::ios::binary).read(head, sizeof head);
  const std::string h(head, sizeof head);
  return (h.compare(0, 3, "CDF") == 0 && (h[3] == 1 || h[3] == 2 || h[3] == 5)) || h == "\x89HDF\r\n\x1a\n";
}

/// Exodus II: one reader kept open; every time step is a step (a mesh-only file gives one).
class ExodusSeries : public InputSeries {
public:
  explicit ExodusSeries(const fs::path& path) : m_path(path.string()) {
    output_window();
    // Checked here first: the Exodus library prints its own complaints to stderr.
    if (!has_netcdf_signature(m_path) || !m_reader->CanReadFile(m_path.c_str()))
      unreadable(m_path, "not an Exodus II (netCDF) file");
    const auto needed = netcdf_classic_min_size(m_path);
    const auto size = fs::file_size(path);
    if (needed && size < *needed)
      throw Error(ErrorCode::io_error, "penumbra-replay: cannot read '" + m_path + "': file is truncated (" +
                                           std::to_string(size) + " bytes, its header needs at least " +
                                           std::to_string(*needed) + ")");
    m_reader->SetFileName(m_path.c_str());
    m_reader->UpdateInformation();
    if (m_reader->GetErrorCode() != 0) unreadable(m_path, "invalid Exodus II metadata");
    for (int type : {vtkExodusIIReader::NODAL, vtkExodusIIReader::ELEM_BLOCK, vtkExodusIIReader::GLOBAL})
      m_reader->SetAllArrayStatus(type, 1);
    m_reader->GenerateGlobalNodeIdArrayOn();  // merge key for blocks that share nodes
    vtkInformation* info = m_reader->GetOutputInformation(0);
    const auto key = vtkStreamingDemandDrivenPipeline::TIME_STEPS();
    if (info->Has(key)) {
      const double* t = info->Get(key);
      m_times.assign(t, t + info->Length(key));
    }
  }
  std::size_t size() const override { return std::max<std::size_t>(1, m_times.size()); }
  std::string describe() const override {
    return "Exodus II '" + fs::path(m_path).filename().string() + "', " +
           (m_times.empty() ? std::string("mesh only (no time steps)") : std::to_string(m_times.size()) + " step(s)");
  }
  Step load(std::size_t index) override {
    if (!m_times.empty()) m_reader->SetTimeStep(static_cast<int>(index));
    vtk_errors();  // only errors of this Update count
    m_reader->Update();
    const std::string errors = vtk_errors();
    if (m_reader->GetErrorCode() != 0 || !errors.empty())
      throw Error(ErrorCode::io_error, "penumbra-replay: cannot read step " + std::to_string(index) + " of '" +
                                           m_path + "'" + (errors.empty() ? "" : ": " + errors));
    Step s;
    // The merged grid must not alias the reader's output, which the next Update() overwrites.
    auto grid = merge_to_grid(m_reader->GetOutput(), m_path.c_str());
    s.grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
    s.grid->ShallowCopy(grid);
    s.time = m_times.empty() ? 0.0 : m_times[index];
    s.cycle = static_cast<std::int64_t>(index);
    return s;
  }

private:
  std::string m_path;
  vtkNew<vtkExodusIIReader> m_reader;
  std::vector<double> m_times;
};

/// A single .vtu/.vtk file: one step.
class SingleFile : public InputSeries {
public:
  explicit SingleFile(std::string path) : m_path(std::move(path)) {}
  std::size_t size() const override { return 1; }
  std::string describe() const override { return "'" + fs::path(m_path).filename().string() + "', 1 step"; }
  Step load(std::size_t) override { return with_time(read_grid_file(m_path), 0.0, 0); }

private:
  std::string m_path;
};

}  // namespace

vtkSmartPointer<vtkUnstructuredGrid> read_grid_file(const std::string& path) {
  output_window();
  vtk_errors();  // discard anything left from earlier, unrelated calls
  require_file(path, "");
  const std::string ext = lower_extension(path);
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  if (ext == ".vtu") {
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    if (!reader->CanReadFile(path.c_str())) unreadable(path, "not a VTK XML UnstructuredGrid (.vtu) file");
    reader->SetFileName(path.c_str());
    reader->Update();
    if (reader->GetErrorCode() != 0 || reader->GetOutput()->GetNumberOfPoints() == 0)
      unreadable(path, "corrupt or empty .vtu file");
    grid = reader->GetOutput();
  } else if (ext == ".vtk") {
    vtkNew<vtkUnstructuredGridReader> reader;
    reader->SetFileName(path.c_str());
    if (!reader->IsFileUnstructuredGrid()) unreadable(path, "not a legacy VTK UNSTRUCTURED_GRID file");
    reader->ReadAllScalarsOn();
    reader->ReadAllVectorsOn();
    reader->ReadAllTensorsOn();
    reader->ReadAllFieldsOn();
    reader->Update();
    const std::string errors = vtk_errors();
    if (reader->GetErrorCode() != 0 || !errors.empty() || reader->GetOutput()->GetNumberOfPoints() == 0)
      throw Error(ErrorCode::io_error, "penumbra-replay: cannot read '" + path + "': corrupt or empty legacy .vtk file" +
                                           (errors.empty() ? "" : " (" + errors + ")"));
    grid = reader->GetOutput();
  } else {
    throw Error(ErrorCode::invalid_argument,
                "penumbra-replay: '" + path + "' has unsupported extension '" + ext + "' (expected .vtu or .vtk)");
  }
  const std::string leftover = vtk_errors();
  if (!leftover.empty()) throw Error(ErrorCode::io_error, "penumbra-replay: cannot read '" + path + "': " + leftover);
  return grid;
}

std::unique_ptr<InputSeries> InputSeries::open(const std::string& path_text) {
  const fs::path path(path_text);
  require_file(path, "INPUT ");
  const std::string ext = lower_extension(path);
  if (ext == ".vtu" || ext == ".vtk") return std::make_unique<SingleFile>(path_text);
  if (ext == ".pvd") return open_pvd(path);
  if (ext == ".series") return open_json_series(path);
  for (const char* e : {".e", ".ex2", ".exo", ".exii", ".g", ".gen"})
    if (ext == e) return std::make_unique<ExodusSeries>(path);
  throw Error(ErrorCode::invalid_argument,
              "penumbra-replay: INPUT '" + path_text + "' has unsupported extension '" + ext +
                  "' (expected .vtu, .vtk, .pvd, .series or Exodus .e/.ex2/.exo)");
}

}  // namespace penumbra::replay
