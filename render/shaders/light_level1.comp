// render/shaders/light_level1.comp -- a semi-Lagrangian pass of level 1 (level1_solve.cpp)
//
// u_mode 0: one slab group of the vertex order. Each invocation traces back from its vertex by
// its step through the tets (trace_segment: the same start-tet choice, canonical face planes,
// exit rule and exact optical depth), takes rho at the departure point from its tet's corners
// (interpolate_light) or level 0 where the walk left the mesh, and writes next[v]. A corner in an
// earlier group is read from next (updated in this pass), any other from rho1 (the previous
// pass): what the CPU's ordered Gauss-Seidel pass reads.
// u_mode 1: publishes the pass (rho1 = next for every ordered vertex) and takes the largest change.
// Float32 throughout; points and light relative to the mesh centre.
#version 450

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Points { vec4 points[]; };  // xyz, w = longest incident edge
layout(std430, binding = 1) readonly buffer Tets { ivec4 tets[]; };
layout(std430, binding = 2) readonly buffer Neighbors { ivec4 neighbors[]; };
layout(std430, binding = 3) readonly buffer TetField { vec4 tet_field[]; };  // gradient, scalar at vertex 0
layout(std430, binding = 4) readonly buffer Incidence { int incidence[]; };  // np + 1 offsets, then 4 tet + local
layout(std430, binding = 5) readonly buffer Params { float params[]; };  // extinction table, occluder boxes
layout(std430, binding = 6) readonly buffer Mask { uint mask_bytes[]; };  // level 0, 4 bytes per uint
layout(std430, binding = 7) readonly buffer Rho0 { float rho0[]; };
layout(std430, binding = 8) buffer Rho1 { float rho1[]; };
layout(std430, binding = 9) buffer Next { float next_rho[]; };
layout(std430, binding = 10) readonly buffer Order { int order[]; };  // ordered vertices, then group per point
layout(std430, binding = 11) buffer StartTet { int start_tet[]; };
layout(std430, binding = 12) buffer Counters { uint counters[]; };  // 0: largest change (float bits), 1: lost walks

uniform int u_mode;
uniform int u_group;
uniform int u_begin;          // the group's range in the order (mode 0)
uniform int u_count;          // its size (mode 0) / the ordered vertices (mode 1)
uniform int u_group_offset;   // where the groups start in Order
uniform int u_point;          // 1: point light
uniform vec3 u_light;         // point: position; directional: unit direction of travel
uniform float u_sigma_a;
uniform float u_step;
uniform int u_adaptive;
uniform vec3 u_box_lo;        // mesh bounds
uniform vec3 u_box_hi;
uniform ivec3 u_dims;         // level 0
uniform vec3 u_grid_lo;
uniform vec3 u_spacing;
uniform int u_breakpoints;    // table: x[n], a[n + 1], b[n + 1] at the start of params
uniform int u_occluders;      // boxes (lo.xyz, hi.xyz) after the table
uniform int u_occluder_offset;

const int kMaxMoves = 200000;
const float kParallel = 1e-12;
const float kGeometricDepth = 1.3862943611198906;
const float kLinearDepth = 2.772588722239781;
const uint kOutside = 0u;
const int kInside = 0, kLeftMesh = 1, kLost = 2;
const int kFaceVertices[12] = int[12](1, 2, 3, 0, 3, 2, 0, 1, 3, 0, 2, 1);

bool is_nan_bits(float x) { return (floatBitsToUint(x) & 0x7fffffffu) > 0x7f800000u; }
float flush_small(float v) { return v < 1e-30 ? 0.0 : v; }
vec3 point_at(int p) { return points[p].xyz; }

// ---- extinction table (extinction_table.h) ----
float tx(int i) { return params[i]; }
float ta(int p) { return params[u_breakpoints + p]; }
float tb(int p) { return params[2 * u_breakpoints + 1 + p]; }
int piece(float s) {  // number of breakpoints <= s (std::upper_bound)
  int lo = 0, hi = u_breakpoints;
  while (lo < hi) {
    int mid = (lo + hi) >> 1;
    if (tx(mid) <= s) lo = mid + 1; else hi = mid;
  }
  return lo;
}
float tau_at(int p, float s) { return max(0.0, ta(p) + tb(p) * s); }
float integral(float s0, float s1, float len) {
  if (!(len > 0.0)) return 0.0;
  int p0 = piece(s0), p1 = piece(s1);
  if (p0 == p1) return 0.5 * (tau_at(p0, s0) + tau_at(p0, s1)) * len;
  int stp = p1 > p0 ? 1 : -1;
  float inv_ds = 1.0 / (s1 - s0);
  float sa = s0, fa = 0.0, sum = 0.0;
  for (int p = p0;; p += stp) {
    bool last = p == p1;
    float sb = last ? s1 : tx(stp > 0 ? p : p - 1);
    float fb = last ? 1.0 : (sb - s0) * inv_ds;
    sum += 0.5 * (tau_at(p, sa) + tau_at(p, sb)) * (fb - fa);
    if (last) break;
    sa = sb;
    fa = fb;
  }
  return sum * len;
}

