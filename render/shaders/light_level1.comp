// SPDX-License-Identifier: BSD-3-Clause
// render/shaders/light_level1.comp -- a semi-Lagrangian pass of level 1 (level1_solve.cpp)
//
// u_mode 0: one slab group of the vertex order. Each invocation traces back from its vertex by
// its step through the tets (level1_walk.cpp: the same start, edge-sign exit rule with the same
// tie rule and turned retries, and exact optical depth), takes rho at the departure point from
// its tet's corners (interpolate_light) or level 0 where the walk left the mesh, and writes
// next[v]. A corner in an
// earlier group is read from next (updated in this pass), any other from rho1 (the previous
// pass): what the CPU's ordered Gauss-Seidel pass reads.
// u_mode 1: publishes the pass (rho1 = next for every ordered vertex) and takes the largest change.
// Float32 throughout; points and light relative to the mesh centre.
#version 450

layout(local_size_x = kLightGroup) in;

layout(std430, binding = 0) readonly buffer Points { vec4 points[]; };  // xyz, w = longest incident edge
layout(std430, binding = 1) readonly buffer Tets { ivec4 tets[]; };  // walk records (level1_mesh.h)
layout(std430, binding = 2) readonly buffer Neighbors { ivec4 neighbors[]; };  // record << 2 | face, -1
layout(std430, binding = 3) readonly buffer PointScalars { float scalars[]; };
// np + 1 offsets, then per star entry: record << 2 | local index, the opposite face's vertices
layout(std430, binding = 4) readonly buffer Incidence { int incidence[]; };
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

const int kInside = 0, kLeftMesh = 1, kLost = 2;

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
  if (!(len > 0.0) || is_nan_bits(s0) || is_nan_bits(s1)) return 0.0;
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
    if (prefer_outside && mask_at(id) == kMaskOutside) {
      any_outside = true;
      float wo = max(w, 1e-12);
      sum_out += wo * v;
      wsum_out += wo;
    }
  }
  if (!prefer_outside) return sum;
  return any_outside ? sum_out / wsum_out : sum / wsum;
}

// ---- the walk (level1_walk.cpp, ray_frame.h) ----
const int kFaceVertices[12] = int[12](1, 2, 3, 0, 3, 2, 0, 1, 3, 0, 2, 1);
const int kAbc[12] = int[12](1, 3, 2, 0, 2, 3, 1, 0, 3, 0, 1, 2);
const int kExitX[8] = int[8](1, 1, 2, 2, 3, 1, 3, 1);

// The ray's frame (RayFrame: Duff et al.), the quarter turn of the plane across it, and whether
// edge values within kSnap of their size are snapped to 0 (a retried walk: level1_walk.cpp).
// Float32 projections are noisier than the CPU's doubles, hence the larger kSnap.
vec3 g_origin, g_u, g_v, g_d;
int g_quarter;
bool g_snap;
const float kSnap = 1e-5;

void set_frame(vec3 o, vec3 d) {
  g_origin = o;
  g_d = d;
  float sgn = (floatBitsToUint(d.z) & 0x80000000u) != 0u ? -1.0 : 1.0;  // copysign(1, d.z)
  float a = -1.0 / (sgn + d.z);
  float b = d.x * d.y * a;
  g_u = vec3(1.0 + sgn * d.x * d.x * a, sgn * b, -sgn * d.x);
  g_v = vec3(b, sgn + d.y * d.y * a, -d.y);
}

// Ray-plane coordinates and depth of point id; `precise` so that every use of a point and of
// an edge computes the very same value (the walk's consistency rests on it).
vec3 at(int id) {
  precise vec3 r = points[id].xyz - g_origin;
  precise float x = dot(r, g_u);
  precise float y = dot(r, g_v);
  precise float z = dot(r, g_d);
  if (g_quarter == 1) return vec3(-y, x, z);
  if (g_quarter == 2) return vec3(-x, -y, z);
  if (g_quarter == 3) return vec3(y, -x, z);
  return vec3(x, y, z);
}

float edge_noise(vec3 a, vec3 b) { return kSnap * (a.x * a.x + a.y * a.y + b.x * b.x + b.y * b.y); }

float edge_value(vec3 a, int ia, vec3 b, int ib) {
  bool fwd = ia <= ib;
  vec3 p = fwd ? a : b, q = fwd ? b : a;
  precise float v = p.x * q.y - p.y * q.x;
  if (g_snap && abs(v) <= edge_noise(a, b)) return 0.0;
  return fwd ? v : -v;
}

