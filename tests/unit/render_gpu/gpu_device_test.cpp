// SPDX-License-Identifier: BSD-3-Clause
// Opening the headless context, and the clear error when EGL is missing.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "penumbra/core/error.h"
#include "penumbra/render/gpu_ray_caster.h"

namespace penumbra {
namespace {

// Runs `f`, which must throw Error(backend_unavailable) whose message contains `text`.
template <class F>
void expect_unavailable(F&& f, const std::string& text) {
  try {
    f();
    ADD_FAILURE() << "expected Error(backend_unavailable) containing: " << text;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::backend_unavailable) << e.what();
    if (render::gpu_backend_compiled()) EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}

TEST(GpuDevice, MissingEglLibraryIsAClearErrorNotACrash) {
  render::GpuOptions o;
  o.egl_library = "/nonexistent/libEGL.so.1";
  expect_unavailable([&] { render::GpuDevice::open(o); },
                     "cannot load the EGL library '/nonexistent/libEGL.so.1'");
  expect_unavailable([&] { render::list_egl_devices(o); }, "/nonexistent/libEGL.so.1");
  EXPECT_FALSE(render::hardware_gpu_present(o));
}

TEST(GpuDevice, EnvironmentNamesTheEglLibrary) {
  ::setenv("PNB_EGL_LIBRARY", "/nonexistent/elsewhere/libEGL.so.1", 1);
  expect_unavailable([] { render::GpuDevice::open(); }, "'/nonexistent/elsewhere/libEGL.so.1'");
  ::unsetenv("PNB_EGL_LIBRARY");
}

TEST(GpuDevice, LibraryThatIsNotEglIsRefused) {
  render::GpuOptions o;
  o.egl_library = "libz.so.1";  // loads fine, exports no EGL
  expect_unavailable([&] { render::GpuDevice::open(o); }, "'libz.so.1' is not an EGL 1.4 library");
}

TEST(GpuDevice, EglWithoutAnyDriverIsAClearError) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  // libglvnd's libEGL with no vendor library (no Mesa, no NVIDIA EGL): run in a fresh process,
  // since libEGL reads its vendor list once per process.
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        ::setenv("__EGL_VENDOR_LIBRARY_FILENAMES", "/nonexistent/vendor.json", 1);
        int status = 3;
        try {
          render::GpuOptions o;
          o.log = [](const std::string&) {};
          render::GpuDevice::open(o);
        } catch (const Error& e) {
          const bool clear = e.code() == ErrorCode::backend_unavailable &&
                             std::string(e.what()).find("GPU backend:") != std::string::npos;
          std::fprintf(stderr, "%s\n", e.what());
          status = clear ? 0 : 2;
        }
        std::exit(status);
      },
      ::testing::ExitedWithCode(0), "GPU backend");
}

TEST(GpuDevice, OpensAHeadlessContextAndLogsItOnce) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  std::vector<std::string> lines;
  render::GpuOptions o;
  o.log = [&](const std::string& s) { lines.push_back(s); };
  const auto device = render::GpuDevice::open(o);
  const auto& info = device->info();
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find(info.gl_renderer), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find(info.gl_version), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find(info.device), std::string::npos) << lines[0];
  EXPECT_EQ(info.gl_version.rfind("4.", 0), 0u) << info.gl_version;
  EXPECT_FALSE(info.gl_renderer.empty());
  EXPECT_GE(info.max_storage_block_bytes, std::int64_t{1} << 24);  // GL 4.5 guarantees 2^24
  // Without a hardware GPU the software device runs (that is how CI tests the backend).
  if (!render::hardware_gpu_present()) EXPECT_TRUE(info.software) << info.summary();
}

TEST(GpuDevice, DeviceListAgreesWithHardwareFlag) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  const auto devices = render::list_egl_devices();
  ASSERT_FALSE(devices.empty()) << "EGL lists no device at all (Mesa lists at least its software device)";
  bool any_hardware = false;
  for (std::size_t i = 0; i < devices.size(); ++i) {
    EXPECT_EQ(devices[i].index, static_cast<int>(i));
    any_hardware |= devices[i].hardware();
  }
  EXPECT_EQ(render::hardware_gpu_present(), any_hardware);
}

TEST(GpuDevice, RequestedDeviceOutOfRangeIsNamed) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  render::GpuOptions o;
  o.device = "99";
  expect_unavailable([&] { render::GpuDevice::open(o); }, "device 99 was requested but EGL lists");
  ::setenv("PNB_EGL_DEVICE", "98", 1);
  expect_unavailable([] { render::GpuDevice::open(); }, "device 98 was requested");
  ::unsetenv("PNB_EGL_DEVICE");
}

TEST(GpuDevice, RequiringHardwareFailsCleanlyOnSoftwareOnlyNodes) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  render::GpuOptions o;
  o.require_hardware = true;
  o.log = [](const std::string&) {};
  if (render::hardware_gpu_present()) {
    EXPECT_FALSE(render::GpuDevice::open(o)->info().software);
  } else {
    expect_unavailable([&] { render::GpuDevice::open(o); }, "no hardware GPU");
  }
}

TEST(GpuDevice, SeveralDevicesCoexistAndCloseIndependently) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  render::GpuOptions o;
  o.log = [](const std::string&) {};
  auto a = render::GpuDevice::open(o);
  auto b = render::GpuDevice::open(o);
  a.reset();  // must not terminate the display under b
  auto c = render::GpuDevice::open(o);
  EXPECT_EQ(b->info().gl_renderer, c->info().gl_renderer);
}

}  // namespace
}  // namespace penumbra
