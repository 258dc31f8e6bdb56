// SPDX-License-Identifier: BSD-3-Clause
// bench/render/vtk_window.cpp -- a VTK render window for a benchmark scene, and its read-back
#include "vtk_window.h"

#include <vtkCamera.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkRenderer.h>
#include <vtkVolume.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>

#include "penumbra/core/error.h"

namespace penumbra::bench {

vtkSmartPointer<vtkRenderWindow> scene_window(const Scene& scene, vtkAbstractVolumeMapper* mapper,
                                              vtkVolumeProperty* property) {
  vtkNew<vtkVolume> volume;
  volume->SetMapper(mapper);
  volume->SetProperty(property);
  vtkNew<vtkRenderer> ren;
  ren->SetBackground(scene.background[0], scene.background[1], scene.background[2]);
  ren->AddVolume(volume);
  vtkCamera* cam = ren->GetActiveCamera();
  const SceneCamera& c = scene.camera;
  cam->SetPosition(c.eye.x, c.eye.y, c.eye.z);
  cam->SetFocalPoint(c.target.x, c.target.y, c.target.z);
  cam->SetViewUp(c.up.x, c.up.y, c.up.z);
  cam->SetViewAngle(c.fov_y_deg);
  ren->ResetCameraClippingRange();
  auto window = vtkSmartPointer<vtkRenderWindow>::New();
  window->SetSize(scene.width, scene.height);
  window->SetMultiSamples(0);
  window->AddRenderer(ren);
  return window;
}

std::vector<unsigned char> read_back(vtkRenderWindow* window, int width, int height, const std::string& who) {
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->ShouldRerenderOff();
  grab->Update();
  vtkImageData* img = grab->GetOutput();
  int dims[3];
  img->GetDimensions(dims);
  require(dims[0] == width && dims[1] == height, who + ": framebuffer has the wrong size");
  auto* px = static_cast<unsigned char*>(img->GetScalarPointer());
  std::vector<unsigned char> rgb(static_cast<std::size_t>(width) * height * 3);
  for (int y = 0; y < height; ++y)
    std::copy(px + static_cast<std::size_t>(height - 1 - y) * width * 3, px + static_cast<std::size_t>(height - y) * width * 3,
              rgb.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(y) * width * 3));
  return rgb;
}

}  // namespace penumbra::bench