bool edge_positive(float value, vec3 a, int ia, vec3 b, int ib) {
  if (value > 0.0) return true;
  if (value < 0.0) return false;
  bool fwd = ia <= ib;
  vec3 p = fwd ? a : b, q = fwd ? b : a;
  float dy = q.y - p.y, dx = q.x - p.x;
  int s = dy != 0.0 ? (dy > 0.0 ? -1 : 1) : (dx != 0.0 ? (dx > 0.0 ? 1 : -1) : 0);
  return (fwd ? s : -s) > 0;
}

struct Trace {
  int kind;
  int tet;      // walk record holding the end, or the last one walked
  float end;    // ray parameter of the departure point, or where the walk left the mesh
  float depth;
  vec4 w;       // the departure point's weights in tet
  bool grazed;  // could not start only by the tie rule
};

// A crossing: face points, their weights, depth and scalar.
ivec3 c_id;
vec3 c_mu;
float c_t, c_s;

void cross_face(ivec3 id, vec3 qa, vec3 qb, vec3 qc, vec3 w, float t_in, float s_in) {
  c_id = id;
  float sum = w.x + w.y + w.z;
  if (!(sum > 0.0)) {
    c_mu = vec3(0.0);
    c_t = t_in;
    c_s = s_in;
    return;
  }
  c_mu = w / sum;
  c_t = max(c_mu.x * qa.z + c_mu.y * qb.z + c_mu.z * qc.z, t_in);
  c_s = c_mu.x * scalars[id.x] + c_mu.y * scalars[id.y] + c_mu.z * scalars[id.z];
}

// Whether the ray from v leaves through the face (outward order) opposite v; sets the crossing.
bool leaves_through(ivec3 f, int v, inout bool grazed) {
  vec3 q0 = at(f.x), q1 = at(f.y), q2 = at(f.z);
  float e0 = edge_value(q1, f.y, q2, f.z), e1 = edge_value(q2, f.z, q0, f.x), e2 = edge_value(q0, f.x, q1, f.y);
  bool positive = edge_positive(e0, q1, f.y, q2, f.z) && edge_positive(e1, q2, f.z, q0, f.x) &&
                  edge_positive(e2, q0, f.x, q1, f.y);
  if (!positive) {
    // Touched on its rim, up to rounding noise: the ray runs along the boundary.
    grazed = grazed || (e0 >= -edge_noise(q1, q2) && e1 >= -edge_noise(q2, q0) && e2 >= -edge_noise(q0, q1));
    return false;
  }
  cross_face(f, q0, q1, q2, max(vec3(e0, e1, e2), vec3(0.0)), 0.0, scalars[v]);
  return true;
}

