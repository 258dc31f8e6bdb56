// SPDX-License-Identifier: BSD-3-Clause
// Which EGL device the GPU backend picks: pure logic over device descriptions.
#include <gtest/gtest.h>

#include <cstdlib>

#include "penumbra/core/error.h"
#include "penumbra/render/egl_device.h"

namespace penumbra {
namespace {

using render::EglDeviceInfo;

EglDeviceInfo software(int i) {
  EglDeviceInfo d;
  d.index = i;
  d.extensions = "EGL_MESA_device_software";
  d.software = true;
  return d;
}

EglDeviceInfo drm_gpu(int i, const char* node) {
  EglDeviceInfo d;
  d.index = i;
  d.extensions = "EGL_EXT_device_drm EGL_EXT_device_drm_render_node";
  d.drm_file = "/dev/dri/card" + std::to_string(i);
  d.render_node = node;
  return d;
}

EglDeviceInfo nvidia(int i) {
  EglDeviceInfo d;
  d.index = i;
  d.extensions = "EGL_NV_device_cuda EGL_EXT_device_drm";
  d.drm_file = "/dev/dri/card1";
  return d;
}

ErrorCode code_of(const std::vector<EglDeviceInfo>& devices, const std::string& requested, bool hardware) {
  try {
    render::select_egl_device(devices, requested, hardware);
  } catch (const Error& e) {
    return e.code();
  }
  return ErrorCode::ok;
}

TEST(EglDeviceSelection, KindsAreRecognised) {
  EXPECT_FALSE(software(0).hardware());
  EXPECT_TRUE(drm_gpu(0, "/dev/dri/renderD128").hardware());
  EXPECT_TRUE(nvidia(0).hardware());
  EglDeviceInfo bare;  // no DRM node, not marked software: not known to be a GPU
  EXPECT_FALSE(bare.hardware());
  EXPECT_EQ(drm_gpu(1, "/dev/dri/renderD129").describe(), "EGL device 1 (/dev/dri/renderD129, hardware)");
  EXPECT_EQ(software(0).describe(), "EGL device 0 (software)");
}

TEST(EglDeviceSelection, AutomaticPrefersHardwareWhateverTheOrder) {
  // Mesa lists its software device last on GPU nodes, NVIDIA first; neither order matters.
  EXPECT_EQ(render::select_egl_device({software(0), nvidia(1)}, "", false), 1);
  EXPECT_EQ(render::select_egl_device({nvidia(0), drm_gpu(1, "x"), software(2)}, "", false), 0);
}

TEST(EglDeviceSelection, WithoutHardwareTheSurfacelessPlatformIsChosen) {
  EXPECT_EQ(render::select_egl_device({software(0)}, "", false), -1);
  EglDeviceInfo unknown;  // neither a DRM node nor marked software
  EXPECT_EQ(render::select_egl_device({unknown, software(1)}, "", false), -1);
}

TEST(EglDeviceSelection, RanksOnANodeSpreadOverItsGpus) {
  const std::vector<EglDeviceInfo> devices = {nvidia(0), software(1), nvidia(2), drm_gpu(3, "r")};
  EXPECT_EQ(render::select_egl_device(devices, "", false, 0), 0);
  EXPECT_EQ(render::select_egl_device(devices, "", false, 1), 2);
  EXPECT_EQ(render::select_egl_device(devices, "", false, 2), 3);
  EXPECT_EQ(render::select_egl_device(devices, "", false, 3), 0);  // more ranks than GPUs: shared
  EXPECT_EQ(render::select_egl_device(devices, "1", false, 3), 1);  // an explicit request wins
  EXPECT_EQ(render::select_egl_device({software(0)}, "", false, 5), -1);
}

TEST(EglDeviceSelection, LocalRankComesFromTheLauncher) {
  for (const char* name : {"OMPI_COMM_WORLD_LOCAL_RANK", "MPI_LOCALRANKID", "MV2_COMM_WORLD_LOCAL_RANK", "SLURM_LOCALID"})
    ::unsetenv(name);
  EXPECT_EQ(render::node_local_rank(), 0);
  ::setenv("SLURM_LOCALID", "3", 1);
  EXPECT_EQ(render::node_local_rank(), 3);
  ::setenv("OMPI_COMM_WORLD_LOCAL_RANK", "1", 1);  // the MPI launcher's own variable first
  EXPECT_EQ(render::node_local_rank(), 1);
  ::setenv("OMPI_COMM_WORLD_LOCAL_RANK", "x", 1);  // malformed: ignored
  EXPECT_EQ(render::node_local_rank(), 3);
  ::unsetenv("OMPI_COMM_WORLD_LOCAL_RANK");
  ::unsetenv("SLURM_LOCALID");
}

TEST(EglDeviceSelection, NoDevicesFallsBackToSurfaceless) {
  EXPECT_EQ(render::select_egl_device({}, "", false), -1);
  EXPECT_EQ(render::select_egl_device({software(0)}, "surfaceless", false), -1);
}

TEST(EglDeviceSelection, ExplicitIndex) {
  const std::vector<EglDeviceInfo> devices = {nvidia(0), nvidia(1), software(2)};
  EXPECT_EQ(render::select_egl_device(devices, "1", false), 1);
  EXPECT_EQ(render::select_egl_device(devices, "2", false), 2);  // asking for software is allowed
  EXPECT_EQ(code_of(devices, "3", false), ErrorCode::backend_unavailable);
  EXPECT_EQ(code_of(devices, "-1", false), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of(devices, "gpu0", false), ErrorCode::invalid_argument);
  EXPECT_EQ(code_of(devices, "1x", false), ErrorCode::invalid_argument);
}

TEST(EglDeviceSelection, RequiredHardwareRefusesSoftware) {
  EXPECT_EQ(code_of({software(0)}, "", true), ErrorCode::backend_unavailable);
  EXPECT_EQ(code_of({}, "", true), ErrorCode::backend_unavailable);
  EXPECT_EQ(code_of({software(0), nvidia(1)}, "0", true), ErrorCode::backend_unavailable);
  EXPECT_EQ(code_of({software(0)}, "surfaceless", true), ErrorCode::backend_unavailable);
  EXPECT_EQ(render::select_egl_device({software(0), nvidia(1)}, "", true), 1);
  try {
    render::select_egl_device({software(0)}, "", true);
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no hardware GPU; EGL lists: EGL device 0 (software)"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace penumbra