// ---- geometry (tet_geometry.h) ----
bool inside_box(vec3 p, vec3 lo, vec3 hi) { return all(greaterThanEqual(p, lo)) && all(lessThanEqual(p, hi)); }
vec3 occ_lo(int b) { int o = u_occluder_offset + 6 * b; return vec3(params[o], params[o + 1], params[o + 2]); }
vec3 occ_hi(int b) { int o = u_occluder_offset + 6 * b + 3; return vec3(params[o], params[o + 1], params[o + 2]); }

bool segment_meets_box(vec3 p0, vec3 p1, vec3 lo, vec3 hi) {
  float t0 = 0.0, t1 = 1.0;
  for (int a = 0; a < 3; ++a) {
    float d = p1[a] - p0[a];
    if (d == 0.0) {
      if (p0[a] < lo[a] || p0[a] > hi[a]) return false;
      continue;
    }
    float qa = (lo[a] - p0[a]) / d, qb = (hi[a] - p0[a]) / d;
    if (qa > qb) { float t = qa; qa = qb; qb = t; }
    t0 = max(t0, qa);
    t1 = min(t1, qb);
    if (t0 > t1) return false;
  }
  return true;
}

float volume6(vec3 a, vec3 b, vec3 c, vec3 d) { return dot(b - a, cross(c - a, d - a)); }

vec4 convex_weights(int t, vec3 p) {
  ivec4 tv = tets[t];
  vec3 q0 = point_at(tv.x), q1 = point_at(tv.y), q2 = point_at(tv.z), q3 = point_at(tv.w);
  float inv = 1.0 / volume6(q0, q1, q2, q3);
  vec4 w = vec4(volume6(p, q1, q2, q3), volume6(q0, p, q2, q3), volume6(q0, q1, p, q3), volume6(q0, q1, q2, p)) * inv;
  w = max(w, vec4(0.0));
  float sum = w.x + w.y + w.z + w.w;
  if (!(sum > 0.0)) return vec4(0.25);
  return w / sum;
}

// Outward face normal (not unit) and a point of face j, from the face's vertices sorted by id,
// so that both tets of a face get the same plane.
void face_plane(int t, int j, out vec3 n, out vec3 a) {
  ivec4 tv = tets[t];
  int f0 = tv[kFaceVertices[3 * j]], f1 = tv[kFaceVertices[3 * j + 1]], f2 = tv[kFaceVertices[3 * j + 2]];
  if (f0 > f1) { int x = f0; f0 = f1; f1 = x; }
  if (f1 > f2) { int x = f1; f1 = f2; f2 = x; }
  if (f0 > f1) { int x = f0; f0 = f1; f1 = x; }
  a = point_at(f0);
  precise vec3 nn = cross(point_at(f1) - a, point_at(f2) - a);
  if (dot(nn, point_at(tv[j]) - a) > 0.0) nn = -nn;
  n = nn;
}

float box_path_length(vec3 x) {
  vec3 d;
  float t1;
  if (u_point == 0) {
    d = -u_light;
    t1 = 3.0e38;
  } else {
    vec3 r = u_light - x;
    t1 = length(r);
    if (!(t1 > 0.0)) return 0.0;
    d = r / t1;
  }
  float t0 = 0.0;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (x[a] < u_box_lo[a] || x[a] > u_box_hi[a]) return 0.0;
      continue;
    }
    float qa = (u_box_lo[a] - x[a]) / d[a], qb = (u_box_hi[a] - x[a]) / d[a];
    if (qa > qb) { float t = qa; qa = qb; qb = t; }
    t0 = max(t0, qa);
    t1 = min(t1, qb);
  }
  return t1 > t0 ? t1 - t0 : 0.0;
}

