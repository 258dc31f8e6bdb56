// SPDX-License-Identifier: BSD-3-Clause
// render/shaders/cone_trace.comp -- one Gaussian cone per invocation, as
// render/src/occlusion/cone_tracer.cpp (ConeTracer::transmittance) and occlusion_shading.cpp
//
// The schedule (distance, trapezoid weight, section weight times alpha, the level, the level it
// blends toward and the blend, cone count) is the host ConeTracer's, so both paths take the same
// samples; this shader only walks it. Positions are relative to the pyramid's bounds centre so
// that float32 keeps ~1e-7 of the domain size.
// Fetches are trilinear from the level's nodes and read 0 beyond them (tau = 0 outside, never
// clamp-to-edge), exactly as PyramidLevel::sample.
#version 450

layout(local_size_x = kConeTraceGroup, local_size_y = 1, local_size_z = 1) in;

struct LevelInfo {
  ivec4 dims_offset;  // node counts, first value in `tau`
  vec4 lo;            // first node, relative to the origin; w = 1: 0 beyond the nodes themselves
  vec4 inv_spacing;
};
struct ScheduleEntry {
  vec4 distance_weight_kappa;  // distance, trapezoid weight, kappa * alpha, blend toward level_cones.z
  ivec4 level_cones;           // level, cones in the section (1, 3, 7), level blended toward, unused
};

layout(std430, binding = 0) readonly buffer Levels { float tau[]; };
layout(std430, binding = 1) readonly buffer Infos { LevelInfo levels[]; };
layout(std430, binding = 2) readonly buffer Schedule { ScheduleEntry schedule[]; };
layout(std430, binding = 3) readonly buffer Points { float point_xyz[]; };  // sources 0 and 2
layout(std430, binding = 4) writeonly buffer Result { float result[]; };
layout(std430, binding = 5) readonly buffer Grid { float grid_values[]; };  // source 2

// What one invocation computes:
//  0: the cone at point_xyz[first + id]
//  1: the cone at grid node first + id (object-space pre-illumination)
//  2: grid_values sampled trilinearly (clamped) at point_xyz[first + id]
uniform int u_source;
uniform int u_first;
uniform int u_count;
uniform vec3 u_grid_lo;
uniform vec3 u_grid_spacing;
uniform int u_grid_nx;
uniform int u_grid_ny;
uniform int u_grid_nz;
// 0: towards the eye u_target (full length); 1: along the direction u_target (directional
// light); 2: to the point light u_target, stopping there; 3: as 2 for a spot lighting the points
// whose direction from the light has cosine >= u_spot_cos with u_spot_dir.
uniform int u_target_kind;
uniform vec3 u_target;
uniform vec3 u_spot_dir;
uniform float u_spot_cos;
uniform int u_schedule_count;
uniform float u_gap;
uniform float u_length;
uniform vec3 u_dir3[3];  // sub-cone axes in the cone frame (x, y across, z along)
uniform vec3 u_dir7[7];
uniform float u_lateral3;  // ConeTracer::lateral_variance_ratio(3) and (7)
uniform float u_lateral7;


bool finite_value(float x) { return (floatBitsToUint(x) & 0x7fffffffu) < 0x7f800000u; }

float fetch(int l, vec3 p) {
  LevelInfo li = levels[l];
  ivec3 dims = li.dims_offset.xyz;
  vec3 u = (p - li.lo.xyz) * li.inv_spacing.xyz;
  if (!(u.x > -1.0 && u.y > -1.0 && u.z > -1.0 && u.x < float(dims.x) && u.y < float(dims.y) &&
        u.z < float(dims.z)))
    return 0.0;  // also rejects NaN
  if (li.lo.w > 0.5 && (any(lessThan(u, vec3(0.0))) || any(greaterThan(u, vec3(dims - 1))))) return 0.0;
  vec3 fl = floor(u);
  ivec3 i = ivec3(fl);
  vec3 f = u - fl;
  float sum = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    ivec3 d = ivec3(corner & 1, (corner >> 1) & 1, corner >> 2);
    ivec3 c = i + d;
    if (any(lessThan(c, ivec3(0))) || any(greaterThanEqual(c, dims))) continue;
    vec3 wv = mix(vec3(1.0) - f, f, vec3(d));
    float w = wv.x * wv.y * wv.z;
    sum += w * tau[li.dims_offset.w + c.x + dims.x * (c.y + dims.y * c.z)];
  }
  return sum;
}

