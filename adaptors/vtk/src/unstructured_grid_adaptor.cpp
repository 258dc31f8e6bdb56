// SPDX-License-Identifier: BSD-3-Clause
// adaptors/vtk/src/unstructured_grid_adaptor.cpp -- vtkUnstructuredGrid -> pnb_mesh_desc / pnb_field_desc
#include "penumbra/vtk/unstructured_grid_adaptor.h"

#include <vtkCell.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellTypes.h>
#include <vtkDataArray.h>
#include <vtkGenericCell.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>

#include <array>
#include <map>
#include <optional>
#include <sstream>

#include "penumbra/core/error.h"

namespace penumbra::vtk {
namespace {

/// How a VTK cell type becomes a Penumbra cell: the target type and which of its points are
/// the corners, in the target's VTK ordering. target == 0 means "not a volume cell".
struct CellMapping {
  std::uint8_t target = 0;
  std::array<std::uint8_t, 8> corners{};
  bool identity = false;
  bool surface = false;  // 0-, 1- or 2-D: dropped silently (boundary faces, edges, vertices)
};

constexpr std::array<std::uint8_t, 8> k_first8{0, 1, 2, 3, 4, 5, 6, 7};

CellMapping classify(std::uint8_t vtk_type) {
  switch (vtk_type) {
    case VTK_TETRA: case VTK_HEXAHEDRON: case VTK_WEDGE: case VTK_PYRAMID:
      return {vtk_type, k_first8, true, false};
    // A voxel is an axis-aligned hexahedron with points in x-fastest order.
    case VTK_VOXEL: return {VTK_HEXAHEDRON, {0, 1, 3, 2, 4, 5, 7, 6}, false, false};
    // Higher-order cells list their linear corners first, in the linear cell's order.
    case VTK_QUADRATIC_TETRA: case VTK_LAGRANGE_TETRAHEDRON: case VTK_BEZIER_TETRAHEDRON:
      return {VTK_TETRA, k_first8, false, false};
    case VTK_QUADRATIC_HEXAHEDRON: case VTK_TRIQUADRATIC_HEXAHEDRON:
    case VTK_BIQUADRATIC_QUADRATIC_HEXAHEDRON: case VTK_LAGRANGE_HEXAHEDRON: case VTK_BEZIER_HEXAHEDRON:
      return {VTK_HEXAHEDRON, k_first8, false, false};
    case VTK_QUADRATIC_WEDGE: case VTK_QUADRATIC_LINEAR_WEDGE: case VTK_BIQUADRATIC_QUADRATIC_WEDGE:
    case VTK_LAGRANGE_WEDGE: case VTK_BEZIER_WEDGE:
      return {VTK_WEDGE, k_first8, false, false};
    case VTK_QUADRATIC_PYRAMID: case VTK_TRIQUADRATIC_PYRAMID:
      return {VTK_PYRAMID, k_first8, false, false};
    default: break;
  }
  CellMapping m;
  vtkNew<vtkGenericCell> probe;
  probe->SetCellType(vtk_type);
  m.surface = probe->GetCellDimension() < 3;
  return m;
}

std::string cell_type_label(int vtk_type) {
  const char* cls = vtkCellTypes::GetClassNameFromTypeId(vtk_type);
  std::string name = cls ? cls : "unknown";
  if (name.rfind("vtk", 0) == 0) name = name.substr(3);
  return name + " (" + std::to_string(vtk_type) + ")";
}

bool is_packed_float(vtkDataArray* a) {
  return a->HasStandardMemoryLayout() && (a->GetDataType() == VTK_FLOAT || a->GetDataType() == VTK_DOUBLE);
}

pnb_type float_type(vtkDataArray* a) { return a->GetDataType() == VTK_FLOAT ? PNB_FLOAT32 : PNB_FLOAT64; }

}  // namespace

struct UnstructuredGridAdaptor::Impl {
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  pnb_mesh_desc mesh PNB_MESH_DESC_INIT;
  std::vector<pnb_field_desc> fields;
  AdaptorReport report;
  UnstructuredGridAdaptor::CopyFilter copy_filter;

