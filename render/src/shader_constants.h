// SPDX-License-Identifier: BSD-3-Clause
// render/src/shader_constants.h -- the constants the C++ code and the GLSL shaders share
//
// Each PNB_SHARED(type, name, value) line is a C++ constant here and, written by the build into
// every shader after its #version line (render/shaders/embed_shader.cmake), a GLSL constant of
// the same name and value there: the two cannot differ. Types: double (GLSL float), int, unsigned
// (GLSL uint).
#pragma once

#define PNB_SHARED(type, name, value) inline constexpr type name = value;

namespace penumbra::render::shader {

// Work-group sizes: the shaders' local_size and the dispatches' group counts.
PNB_SHARED(int, kRayCastTile, 8)         // ray_cast.comp: tiles of kRayCastTile x kRayCastTile pixels
PNB_SHARED(int, kConeTraceGroup, 64)     // cone_trace.comp
PNB_SHARED(int, kPyramidFilterGroup, 64)  // pyramid_filter.comp
PNB_SHARED(int, kLightGroup, 64)          // light_level0.comp, light_level1.comp, light_scatter.comp

// Runs inside the mesh a GPU ray returns at most (RenderOptions::ray_runs).
PNB_SHARED(int, kMaxRayRuns, 16)

// Level 1 of the light volume (level1_solve.cpp, level1_walk.cpp, light_level1.comp): optical
// depth is interpolated up to kGeometricDepth across a tet (a factor 4 in rho), rho linearly from
// kLinearDepth (a factor 16); a walk that takes kMaxMoves steps cycles in a degenerate
// configuration and falls back to level 0.
PNB_SHARED(double, kGeometricDepth, 1.3862943611198906)
PNB_SHARED(double, kLinearDepth, 2.772588722239781)
PNB_SHARED(int, kMaxMoves, 200000)
// Level 0's grid mask (render::Level0Mask) as the shaders read it.
PNB_SHARED(unsigned, kMaskOutside, 0)
PNB_SHARED(unsigned, kMaskOccluder, 2)

// Cone tracing (cone_tracer.cpp, cone_trace.comp): a depth beyond which exp(-depth) is below
// float resolution of any shading result, and the depth at which a (sub-)cone counts as opaque
// for the lateral variance (exp(-10) = 4.5e-5, far below one level of an 8-bit image).
PNB_SHARED(double, kOpaqueDepth, 40.0)
PNB_SHARED(double, kSaturatedDepth, 10.0)

}  // namespace penumbra::render::shader

#undef PNB_SHARED