Trace walk(int v, float seg_length, bool use_cache) {
  Trace tr = Trace(kLost, -1, 0.0, 0.0, vec4(0.0), false);
  int cache = use_cache ? start_tet[v] : -1;
  if (cache == -2) {
    tr.kind = kLeftMesh;
    return tr;
  }
  int slot = -1, k = -1;
  if (cache >= 0) {
    slot = cache >> 2;
    k = cache & 3;
    ivec4 tv = tets[slot];
    bool unused = false;
    leaves_through(ivec3(tv[kFaceVertices[3 * k]], tv[kFaceVertices[3 * k + 1]], tv[kFaceVertices[3 * k + 2]]), v, unused);
  } else {
    int s_end = incidence[v + 1];
    for (int s = incidence[v]; s < s_end; s += 4) {
      if (leaves_through(ivec3(incidence[s + 1], incidence[s + 2], incidence[s + 3]), v, tr.grazed)) {
        slot = incidence[s] >> 2;
        k = incidence[s] & 3;
        break;
      }
    }
    if (slot >= 0) tr.grazed = false;
    if (use_cache) start_tet[v] = slot < 0 ? -2 : ((slot << 2) | k);
    if (slot < 0) {
      tr.kind = kLeftMesh;
      return tr;
    }
  }
  // The segment in the current tet runs from the entry crossing to c_*; v enters the first.
  ivec3 in_id = ivec3(v);
  vec3 in_mu = vec3(1.0, 0.0, 0.0);
  float in_t = 0.0, in_s = scalars[v];
  int nxt = neighbors[slot][k];
  for (int move = 0; move < kMaxMoves; ++move) {
    if (c_t >= seg_length) {
      ivec4 tv = tets[slot];
      float f = c_t > in_t ? (seg_length - in_t) / (c_t - in_t) : 0.0;
      vec4 w = vec4(0.0);
      for (int j = 0; j < 4; ++j) {
        for (int c = 0; c < 3; ++c) {
          if (in_id[c] == tv[j]) w[j] += (1.0 - f) * in_mu[c];
          if (c_id[c] == tv[j]) w[j] += f * c_mu[c];
        }
      }
      w = max(w, vec4(0.0));
      float sum = w.x + w.y + w.z + w.w;
      tr.w = sum > 0.0 ? w / sum : vec4(0.25);
      tr.depth += integral(in_s, in_s + f * (c_s - in_s), seg_length - in_t);
      tr.kind = kInside;
      tr.tet = slot;
      tr.end = seg_length;
      return tr;
    }
    tr.depth += integral(in_s, c_s, c_t - in_t);
    if (nxt < 0) {
      tr.kind = kLeftMesh;
      tr.tet = slot;
      tr.end = c_t;
      return tr;
    }
    slot = nxt >> 2;
    k = nxt & 3;
    in_id = c_id;
    in_mu = c_mu;
    in_t = c_t;
    in_s = c_s;
    ivec4 tv = tets[slot];
    int id[4] = int[4](tv[k], tv[kAbc[3 * k]], tv[kAbc[3 * k + 1]], tv[kAbc[3 * k + 2]]);  // D, A, B, C
    vec3 q[4] = vec3[4](at(id[0]), at(id[1]), at(id[2]), at(id[3]));
    float e_d[4];
    e_d[0] = 0.0;
    int pattern = 0;
    for (int j = 1; j < 4; ++j) {
      e_d[j] = edge_value(q[0], id[0], q[j], id[j]);
      if (edge_positive(e_d[j], q[0], id[0], q[j], id[j])) pattern |= 1 << (j - 1);
    }
    int x = kExitX[pattern], y = x == 3 ? 1 : x + 1;
    nxt = neighbors[slot][kAbc[3 * k + 5 - x - y]];
    vec3 w3 = max(vec3(edge_value(q[x], id[x], q[y], id[y]), -e_d[y], e_d[x]), vec3(0.0));
    cross_face(ivec3(id[0], id[x], id[y]), q[0], q[x], q[y], w3, in_t, in_s);
  }
  tr.kind = kLost;
  tr.tet = slot;
  tr.end = seg_length;
  return tr;
}

// The walk, retried with rounding noise snapped and the plane across the ray turned when it
// could not start only by the tie rule or by that noise (walk_turned in level1_walk.cpp).
Trace walk_to_light(int v, vec3 x, vec3 d, float seg_length, bool use_cache) {
  set_frame(x, d);
  g_quarter = 0;
  g_snap = false;
  Trace first = walk(v, seg_length, use_cache);
  if (!first.grazed) return first;
  if (use_cache) start_tet[v] = -1;
  g_snap = true;
  for (g_quarter = 0; g_quarter <= 3; ++g_quarter) {
    Trace t = walk(v, seg_length, false);
    if (t.tet >= 0) return t;
  }
  return first;
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

bool departure_value(Trace tr, vec3 end, out float value) {
  vec4 w = tr.w;
  ivec4 tv = tets[tr.tet];
  float values[4], path[4];
  vec3 corner[4];
  for (int k = 0; k < 4; ++k) {
    values[k] = read_rho(tv[k]);
    corner[k] = point_at(tv[k]);
    path[k] = box_path_length(corner[k]);
  }
  vec3 u = u_point != 0 ? normalize(end - u_light) : u_light;
  return interpolate_light(w, values, path, box_path_length(end), corner, u, value);
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
  Trace tr = walk_to_light(v, x, d, len, true);
  vec3 end = x + d * tr.end;
  float upstream = 0.0;
  bool walk_on = false;
  if (tr.kind == kInside && !reaches_light) {
    walk_on = !departure_value(tr, end, upstream);
    if (walk_on) {
      tr = walk_to_light(v, x, d, box_path_length(x) * (1.0 + 1e-5) + 1e-30, false);
      end = x + d * tr.end;
    }
  }
  if (tr.kind == kInside) {
    if (reaches_light || walk_on) upstream = 1.0;
  } else if (tr.kind == kLeftMesh) {
    // A hair beyond the exit, as the CPU (kExitNudge of the smallest level-0 spacing).
    upstream = sample_level0(end + d * (1e-4 * min(u_spacing.x, min(u_spacing.y, u_spacing.z))), true);
  } else {
    atomicAdd(counters[1], 1u);
    upstream = sample_level0(end, false);
  }
  for (int b = 0; b < u_occluders; ++b)
    if (segment_meets_box(x, end, occ_lo(b), occ_hi(b))) return 0.0;
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