  std::vector<double> own_points;
  std::vector<std::int64_t> own_connectivity;
  std::vector<std::int64_t> own_offsets;
  std::vector<std::uint8_t> own_types;
  std::vector<std::int64_t> kept_cells;  // filled only when cells were filtered
  // Growing the outer vector moves the inner vectors, never their buffers: data() stays valid.
  std::vector<std::vector<double>> own_values;

  void build_points();
  void build_cells();
  template <class Index> void rebuild_cells(const Index* offsets, const Index* connectivity,
                                            const std::uint8_t* types, std::size_t n);
  void build_fields(vtkDataSetAttributes* data, pnb_association association);
  pnb_field_desc copy_field(vtkDataArray* a, pnb_association association, bool filter);
};

void UnstructuredGridAdaptor::Impl::build_points() {
  vtkPoints* pts = grid->GetPoints();
  require(pts && pts->GetNumberOfPoints() > 0,
          "UnstructuredGridAdaptor: grid has no points (expected a volume mesh)");
  vtkDataArray* data = pts->GetData();
  const auto n = static_cast<std::size_t>(pts->GetNumberOfPoints());
  mesh.point_count = static_cast<std::int64_t>(n);
  mesh.point_stride_bytes = 0;
  if (is_packed_float(data) && data->GetNumberOfComponents() == 3) {
    mesh.points = data->GetVoidPointer(0);
    mesh.point_type = float_type(data);
    return;
  }
  own_points.resize(3 * n);
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) own_points[3 * i + c] = data->GetComponent(static_cast<vtkIdType>(i), c);
  mesh.points = own_points.data();
  mesh.point_type = PNB_FLOAT64;
  report.points_copied = true;
}

template <class Index>
void UnstructuredGridAdaptor::Impl::rebuild_cells(const Index* offsets, const Index* connectivity,
                                                  const std::uint8_t* types, std::size_t n) {
  std::array<std::optional<CellMapping>, 256> cache;  // indexed by VTK type id
  std::map<int, std::size_t> dropped_by_type;
  own_offsets.reserve(n + 1);
  own_offsets.assign(1, 0);
  own_connectivity.reserve(static_cast<std::size_t>(offsets[n]));
  own_types.reserve(n);
  for (std::size_t c = 0; c < n; ++c) {
    std::optional<CellMapping>& cached = cache[types[c]];
    if (!cached) cached = classify(types[c]);
    const CellMapping& m = *cached;
    const auto begin = static_cast<std::int64_t>(offsets[c]);
    const auto size = static_cast<int>(offsets[c + 1] - offsets[c]);
    const int corners = cell_point_count(m.target);
    if (m.target == 0 || size < corners) {
      ++dropped_by_type[types[c]];
      ++(m.surface ? report.dropped_surface_cells : report.dropped_unsupported_cells);
      continue;
    }
    if (!m.identity) ++report.linearized_cells;
    for (int k = 0; k < corners; ++k) own_connectivity.push_back(connectivity[begin + m.corners[k]]);
    own_offsets.push_back(static_cast<std::int64_t>(own_connectivity.size()));
    own_types.push_back(m.target);
    kept_cells.push_back(static_cast<std::int64_t>(c));
  }
  if (own_types.empty()) {
    std::ostringstream msg;
    msg << "UnstructuredGridAdaptor: grid has no volume cells (tetra 10, hexahedron 12, wedge 13, "
           "pyramid 14, or their voxel/quadratic forms); it holds";
    const char* sep = " ";
    for (const auto& [type, count] : dropped_by_type) {
      msg << sep << count << " " << cell_type_label(type);
      sep = ", ";
    }
    msg << ". A surface mesh cannot be volume-rendered.";
    throw Error(ErrorCode::invalid_argument, msg.str());
  }
  if (kept_cells.size() == n) kept_cells.clear();  // nothing filtered: cell fields stay views
}

