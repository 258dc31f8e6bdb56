// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/egl_device_selection.cpp -- which EGL device the GPU backend uses (no EGL needed)
#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <sstream>
#include <string>

#include "penumbra/core/error.h"
#include "penumbra/render/egl_device.h"

namespace penumbra::render {
namespace {

bool listed(const std::string& list, const char* name) {
  std::istringstream in(list);
  std::string word;
  while (in >> word)
    if (word == name) return true;
  return false;
}

std::string device_list_text(const std::vector<EglDeviceInfo>& devices) {
  if (devices.empty()) return "EGL lists no devices";
  std::string s = "EGL lists:";
  for (const auto& d : devices) s += " " + d.describe() + ";";
  s.pop_back();
  return s;
}

}  // namespace

bool EglDeviceInfo::hardware() const {
  // NVIDIA's devices carry EGL_NV_device_cuda and usually a DRM node; Mesa's GPUs a DRM node.
  return !software && (!drm_file.empty() || !render_node.empty() || listed(extensions, "EGL_NV_device_cuda"));
}

std::string EglDeviceInfo::describe() const {
  std::string s = "EGL device " + std::to_string(index) + " (";
  const std::string& node = !render_node.empty() ? render_node : drm_file;
  if (!node.empty()) s += node + ", ";
  s += hardware() ? "hardware" : (software ? "software" : "unknown kind");
  return s + ")";
}

int select_egl_device(const std::vector<EglDeviceInfo>& devices, const std::string& requested, bool require_hardware,
                      int local_rank) {
  if (requested == "surfaceless") {
    if (require_hardware)
      throw Error(ErrorCode::backend_unavailable,
                  "GPU backend: device \"surfaceless\" was requested but a hardware device is required");
    return -1;
  }
  if (!requested.empty()) {
    int index = -1;
    const auto r = std::from_chars(requested.data(), requested.data() + requested.size(), index);
    require(r.ec == std::errc() && r.ptr == requested.data() + requested.size() && index >= 0,
            "GPU backend: device \"" + requested + "\" is not a device index (0, 1, ...) or \"surfaceless\"");
    if (static_cast<std::size_t>(index) >= devices.size())
      throw Error(ErrorCode::backend_unavailable, "GPU backend: device " + requested + " was requested but " +
                                                      device_list_text(devices));
    if (require_hardware && !devices[static_cast<std::size_t>(index)].hardware())
      throw Error(ErrorCode::backend_unavailable, "GPU backend: device " + requested +
                                                      " is not a hardware device; " + device_list_text(devices));
    return index;
  }
  std::vector<int> gpus;
  for (const auto& d : devices)
    if (d.hardware()) gpus.push_back(d.index);
  if (!gpus.empty()) return gpus[static_cast<std::size_t>(std::max(local_rank, 0)) % gpus.size()];
  if (require_hardware)
    throw Error(ErrorCode::backend_unavailable, "GPU backend: no hardware GPU; " + device_list_text(devices));
  // No GPU: Mesa's surfaceless platform (GpuDevice::open falls back to the listed devices when
  // the EGL library lacks it).
  return -1;
}

int node_local_rank() noexcept {
  for (const char* name : {"OMPI_COMM_WORLD_LOCAL_RANK", "MPI_LOCALRANKID", "MV2_COMM_WORLD_LOCAL_RANK", "SLURM_LOCALID"}) {
    const char* v = std::getenv(name);
    if (v == nullptr) continue;
    int rank = -1;
    const char* end = v + std::char_traits<char>::length(v);
    const auto r = std::from_chars(v, end, rank);
    if (r.ec == std::errc() && r.ptr == end && rank >= 0) return rank;
  }
  return 0;
}

}  // namespace penumbra::render
