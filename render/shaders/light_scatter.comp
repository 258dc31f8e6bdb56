// SPDX-License-Identifier: BSD-3-Clause
// render/shaders/light_scatter.comp -- one Chebyshev-accelerated Jacobi iteration of the implicit
// diffusion step (eq. 12)
//
// The update of light_scattering.cpp, reading the previous iterate everywhere:
//     J_v = (L0_v + s sum_i w_i L_i) / (1 + s sum_i w_i),  L_v <- L_v' + omega (J_v - L_v')
// per channel, with L' the iterate before the previous one (in the buffer being overwritten) and
// omega from scatter_iteration_part's recurrence (1 on the first iteration). Points whose source is not
// finite are left out of every neighbour sum and take the weighted mean of their finite
// neighbours (0 without any), so NaN never spreads. The largest change goes to counters[u_slot].
#version 450

layout(local_size_x = kLightGroup) in;

layout(std430, binding = 0) readonly buffer Edges { int edges[]; };  // np + 1 offsets, then neighbour ids
layout(std430, binding = 1) readonly buffer Weights { float weights[]; };
layout(std430, binding = 2) readonly buffer Source { float pre[]; };
layout(std430, binding = 3) readonly buffer Previous { float src[]; };
layout(std430, binding = 4) buffer Current { float dst[]; };  // the iterate before src, overwritten
layout(std430, binding = 5) buffer Counters { uint counters[]; };

uniform int u_points;
uniform vec3 u_sigma_s;
uniform int u_slot;
uniform vec3 u_omega;
uniform int u_first;  // 1: dst holds nothing yet (omega is 1)

bool finite_bits(float x) { return (floatBitsToUint(x) & 0x7f800000u) != 0x7f800000u; }
bool finite_source(int p) { return finite_bits(pre[3 * p]) && finite_bits(pre[3 * p + 1]) && finite_bits(pre[3 * p + 2]); }

void main() {
  int p = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
  if (p >= u_points) return;
  vec3 sum = vec3(0.0);
  float wsum = 0.0;
  int s_end = edges[p + 1];
  for (int s = edges[p]; s < s_end; ++s) {
    int q = edges[s];
    float w = weights[s - (u_points + 1)];
    if (w == 0.0 || !finite_source(q)) continue;
    sum += w * vec3(src[3 * q], src[3 * q + 1], src[3 * q + 2]);
    wsum += w;
  }
  bool own = finite_source(p);
  float residual = 0.0;
  for (int ch = 0; ch < 3; ++ch) {
    float old = src[3 * p + ch];
    float v;
    if (!own)
      v = wsum > 0.0 ? sum[ch] / wsum : 0.0;
    else if (u_sigma_s[ch] == 0.0 || wsum == 0.0)
      v = pre[3 * p + ch];
    else
      v = (pre[3 * p + ch] + u_sigma_s[ch] * sum[ch]) / (1.0 + u_sigma_s[ch] * wsum);
    if (own && u_first == 0) {
      float before = dst[3 * p + ch];
      v = before + u_omega[ch] * (v - before);
    }
    float change = abs(v - old);
    if (finite_bits(change)) residual = max(residual, change);
    dst[3 * p + ch] = v;
  }
  if (residual > 0.0) atomicMax(counters[u_slot], floatBitsToUint(residual));
}