void UnstructuredGridAdaptor::Impl::build_cells() {
  vtkCellArray* cells = grid->GetCells();
  const auto n = static_cast<std::size_t>(grid->GetNumberOfCells());
  report.input_cells = n;
  require(cells && n > 0, "UnstructuredGridAdaptor: grid has no cells (expected a volume mesh)");
  vtkUnsignedCharArray* types_array = grid->GetCellTypesArray();
  const std::uint8_t* types = types_array->GetPointer(0);

  bool all_native = true;
  for (std::size_t c = 0; c < n && all_native; ++c)
    all_native = cell_point_count(types[c]) > 0;
  const bool wide = cells->IsStorage64Bit();
  const void* offsets = wide ? static_cast<const void*>(cells->GetOffsetsArray64()->GetPointer(0))
                             : static_cast<const void*>(cells->GetOffsetsArray32()->GetPointer(0));
  const void* connectivity = wide ? static_cast<const void*>(cells->GetConnectivityArray64()->GetPointer(0))
                                  : static_cast<const void*>(cells->GetConnectivityArray32()->GetPointer(0));
  if (all_native) {
    mesh.connectivity = connectivity;
    mesh.connectivity_count = cells->GetNumberOfConnectivityIds();
    mesh.offsets = offsets;
    mesh.index_type = wide ? PNB_INT64 : PNB_INT32;
    mesh.cell_types = types;
    mesh.cell_types_count = static_cast<std::int64_t>(n);
    report.volume_cells = n;
    return;
  }
  if (wide)
    rebuild_cells(static_cast<const std::int64_t*>(offsets), static_cast<const std::int64_t*>(connectivity), types, n);
  else
    rebuild_cells(static_cast<const std::int32_t*>(offsets), static_cast<const std::int32_t*>(connectivity), types, n);
  mesh.connectivity = own_connectivity.data();
  mesh.connectivity_count = static_cast<std::int64_t>(own_connectivity.size());
  mesh.offsets = own_offsets.data();
  mesh.index_type = PNB_INT64;
  mesh.cell_types = own_types.data();
  mesh.cell_types_count = static_cast<std::int64_t>(own_types.size());
  report.volume_cells = own_types.size();
  report.cells_copied = true;
}

pnb_field_desc UnstructuredGridAdaptor::Impl::copy_field(vtkDataArray* a, pnb_association association,
                                                         bool filter) {
  const int nc = a->GetNumberOfComponents();
  const std::size_t count = filter ? kept_cells.size() : static_cast<std::size_t>(a->GetNumberOfTuples());
  std::vector<double> values(count * static_cast<std::size_t>(nc));
  for (std::size_t i = 0; i < count; ++i) {
    const vtkIdType src = filter ? kept_cells[i] : static_cast<vtkIdType>(i);
    for (int c = 0; c < nc; ++c) values[i * nc + c] = a->GetComponent(src, c);
  }
  own_values.push_back(std::move(values));
  std::string why = filter ? "filtered to volume cells" : std::string(a->GetDataTypeAsString()) + " to float64";
  report.copied_fields.push_back(std::string(a->GetName()) + " (" + why + ")");
  return {sizeof(pnb_field_desc), a->GetName(), association, own_values.back().data(), static_cast<std::int64_t>(count), nc, 0,
          PNB_FLOAT64};
}

void UnstructuredGridAdaptor::Impl::build_fields(vtkDataSetAttributes* data, pnb_association association) {
  if (!data) return;
  const bool filter = association == PNB_CELL_FIELD && !kept_cells.empty();
  for (int i = 0; i < data->GetNumberOfArrays(); ++i) {
    vtkAbstractArray* abstract = data->GetAbstractArray(i);
    vtkDataArray* a = data->GetArray(i);
    const char* name = abstract ? abstract->GetName() : nullptr;
    if (!a || !name || !*name) {
      report.skipped_arrays.push_back(name && *name ? name : "(unnamed)");
      continue;
    }
    if (!filter && is_packed_float(a)) {
      fields.push_back({sizeof(pnb_field_desc), name, association, a->GetVoidPointer(0), a->GetNumberOfTuples(),
                        a->GetNumberOfComponents(), 0, float_type(a)});
    } else if (!copy_filter || copy_filter(name)) {
      fields.push_back(copy_field(a, association, filter));
    } else {
      report.unconverted_fields.push_back(name);
    }
  }
}

UnstructuredGridAdaptor::UnstructuredGridAdaptor(vtkUnstructuredGrid* grid, std::uint64_t topology_version)
    : UnstructuredGridAdaptor(grid, topology_version, CopyFilter{}) {}