// ---- level 0 (level0_grid.cpp) ----
uint mask_at(int id) { return (mask_bytes[id >> 2] >> (8 * (id & 3))) & 0xffu; }
int grid_index(int i, int j, int k) { return i + u_dims.x * (j + u_dims.y * k); }
void locate(vec3 p, out ivec3 c, out vec3 f) {
  for (int a = 0; a < 3; ++a) {
    float u = clamp((p[a] - u_grid_lo[a]) / u_spacing[a], 0.0, float(u_dims[a] - 1));
    int i = min(int(u), u_dims[a] - 2);
    c[a] = i;
    f[a] = u - float(i);
  }
}
float sample_level0(vec3 p, bool prefer_outside) {
  ivec3 c;
  vec3 f;
  locate(p, c, f);
  float sum = 0.0, wsum = 0.0, sum_out = 0.0, wsum_out = 0.0;
  bool any_outside = false;
  for (int corner = 0; corner < 8; ++corner) {
    int dx = corner & 1, dy = (corner >> 1) & 1, dz = corner >> 2;
    float w = (dx != 0 ? f.x : 1.0 - f.x) * (dy != 0 ? f.y : 1.0 - f.y) * (dz != 0 ? f.z : 1.0 - f.z);
    int id = grid_index(c.x + dx, c.y + dy, c.z + dz);
    float v = rho0[id];
    sum += w * v;
    wsum += w;
    if (prefer_outside && mask_at(id) == kOutside) {
      any_outside = true;
      float wo = max(w, 1e-12);
      sum_out += wo * v;
      wsum_out += wo;
    }
  }
  if (!prefer_outside) return sum;
  return any_outside ? sum_out / wsum_out : sum / wsum;
}

// ---- the walk (trace_segment) ----
struct Trace {
  int kind;
  int tet;
  vec3 end;
  float depth;
};

float segment_depth(int t, vec3 x, vec3 d, float t0, float t1) {
  if (!(t1 > t0)) return 0.0;
  vec4 fld = tet_field[t];
  if (is_nan_bits(fld.w)) return 0.0;
  float s_x = fld.w + dot(fld.xyz, x - point_at(tets[t].x));
  float slope = dot(fld.xyz, d);
  return integral(s_x + slope * t0, s_x + slope * t1, t1 - t0);
}

Trace trace_segment(int v, vec3 x, vec3 d, float seg_length, bool use_cache) {
  int tet = -1;
  int local = 0;
  float best = -3.0e38;
  int cache = use_cache ? start_tet[v] : -1;
  if (cache == -2) return Trace(kLeftMesh, -1, x, 0.0);
  if (cache >= 0) {
    tet = cache;
    ivec4 tv = tets[tet];
    while (local < 3 && tv[local] != v) ++local;
    best = 1.0;
  } else {
    int s_end = incidence[v + 1];
    for (int s = incidence[v]; s < s_end; ++s) {
      int entry = incidence[s];
      int t = entry >> 2, k = entry & 3;
      ivec4 tv = tets[t];
      vec3 e[3];
      int n = 0;
      for (int j = 0; j < 4; ++j)
        if (j != k) e[n++] = point_at(tv[j]) - x;
      vec3 c0 = cross(e[1], e[2]), c1 = cross(e[2], e[0]), c2 = cross(e[0], e[1]);
      float sgn = dot(e[0], c0) > 0.0 ? 1.0 : -1.0;
      float score = min(sgn * dot(d, c0) / length(c0), min(sgn * dot(d, c1) / length(c1), sgn * dot(d, c2) / length(c2)));
      if (score > best) {
        best = score;
        tet = t;
        local = k;
        if (best > 1e-3) break;
      }
    }
    // float32: a direction along a boundary face scores a rounding error either side of 0.
    if (tet < 0 || best < -1e-6) {
      if (use_cache) start_tet[v] = -2;
      return Trace(kLeftMesh, tet, x, 0.0);
    }
    if (use_cache) start_tet[v] = tet;
  }

  uint excluded = 0xFu & ~(1u << local);
  float t_in = 0.0, depth = 0.0;
  for (int move = 0; move < kMaxMoves; ++move) {
    float t_out = 3.0e38;
    int exit_face = -1;
    for (int j = 0; j < 4; ++j) {
      if ((excluded & (1u << j)) != 0u) continue;
      vec3 fn, fa;
      face_plane(tet, j, fn, fa);
      float den = dot(fn, d);
      if (den <= 0.0 || den * den <= kParallel * kParallel * dot(fn, fn)) continue;
      float tj = dot(fn, fa - x) / den;
      if (tj < t_out) {
        t_out = tj;
        exit_face = j;
      }
    }
    t_out = max(t_out, t_in);
    if (t_out >= seg_length || exit_face < 0) {
      depth += segment_depth(tet, x, d, t_in, seg_length);
      return Trace(kInside, tet, x + d * seg_length, depth);
    }
    depth += segment_depth(tet, x, d, t_in, t_out);
    int nxt = neighbors[tet][exit_face];
    if (nxt < 0) return Trace(kLeftMesh, tet, x + d * t_out, depth);
    excluded = 0u;
    ivec4 nb = neighbors[nxt];
    for (int f = 0; f < 4; ++f)
      if (nb[f] == tet) excluded |= 1u << f;
    tet = nxt;
    t_in = t_out;
  }
  return Trace(kLost, tet, x + d * seg_length, depth);
}

