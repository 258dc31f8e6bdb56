// SPDX-License-Identifier: BSD-3-Clause
// render/shaders/pyramid_filter.comp -- one pass of the extinction pyramid's construction, as
// render/src/occlusion/extinction_pyramid.cpp: a separable Gaussian pass along one axis (zeros
// beyond the input, never clamp-to-edge), or the per-value conversion to opacity and back.
#version 450

layout(local_size_x = kPyramidFilterGroup, local_size_y = 1, local_size_z = 1) in;

layout(std430, binding = 0) readonly buffer Src { float src[]; };
layout(std430, binding = 1) writeonly buffer Dst { float dst[]; };
layout(std430, binding = 2) readonly buffer Taps { float taps[]; };  // 2 u_radius + 1, normalised

// 0: filter along u_axis; 1: tau -> opacity; 2: opacity -> tau; 3: copy.
uniform int u_mode;
uniform int u_first;
uniform int u_count;     // output values in this dispatch
uniform int u_dst_offset;  // first output value in dst
uniform int u_in_nx;
uniform int u_in_ny;
uniform int u_in_nz;
uniform int u_out_nx;    // output dims: the input's with the filtered axis replaced
uniform int u_out_ny;
uniform int u_axis;
uniform int u_stride;    // output node o reads input stride * o + offset + k
uniform int u_offset;
uniform int u_radius;
uniform int u_halve_ends;  // 1: the input's first and last node along u_axis count half
uniform float u_cell;    // the cell length l of the opacity conversion
uniform float u_max_opacity;

// expm1 and log1p without the cancellation of exp(x) - 1 and log(1 + x) near 0 (series below 0.05:
// the first omitted term is < 3e-11 relative).
float expm1_(float x) {
  if (abs(x) < 0.05) return x * (1.0 + x * (0.5 + x * (1.0 / 6.0 + x * (1.0 / 24.0 + x * (1.0 / 120.0)))));
  return exp(x) - 1.0;
}
float log1p_(float x) {
  if (abs(x) < 0.05) return x * (1.0 - x * (0.5 - x * (1.0 / 3.0 - x * (0.25 - x * 0.2))));
  return log(1.0 + x);
}

void main() {
  int id = int(gl_GlobalInvocationID.x);
  if (id >= u_count) return;
  int n = u_first + id;
  if (u_mode == 1) {
    dst[u_dst_offset + n] = min(u_max_opacity, -expm1_(-src[n] * u_cell));
    return;
  }
  if (u_mode == 2) {
    float a = clamp(src[n], 0.0, u_max_opacity);
    dst[u_dst_offset + n] = -log1p_(-a) / u_cell;
    return;
  }
  if (u_mode == 3) {
    dst[u_dst_offset + n] = src[n];
    return;
  }
  ivec3 o = ivec3(n % u_out_nx, (n / u_out_nx) % u_out_ny, n / (u_out_nx * u_out_ny));
  ivec3 in_dims = ivec3(u_in_nx, u_in_ny, u_in_nz);
  int n_in = in_dims[u_axis];
  int centre = u_stride * o[u_axis] + u_offset;
  int k0 = max(-u_radius, -centre), k1 = min(u_radius, n_in - 1 - centre);
  ivec3 c = o;
  float sum = 0.0;
  for (int k = k0; k <= k1; ++k) {
    c[u_axis] = centre + k;
    float end = u_halve_ends != 0 && (c[u_axis] == 0 || c[u_axis] == n_in - 1) ? 0.5 : 1.0;
    sum += end * taps[k + u_radius] * src[c.x + u_in_nx * (c.y + u_in_ny * c.z)];
  }
  dst[u_dst_offset + n] = sum;
}