UnstructuredGridAdaptor::UnstructuredGridAdaptor(vtkUnstructuredGrid* grid, std::uint64_t topology_version,
                                                 CopyFilter copy_filter)
    : m_impl(std::make_unique<Impl>()) {
  require(grid != nullptr, "UnstructuredGridAdaptor: grid is null");
  m_impl->copy_filter = std::move(copy_filter);
  m_impl->grid = grid;
  m_impl->mesh.topology_version = topology_version;
  m_impl->build_points();
  m_impl->build_cells();
  m_impl->build_fields(grid->GetPointData(), PNB_POINT_FIELD);
  m_impl->build_fields(grid->GetCellData(), PNB_CELL_FIELD);
}

UnstructuredGridAdaptor::~UnstructuredGridAdaptor() = default;
UnstructuredGridAdaptor::UnstructuredGridAdaptor(UnstructuredGridAdaptor&&) noexcept = default;
UnstructuredGridAdaptor& UnstructuredGridAdaptor::operator=(UnstructuredGridAdaptor&&) noexcept = default;

const pnb_mesh_desc& UnstructuredGridAdaptor::mesh() const { return m_impl->mesh; }
const std::vector<pnb_field_desc>& UnstructuredGridAdaptor::fields() const { return m_impl->fields; }
const AdaptorReport& UnstructuredGridAdaptor::report() const { return m_impl->report; }

bool UnstructuredGridAdaptor::mesh_is_zero_copy() const {
  return !m_impl->report.points_copied && !m_impl->report.cells_copied;
}

const pnb_field_desc* UnstructuredGridAdaptor::find_field(std::string_view name, pnb_association association) const {
  for (const auto& f : m_impl->fields)
    if (f.association == association && name == f.name) return &f;
  return nullptr;
}

MeshView UnstructuredGridAdaptor::mesh_view() const {
  const pnb_mesh_desc& d = m_impl->mesh;
  MeshView v;
  v.point_type = d.point_type == PNB_FLOAT32 ? ScalarType::float32 : ScalarType::float64;
  v.points.data = static_cast<const std::byte*>(d.points);
  v.points.count = static_cast<std::size_t>(d.point_count);
  v.points.stride_bytes = static_cast<std::ptrdiff_t>(3 * scalar_size(v.point_type));
  const ScalarType index = d.index_type == PNB_INT32 ? ScalarType::int32 : ScalarType::int64;
  v.connectivity = {d.connectivity, static_cast<std::size_t>(d.connectivity_count), index};
  v.offsets = {d.offsets, static_cast<std::size_t>(d.cell_types_count + 1), index};
  v.cell_types = d.cell_types;
  v.cell_type_count = static_cast<std::size_t>(d.cell_types_count);
  v.topology_version = d.topology_version;
  return v;
}

std::string AdaptorReport::summary() const {
  std::ostringstream s;
  s << volume_cells << " volume cells";
  if (volume_cells != input_cells) s << " of " << input_cells;
  const bool zero_copy = !points_copied && !cells_copied;
  s << (zero_copy ? ", zero-copy mesh" : ", mesh copied (");
  if (!zero_copy) s << (points_copied ? "points" : "") << (points_copied && cells_copied ? ", " : "")
                    << (cells_copied ? "cells" : "") << ")";
  if (linearized_cells) s << ", " << linearized_cells << " voxel/higher-order cells linearized";
  if (dropped_surface_cells) s << ", " << dropped_surface_cells << " surface/line/vertex cells dropped";
  if (dropped_unsupported_cells) s << ", " << dropped_unsupported_cells << " unsupported 3-D cells dropped";
  if (!copied_fields.empty()) {
    s << ", " << copied_fields.size() << " field(s) copied:";
    for (const auto& f : copied_fields) s << " " << f << ";";
  }
  if (!skipped_arrays.empty()) s << ", " << skipped_arrays.size() << " non-numeric/unnamed array(s) skipped";
  if (!unconverted_fields.empty()) s << ", " << unconverted_fields.size() << " unused array(s) not converted";
  return s.str();
}

const char* type_name(pnb_type type) {
  switch (type) {
    case PNB_FLOAT32: return "float32";
    case PNB_FLOAT64: return "float64";
    case PNB_INT32: return "int32";
    case PNB_INT64: return "int64";
  }
  return "unknown";
}

}  // namespace penumbra::vtk