// ---- departure value (interpolate_light) ----
float read_rho(int c) { return order[u_group_offset + c] < u_group ? next_rho[c] : rho1[c]; }

float transverse_change(vec3 p[4], float value[4], vec3 u) {
  vec3 e1 = p[1] - p[0], e2 = p[2] - p[0], e3 = p[3] - p[0];
  float det = dot(e1, cross(e2, e3));
  vec3 g = (cross(e2, e3) * (value[1] - value[0]) + cross(e3, e1) * (value[2] - value[0]) +
            cross(e1, e2) * (value[3] - value[0])) / det;
  vec3 across = g - u * dot(g, u);
  float size = 0.0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) size = max(size, dot(p[b] - p[a], p[b] - p[a]));
  return length(across) * sqrt(size);
}

// Returns false where every corner lies on the inflow boundary but the departure point does not
// (the CPU's NaN): the caller walks on to the boundary.
bool interpolate_light(vec4 w, float rho[4], float path[4], float path_d, vec3 corner[4], vec3 u, out float result) {
  float lo = 3.0e38, linear = 0.0;
  for (int k = 0; k < 4; ++k) {
    lo = min(lo, rho[k]);
    linear += w[k] * rho[k];
  }
  result = linear;
  if (!(lo > 0.0)) return true;
  float depth[4];
  float depth_mean = 0.0, path_mean = 0.0;
  for (int k = 0; k < 4; ++k) {
    depth[k] = -log(rho[k]);
    depth_mean += w[k] * depth[k];
    path_mean += w[k] * path[k];
  }
  if (!(path_mean > 0.0)) return !(path_d > 0.0);
  float m = depth_mean / path_mean;
  float residual[4];
  for (int k = 0; k < 4; ++k) residual[k] = depth[k] - m * path[k];
  float across = transverse_change(corner, residual, u);
  float beta = clamp((across - kGeometricDepth) / (kLinearDepth - kGeometricDepth), 0.0, 1.0);
  float geometric = exp(-m * path_d);
  result = (1.0 - beta) * geometric + beta * linear;
  return true;
}

bool departure_value(Trace tr, out float value) {
  vec4 w = convex_weights(tr.tet, tr.end);
  ivec4 tv = tets[tr.tet];
  float values[4], path[4];
  vec3 corner[4];
  for (int k = 0; k < 4; ++k) {
    values[k] = read_rho(tv[k]);
    corner[k] = point_at(tv[k]);
    path[k] = box_path_length(corner[k]);
  }
  vec3 u = u_point != 0 ? normalize(tr.end - u_light) : u_light;
  return interpolate_light(w, values, path, box_path_length(tr.end), corner, u, value);
}

float update(int v) {
  vec3 x = point_at(v);
  for (int b = 0; b < u_occluders; ++b)
    if (inside_box(x, occ_lo(b), occ_hi(b))) return 0.0;
  vec3 d = -u_light;
  float len = u_adaptive != 0 ? max(u_step, 2.0 * points[v].w) : u_step;
  bool reaches_light = false;
  if (u_point != 0) {
    vec3 r = u_light - x;
    float dist = length(r);
    if (dist == 0.0) return 1.0;
    d = r / dist;
    if (dist <= 2.0 * len) {
      len = dist;
      reaches_light = true;
    }
  }
  Trace tr = trace_segment(v, x, d, len, true);
  float upstream = 0.0;
  bool walk_on = false;
  if (tr.kind == kInside && !reaches_light) {
    walk_on = !departure_value(tr, upstream);
    if (walk_on) tr = trace_segment(v, x, d, box_path_length(x) * (1.0 + 1e-5) + 1e-30, false);
  }
  if (tr.kind == kInside) {
    if (reaches_light || walk_on) upstream = 1.0;
  } else if (tr.kind == kLeftMesh) {
    upstream = sample_level0(tr.end, true);
  } else {
    atomicAdd(counters[1], 1u);
    upstream = sample_level0(tr.end, false);
  }
  for (int b = 0; b < u_occluders; ++b)
    if (segment_meets_box(x, tr.end, occ_lo(b), occ_hi(b))) return 0.0;
  return flush_small(upstream * exp(-u_sigma_a * tr.depth));
}

void main() {
  int i = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
  if (i >= u_count) return;
  if (u_mode == 0) {
    int v = order[u_begin + i];
    next_rho[v] = update(v);
  } else {
    int v = order[i];
    float change = abs(next_rho[v] - rho1[v]);
    rho1[v] = next_rho[v];
    if (change > 0.0 && !is_nan_bits(change)) atomicMax(counters[0], floatBitsToUint(change));
  }
}
