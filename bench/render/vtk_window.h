// SPDX-License-Identifier: BSD-3-Clause
// bench/render/vtk_window.h -- a VTK render window for a benchmark scene, and its read-back
#pragma once
#include <vtkAbstractVolumeMapper.h>
#include <vtkRenderWindow.h>
#include <vtkSmartPointer.h>
#include <vtkVolumeProperty.h>

#include <string>
#include <vector>

#include "scene.h"

namespace penumbra::bench {

/// A window of the scene's size (no multisampling) showing `mapper`'s volume with `property`
/// over the scene's background, through the scene's camera.
vtkSmartPointer<vtkRenderWindow> scene_window(const Scene& scene, vtkAbstractVolumeMapper* mapper,
                                              vtkVolumeProperty* property);

/// The back buffer as 8-bit RGB, top row first (VTK's rows start at the bottom); throws naming
/// `who` when the framebuffer is not width x height.
std::vector<unsigned char> read_back(vtkRenderWindow* window, int width, int height, const std::string& who);

}  // namespace penumbra::bench