float trace(vec3 apex, vec3 axis, float max_length) {
  float len = length(axis);
  if (!(len > 0.0) || !finite_value(len) || u_schedule_count == 0 || !(max_length > u_gap)) return 1.0;
  vec3 w = axis / len;
  // The same irrational switch as cone_tracer.cpp's frame().
  vec3 helper = abs(w.x) < 0.6180339887 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
  vec3 u = normalize(cross(helper, w));
  vec3 v = cross(w, u);
  vec3 dirs[7];
  float depth[7], amp[7];
  for (int i = 0; i < 7; ++i) {
    depth[i] = 0.0;
    amp[i] = 0.0;
    dirs[i] = w;
  }
  int cones = 1;
  for (int s = 0; s < u_schedule_count; ++s) {
    vec4 dwk = schedule[s].distance_weight_kappa;
    ivec4 lc = schedule[s].level_cones;
    float dist = dwk.x, weight = dwk.y, kappa = dwk.z;
    bool last = false;
    if (dist >= max_length) {
      // Stop at the target (a point light): one shortened trapezoid to max_length.
      float prev = s > 0 ? schedule[s - 1].distance_weight_kappa.x : dist;
      weight = s > 0 ? 0.5 * (max_length - prev) : 0.0;
      dist = max_length;
      last = true;
    }
    if (lc.y != cones) {
      if (cones == 1)
        for (int i = 1; i < 3; ++i) {
          depth[i] = depth[0];
          amp[i] = amp[0];
        }
      if (lc.y == 7) {
        // 3 -> 7: the centre takes the mean of the three, border cones 2k+1, 2k+2 the closest
        // 3-cone k (thesis Algorithm 4).
        float d3[3] = float[3](depth[0], depth[1], depth[2]);
        float a3[3] = float[3](amp[0], amp[1], amp[2]);
        depth[0] = (d3[0] + d3[1] + d3[2]) / 3.0;
        amp[0] = (a3[0] + a3[1] + a3[2]) / 3.0;
        for (int k = 0; k < 3; ++k)
          for (int j = 0; j < 2; ++j) {
            depth[1 + 2 * k + j] = d3[k];
            amp[1 + 2 * k + j] = a3[k];
          }
      }
      cones = lc.y;
      for (int i = 0; i < cones; ++i) {
        vec3 c = cones == 3 ? u_dir3[i] : u_dir7[i];
        dirs[i] = u * c.x + v * c.y + w * c.z;
      }
    }
    bool all_opaque = true;
    for (int i = 0; i < cones; ++i) {
      vec3 x = apex + dirs[i] * dist;
      float t = fetch(lc.x, x);
      if (dwk.w > 0.0) t += dwk.w * (fetch(lc.z, x) - t);
      float a = kappa * t;
      depth[i] += weight * (amp[i] + a);
      amp[i] = a;
      all_opaque = all_opaque && depth[i] > kOpaqueDepth;
    }
    if (last || all_opaque) break;
  }
  // Variance within each final cone from the spread between them (occlusion.h, "Lateral variance").
  float within = 0.0;
  if (cones > 1) {
    // Opaque depths enter clamped, as in cone_tracer.cpp.
    float clamped[7];
    float mean = 0.0, spread = 0.0;
    for (int i = 0; i < cones; ++i) {
      clamped[i] = min(depth[i], kSaturatedDepth);
      mean += clamped[i];
    }
    mean /= float(cones);
    for (int i = 0; i < cones; ++i) spread += (clamped[i] - mean) * (clamped[i] - mean);
    within = (cones == 3 ? u_lateral3 : u_lateral7) * spread / float(cones);
  }
  // Cosine-weighted mean over the final cones, each the mean of exp(-D) over a gamma-distributed D.
  float sum = 0.0, wsum = 0.0;
  for (int i = 0; i < cones; ++i) {
    float c = cones == 1 ? 1.0 : dot(dirs[i], w);
    float factor = 1.0;
    if (within > 0.0 && depth[i] > 0.0) {
      // ln(1 + x) / x. GLSL's log() near 1 is only good to an absolute 2^-21, so small x take
      // the series (its first left-out term, x^5 / 6, is below 4e-9 for x < 0.03).
      float x = within / depth[i];
      factor = x < 0.03 ? 1.0 - x * (0.5 - x * (1.0 / 3.0 - x * (0.25 - x * 0.2))) : log(1.0 + x) / x;
    }
    sum += c * exp(-depth[i] * factor);
    wsum += c;
  }
  return sum / wsum;
}

// directional_occlusion / shadow_transmittance at x. One call site of trace(): the compiler inlines
// every function, and each copy of the cone walk costs seconds of compile time on llvmpipe.
float cone_at(vec3 x) {
  vec3 axis = u_target;  // directional light: towards it
  float max_length = u_length;
  if (u_target_kind == 0) {
    axis = u_target - x;
  } else if (u_target_kind >= 2) {
    axis = u_target - x;
    max_length = length(axis);
    if (!(max_length > 0.0)) return 1.0;
    if (u_target_kind == 3 && dot(-axis, u_spot_dir) / max_length < u_spot_cos) return 0.0;
  }
  return trace(x, axis, max_length);
}

// PreIlluminationVolume::sample on grid_values.
float grid_sample(vec3 p) {
  ivec3 dims = ivec3(u_grid_nx, u_grid_ny, u_grid_nz);
  ivec3 i;
  vec3 f;
  for (int a = 0; a < 3; ++a) {
    float u = u_grid_spacing[a] > 0.0 ? (p[a] - u_grid_lo[a]) / u_grid_spacing[a] : 0.0;
    if (!finite_value(u)) u = 0.0;
    u = clamp(u, 0.0, float(dims[a] - 1));
    i[a] = min(int(u), dims[a] - 2);
    f[a] = u - float(i[a]);
  }
  float sum = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    ivec3 d = ivec3(corner & 1, (corner >> 1) & 1, corner >> 2);
    vec3 wv = mix(vec3(1.0) - f, f, vec3(d));
    ivec3 c = i + d;
    sum += wv.x * wv.y * wv.z * grid_values[c.x + dims.x * (c.y + dims.y * c.z)];
  }
  return sum;
}

void main() {
  int id = int(gl_GlobalInvocationID.x);
  if (id >= u_count) return;
  int n = u_first + id;
  vec3 x;
  if (u_source == 1) {
    int i = n % u_grid_nx, j = (n / u_grid_nx) % u_grid_ny, k = n / (u_grid_nx * u_grid_ny);
    x = u_grid_lo + vec3(float(i), float(j), float(k)) * u_grid_spacing;
  } else {
    x = vec3(point_xyz[3 * n], point_xyz[3 * n + 1], point_xyz[3 * n + 2]);
  }
  result[n] = u_source == 2 ? grid_sample(x) : cone_at(x);
}
