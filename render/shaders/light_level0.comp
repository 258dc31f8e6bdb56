// SPDX-License-Identifier: BSD-3-Clause
// render/shaders/light_level0.comp -- one wavefront of the level-0 upwind sweep (level0_sweep.cpp)
//
// Node (i, j, k) depends on its upwind neighbours (i - s_i, j, k) ..., s_a the sign of its index
// minus the light's node c_a (0 on the light's plane). Those are one step closer to c in the
// index distance m = |i - c_i| + |j - c_j| + |k - c_k|, so all nodes at one m are independent:
// the host dispatches m = m_min .. m_max in order. One invocation per (j, k) computes the (at
// most two) nodes of its row at distance m. Directional lights have c just outside the grid
// corner the light comes from, so every node has s = the light's octant, as on the CPU.
#version 450

layout(local_size_x = kLightGroup) in;

layout(std430, binding = 0) readonly buffer Tau { float tau[]; };
layout(std430, binding = 1) readonly buffer Mask { uint mask_bytes[]; };  // 4 Level0Mask bytes per uint
layout(std430, binding = 2) buffer Rho { float rho[]; };

uniform ivec3 u_dims;
uniform ivec3 u_centre;     // the light's node (directional: -1 or dims per axis)
uniform int u_level;        // m
uniform int u_point;        // 1: point light
uniform vec3 u_spacing;
uniform vec3 u_light;       // point: light position minus the grid's lo
uniform vec3 u_w_dir;       // directional: |u_a| / h_a normalised to sum 1
uniform float u_ds_dir;     // directional: 1 / sum_a |u_a| / h_a
uniform float u_sigma_a;


uint mask_at(int id) { return (mask_bytes[id >> 2] >> (8 * (id & 3))) & 0xffu; }
int index_of(ivec3 n) { return n.x + u_dims.x * (n.y + u_dims.y * n.z); }
float flush_small(float v) { return v < 1e-30 ? 0.0 : v; }

void solve_node(ivec3 idx) {
  int id = index_of(idx);
  if (mask_at(id) == kMaskOccluder) {
    rho[id] = 0.0;
    return;
  }
  ivec3 s = ivec3(sign(idx - u_centre));
  float value = 0.0;
  if (u_point == 0) {
    float real = 0.0;
    bool outside = false;
    for (int a = 0; a < 3; ++a) {
      if (u_w_dir[a] == 0.0) continue;
      ivec3 nb = idx;
      nb[a] -= s[a];
      if (nb[a] < 0 || nb[a] >= u_dims[a]) {
        outside = true;
        break;
      }
      int nid = index_of(nb);
      real += u_w_dir[a] * rho[nid] * exp(-0.5 * u_sigma_a * u_ds_dir * tau[nid]);
    }
    value = outside ? 1.0 : real * exp(-0.5 * u_sigma_a * u_ds_dir * tau[id]);
  } else {
    vec3 r = vec3(idx) * u_spacing - u_light;
    float dist = length(r);
    if (dist == 0.0) {
      rho[id] = 1.0;
      return;
    }
    vec3 w = vec3(0.0);
    float sum = 0.0;
    for (int a = 0; a < 3; ++a) {
      w[a] = s[a] != 0 ? abs(r[a]) / dist / u_spacing[a] : 0.0;
      sum += w[a];
    }
    float ti = tau[id];
    if (sum == 0.0) {
      value = exp(-u_sigma_a * ti * dist);  // the light's own node
    } else {
      float ds = min(1.0 / sum, dist);
      for (int a = 0; a < 3; ++a) {
        if (w[a] == 0.0) continue;
        ivec3 nb = idx;
        nb[a] -= s[a];
        if (nb[a] < 0 || nb[a] >= u_dims[a]) {
          value = 1.0;
          break;
        }
        int nid = index_of(nb);
        value += w[a] / sum * rho[nid] * exp(-0.5 * u_sigma_a * ds * (ti + tau[nid]));
      }
    }
  }
  rho[id] = flush_small(value);
}

void main() {
  int row = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
  if (row >= u_dims.y * u_dims.z) return;
  int j = row % u_dims.y, k = row / u_dims.y;
  int rest = u_level - abs(j - u_centre.y) - abs(k - u_centre.z);
  if (rest < 0) return;
  int i0 = u_centre.x - rest, i1 = u_centre.x + rest;
  if (i0 >= 0 && i0 < u_dims.x) solve_node(ivec3(i0, j, k));
  if (i1 != i0 && i1 >= 0 && i1 < u_dims.x) solve_node(ivec3(i1, j, k));
}
