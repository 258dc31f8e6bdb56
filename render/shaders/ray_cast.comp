// SPDX-License-Identifier: BSD-3-Clause
// render/shaders/ray_cast.comp -- one ray per invocation, as render/src/cpu_ray_caster.cpp
//
// The same algorithm as the CPU caster, in float32: every boundary entry along the ray from a
// BVH over the boundary faces (taken in depth order, one query per entry, so that there is no
// fixed cap on re-entries), the tet walk by Plücker signs with the id-ordered tie rule
// (simulation of simplicity), the exact per-segment integral (Taylor series of 1 - Z for thin
// segments, closed forms with erfcx and Dawson's integral beyond), early termination.
// `precise` keeps the compiler from fusing or reordering the projections and edge values: two
// tets sharing an edge must see bit-identical numbers for the walk to stay watertight.
#version 450

layout(local_size_x = kRayCastTile, local_size_y = kRayCastTile, local_size_z = 1) in;

layout(std430, binding = 0) readonly buffer Points { float point_xyz[]; };
layout(std430, binding = 1) readonly buffer TetVertices { ivec4 tet_vertices[]; };
layout(std430, binding = 2) readonly buffer TetNext { ivec4 tet_next[]; };
layout(std430, binding = 3) readonly buffer Scalars { float scalars[]; };
layout(std430, binding = 4) readonly buffer Triangles { ivec4 triangles[]; };
layout(std430, binding = 5) readonly buffer Nodes { vec4 bvh_nodes[]; };
layout(std430, binding = 6) readonly buffer Tf { float tf_data[]; };
layout(std430, binding = 7) writeonly buffer Pixels { vec4 pixels[]; };
layout(std430, binding = 8) readonly buffer LightRgb { float light_rgb[]; };  // 3 per point (u_shading 2)
// With u_runs: per pixel of the tile, 1 + 2 kMaxRayRuns: the run count, then per run (entry
// depth, exit depth) and its premultiplied RGBA.
layout(std430, binding = 9) writeonly buffer Runs { vec4 runs[]; };

uniform ivec2 u_image_size;
uniform ivec2 u_tile_origin;     // first pixel of this dispatch
uniform ivec2 u_tile_size;
uniform vec3 u_eye;              // relative to the mesh centre, as the points
uniform vec3 u_forward;
uniform vec3 u_right;
uniform vec3 u_up;
uniform vec2 u_half_extent;      // tan(fov/2) * aspect, tan(fov/2)
uniform int u_eye_outside;       // 1: the eye is outside the padded bounds
uniform float u_reentry_slack;
uniform float u_stop_transmittance;
uniform int u_runs;              // 1: record the runs
uniform int u_tet_count;
uniform int u_triangle_count;
uniform int u_breakpoint_count;
uniform float u_series[64];      // coefficients of 1 - Z, see gpu_tf_layout.h
// Shading (penumbra/render/shading.h): 0 none, 1 Phong, 2 Phong times the light field.
uniform int u_shading;
uniform vec4 u_phong;            // ambient, diffuse, specular, shininess
uniform vec3 u_to_light;         // unit, towards the key light
uniform int u_headlight;         // 1: the light comes from the eye

const int kPieceFloats = 12;
const int kMaxZeroLengthSteps = 1024;
const int kMaxEntries = 1 << 16;
const float kInf = 3.0e38;  // beyond any depth; a literal infinity is not a constant expression everywhere

// Ray frame (Duff et al. 2017): u x v = d.
vec3 g_origin, g_d, g_u, g_v;

vec3 project(int id) {
  precise vec3 r = vec3(point_xyz[3 * id], point_xyz[3 * id + 1], point_xyz[3 * id + 2]) - g_origin;
  precise vec3 q = vec3(dot(r, g_u), dot(r, g_v), dot(r, g_d));
  return q;
}

// e(a, b) computed from the smaller id to the larger, negated for the other direction.
float edge_value(vec3 a, int ia, vec3 b, int ib) {
  bool forward = ia <= ib;
  vec3 p = forward ? a : b;
  vec3 q = forward ? b : a;
  precise float v = p.x * q.y - p.y * q.x;
  return forward ? v : -v;
}

// Sign of e(a, b); an exact zero is decided by displacing the ray by (eps, eps^2) along (u, v).
int edge_sign(float value, vec3 a, int ia, vec3 b, int ib) {
  if (value > 0.0) return 1;
  if (value < 0.0) return -1;
  bool forward = ia <= ib;
  vec3 p = forward ? a : b;
  vec3 q = forward ? b : a;
  float dy = q.y - p.y, dx = q.x - p.x;
  int s = dy != 0.0 ? (dy > 0.0 ? -1 : 1) : (dx != 0.0 ? (dx > 0.0 ? 1 : -1) : 0);
  return forward ? s : -s;
}

// A field value; NaN ("no data") is recognised by its bits, which no compiler folds away.
float scalar_at(int id, inout bool nan) {
  float s = scalars[id];
  if ((floatBitsToUint(s) & 0x7fffffffu) > 0x7f800000u) {
    nan = true;
    return 0.0;
  }
  return s;
}

// ---- transfer function ----------------------------------------------------------------------

float breakpoint(int i) { return tf_data[(u_breakpoint_count + 1) * kPieceFloats + i]; }

// Number of breakpoints <= s.
int piece_of(float s) {
  int lo = 0, hi = u_breakpoint_count;
  while (lo < hi) {
    int mid = (lo + hi) >> 1;
    if (breakpoint(mid) <= s) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

int piece_near(float s, int hint) {
  if (hint >= 0) {
    bool above_lo = hint == 0 || s >= breakpoint(hint - 1);
    bool below_hi = hint == u_breakpoint_count || s < breakpoint(hint);
    if (above_lo && below_hi) return hint;
  }
  return piece_of(s);
}

bool piece_empty(int p) { return tf_data[p * kPieceFloats + 3] != 0.0; }

// erfc(y) exp(y^2) for y >= 0, fractional error < 1.2e-7 (Numerical Recipes' erfcc without
// its exp(-y^2) factor, so it never underflows).
float erfcx(float y) {
  float t = 1.0 / (1.0 + 0.5 * y);
  return t * exp(-1.26551223 + t * (1.00002368 + t * (0.37409196 + t * (0.09678418 + t * (-0.18628806 +
         t * (0.27886807 + t * (-1.13520398 + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))))))));
}

// Dawson's integral for x >= 0, relative error ~2e-7 (Rybicki's method, Numerical Recipes 6.10).
float dawson(float x) {
  if (x < 0.2) {
    float x2 = x * x;
    return x * (1.0 - 0.666666667 * x2 * (1.0 - 0.4 * x2 * (1.0 - 0.285714286 * x2)));
  }
  const float h = 0.4;
  float n0 = 2.0 * floor(0.5 * x / h + 0.5);
  float xp = x - n0 * h;
  float e1 = exp(2.0 * xp * h);
  float e2 = e1 * e1;
  float d1 = n0 + 1.0, d2 = d1 - 2.0, sum = 0.0;
  for (int i = 1; i <= 6; ++i) {
    float c = exp(-((2.0 * float(i) - 1.0) * h) * ((2.0 * float(i) - 1.0) * h));
    sum += c * (e1 / d1 + 1.0 / (d2 * e1));
    d1 += 2.0;
    d2 -= 2.0;
    e1 *= e2;
  }
  return 0.5641895835 * exp(-xp * xp) * sum;
}

// 1 - Z(a, b) by the series (Horner in a over polynomials in k), truncated after order n.
float one_minus_z_series(float a, float k, int n) {
  float sum = 0.0;
  for (int j = n; j >= 0; --j) {
    float inner = 0.0;
    for (int i = n - j; i >= 0; --i) inner = inner * k + u_series[(i + j) * 8 + j];
    sum = sum * a + inner;
  }
  return sum;
}

// 1 - exp(-m) for m >= 0 without cancellation for small m.
float one_minus_exp(float m) {
  if (m < 0.01) return m * (1.0 - m * (0.5 - m * (0.16666667 - m * 0.041666667)));
  return 1.0 - exp(-m);
}

// 1 - Z(a, b), Z = int_0^1 exp(-(a u + (b - a) u^2 / 2)) du (segment_integral.h).
float one_minus_z(float a, float b) {
  float k = 0.5 * (b - a);
  float delta = a + abs(k);
  // Remainder delta^(n+1)/(n+1)! below ~1e-8 (float32 resolution).
  if (delta <= 0.02) return one_minus_z_series(a, k, 3);
  if (delta <= 0.25) return one_minus_z_series(a, k, 7);
  float m = 0.5 * (a + b);
  // |k| tiny against a: Z = (1 - exp(-m)) / m up to O(k^2).
  if (abs(k) <= 1e-4 * m) return 1.0 - one_minus_exp(m) / m;
  float t = exp(-m);
  float sk = sqrt(abs(k));
  float z;
  if (b > a) z = 0.886226925 * (erfcx(a / (2.0 * sk)) - t * erfcx(b / (2.0 * sk))) / sk;
  else z = (dawson(a / (2.0 * sk)) - t * dawson(b / (2.0 * sk))) / sk;
  return 1.0 - z;
}

// Composites the part of a segment inside piece p, scalar sa -> sb over `len`, onto (rgb, T).
// The emitted colour is multiplied by the modulation running from mf (front of the whole
// segment) to mb (back); [fa, fb] is where this piece lies along the segment.
void integrate_in_piece(int p, float sa, float sb, float len, vec3 mf, vec3 mb, float fa, float fb, inout vec3 rgb,
                        inout float T) {
  int o = p * kPieceFloats;
  if (tf_data[o + 3] != 0.0 || !(len > 0.0)) return;
  float s_ref = tf_data[o], tau_ref = tf_data[o + 1], tau1 = tf_data[o + 2];
  float a = max(0.0, tau_ref + tau1 * (sa - s_ref)) * len;
  float b = max(0.0, tau_ref + tau1 * (sb - s_ref)) * len;
  if (a == 0.0 && b == 0.0) return;
  vec3 col_ref = vec3(tf_data[o + 4], tf_data[o + 5], tf_data[o + 6]);
  vec3 col1 = vec3(tf_data[o + 8], tf_data[o + 9], tf_data[o + 10]);
  vec3 cf = (col_ref + col1 * (sa - s_ref)) * mix(mf, mb, fa);
  vec3 cb = (col_ref + col1 * (sb - s_ref)) * mix(mf, mb, fb);
  float w = one_minus_z(a, b);           // weight of the front colour, 1 - Z
  float absorbed = one_minus_exp(0.5 * (a + b));
  rgb += T * (cf * w + cb * (absorbed - w));
  T *= 1.0 - absorbed;
}

// The segment s0 (front) -> s1 (back) of `len`, cut at every breakpoint in between.
void integrate(float s0, int p0, float s1, int p1, float len, vec3 mf, vec3 mb, inout vec3 rgb, inout float T) {
  if (!(len > 0.0)) return;
  if (p0 == p1) {
    integrate_in_piece(p0, s0, s1, len, mf, mb, 0.0, 1.0, rgb, T);
    return;
  }
  int step = p1 > p0 ? 1 : -1;
  float inv_ds = 1.0 / (s1 - s0);
  float sa = s0, fa = 0.0;
  for (int p = p0;; p += step) {
    bool last = p == p1;
    float sb = last ? s1 : breakpoint(step > 0 ? p : p - 1);
    float fb = last ? 1.0 : (sb - s0) * inv_ds;
    integrate_in_piece(p, sa, sb, (fb - fa) * len, mf, mb, fa, fb, rgb, T);
    if (last) break;
    sa = sb;
    fa = fb;
  }
}

// ---- shading --------------------------------------------------------------------------------

// L(x) at point id (non-finite values: no light); white without a light field.
vec3 light_at(int id) {
  if (u_shading != 2) return vec3(1.0);
  vec3 l = vec3(light_rgb[3 * id], light_rgb[3 * id + 1], light_rgb[3 * id + 2]);
  for (int c = 0; c < 3; ++c)
    if (isnan(l[c]) || isinf(l[c])) l[c] = 0.0;
  return l;
}

vec3 point_at(int id) { return vec3(point_xyz[3 * id], point_xyz[3 * id + 1], point_xyz[3 * id + 2]); }

// The Phong factor of a tet (as the CPU caster): its scalar gradient is the normal, two-sided; a
// vanishing or undefined gradient is lit as if facing the light, without a highlight.
float phong_factor(ivec4 wv) {
  if (u_shading == 0) return 1.0;
  vec3 p0 = point_at(wv.x);
  vec3 e1 = point_at(wv.y) - p0, e2 = point_at(wv.z) - p0, e3 = point_at(wv.w) - p0;
  float s0 = scalars[wv.x];
  vec3 g = cross(e2, e3) * (scalars[wv.y] - s0) + cross(e3, e1) * (scalars[wv.z] - s0) + cross(e1, e2) * (scalars[wv.w] - s0);
  // Scaled by its largest component first: length() squares it, which would leave float32's
  // range for gradients whose size is far from 1 although their direction is well defined.
  float gmax = max(max(abs(g.x), abs(g.y)), abs(g.z));
  if (!(gmax > 0.0) || isinf(gmax) || isnan(gmax)) return u_phong.x + u_phong.y;
  g /= gmax;
  vec3 n = g / length(g), view = -g_d;
  vec3 l = u_headlight != 0 ? view : u_to_light;
  vec3 h = l + view;
  float hl = length(h);
  h = hl > 0.0 ? h / hl : l;
  float spec = u_phong.w > 0.0 ? pow(abs(dot(n, h)), u_phong.w) : 1.0;
  return u_phong.x + u_phong.y * abs(dot(n, l)) + u_phong.z * spec;
}

// ---- boundary entries -----------------------------------------------------------------------

// Where the ray enters through boundary triangle i, if it does.
bool entry_through(int i, out float t, out float s, out bool s_nan, out vec3 l) {
  ivec4 tri = triangles[i];
  vec3 q0 = project(tri.x), q1 = project(tri.y), q2 = project(tri.z);
  t = 0.0;
  s = 0.0;
  s_nan = false;
  l = vec3(1.0);
  // The ray enters through an outward face when it sees the face clockwise.
  float e0 = edge_value(q0, tri.x, q1, tri.y);
  if (edge_sign(e0, q0, tri.x, q1, tri.y) >= 0) return false;
  float e1 = edge_value(q1, tri.y, q2, tri.z);
  if (edge_sign(e1, q1, tri.y, q2, tri.z) >= 0) return false;
  float e2 = edge_value(q2, tri.z, q0, tri.x);
  if (edge_sign(e2, q2, tri.z, q0, tri.x) >= 0) return false;
  vec3 w = vec3(max(0.0, -e1), max(0.0, -e2), max(0.0, -e0));
  float sum = w.x + w.y + w.z;
  if (!(sum > 0.0)) return false;
  t = (w.x * q0.z + w.y * q1.z + w.z * q2.z) / sum;
  bool nan = false;
  vec3 sv = vec3(scalar_at(tri.x, nan), scalar_at(tri.y, nan), scalar_at(tri.z, nan));
  s = dot(w, sv) / sum;
  s_nan = nan;
  if (u_shading == 2) l = (w.x * light_at(tri.x) + w.y * light_at(tri.y) + w.z * light_at(tri.z)) / sum;
  return true;
}

bool box_hit(int node, float t0, float t1) {
  vec3 lo = bvh_nodes[2 * node].xyz, hi = bvh_nodes[2 * node + 1].xyz;
  for (int a = 0; a < 3; ++a) {
    if (g_d[a] == 0.0) {
      if (g_origin[a] < lo[a] || g_origin[a] > hi[a]) return false;
      continue;
    }
    float inv = 1.0 / g_d[a];
    float ta = (lo[a] - g_origin[a]) * inv, tb = (hi[a] - g_origin[a]) * inv;
    t0 = max(t0, min(ta, tb));
    t1 = min(t1, max(ta, tb));
    if (t0 > t1) return false;
  }
  return true;
}

// The first entry (by depth, then triangle index) after (prev_t, prev_id) with depth >= t_floor:
// the CPU caster's sorted entry list, taken one at a time.
bool next_entry(float t_floor, float prev_t, int prev_id, float box_t0, out int best_id, out float best_t,
                out float best_s, out bool best_nan, out vec3 best_l) {
  best_id = -1;
  best_t = kInf;
  best_s = 0.0;
  best_nan = false;
  best_l = vec3(1.0);
  if (u_triangle_count == 0) return false;
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    int node = stack[--top];
    if (!box_hit(node, box_t0, best_t)) continue;
    int first = floatBitsToInt(bvh_nodes[2 * node].w);
    int count = floatBitsToInt(bvh_nodes[2 * node + 1].w);
    if (count > 0) {
      for (int i = first; i < first + count; ++i) {
        float t, s;
        bool nan;
        vec3 l;
        if (!entry_through(i, t, s, nan, l)) continue;
        if (t < t_floor) continue;
        if (!(t > prev_t || (t == prev_t && i > prev_id))) continue;
        if (t < best_t || (t == best_t && i < best_id)) {
          best_id = i;
          best_t = t;
          best_s = s;
          best_nan = nan;
          best_l = l;
        }
      }
    } else if (top + 2 <= 64) {
      stack[top++] = first + 1;
      stack[top++] = first;
    }
  }
  return best_id >= 0;
}

// ---- the walk -------------------------------------------------------------------------------

// Entered through face k, the other local vertices (A, B, C) are ordered so that the candidate
// exit faces, listed outward, are (D,A,B), (D,B,C), (D,C,A) with D = k (as the CPU caster):
// k = 0: (1,3,2), 1: (0,2,3), 2: (1,0,3), 3: (0,1,2), two bits each, six bits per k.
const int kAbcPacked = 45 | (56 << 6) | (49 << 12) | (36 << 18);
// Exit face by the sign pattern of e(D,A), e(D,B), e(D,C): (D,A,B) iff e(D,A) > 0 >= e(D,B),
// and cyclically; patterns 0 and 7 cannot occur with consistent signs and take (D,A,B).
// Entries 1,1,2,2,3,1,3,1, two bits each.
const int kExitPacked = 1 | (1 << 2) | (2 << 4) | (2 << 6) | (3 << 8) | (1 << 10) | (3 << 12) | (1 << 14);

// The projection of point `id`: the previous exit face's (bit-identical) when it is one of its
// vertices, else projected anew (a welded duplicate has another id).
vec3 vertex_q(int id, ivec3 face_id, vec3 f0, vec3 f1, vec3 f2) {
  if (id == face_id.x) return f0;
  if (id == face_id.y) return f1;
  if (id == face_id.z) return f2;
  return project(id);
}

// Walks from the entry face `k` of `tet` to the boundary exit (or until the ray is opaque);
// returns the exit depth. Written without dynamically indexed local arrays, which GPUs (and
// llvmpipe) would move to slow memory.
float walk(int tet, int k, float t_in, float s_in, bool nan_in, vec3 l_in, inout vec3 rgb, inout float T) {
  int p_in = nan_in ? -1 : piece_of(s_in);
  int zero_steps = 0;
  ivec3 face_id = ivec3(-1);
  vec3 f0 = vec3(0.0), f1 = vec3(0.0), f2 = vec3(0.0);
  for (int step = 0; step <= u_tet_count; ++step) {
    ivec4 wv = tet_vertices[tet];
    ivec4 wn = tet_next[tet];
    int abc = (kAbcPacked >> (6 * k)) & 63;
    int la = abc & 3, lb = (abc >> 2) & 3, lc = abc >> 4;
    int iD = wv[k], iA = wv[la], iB = wv[lb], iC = wv[lc];
    vec3 qD = project(iD);
    vec3 qA = vertex_q(iA, face_id, f0, f1, f2);
    vec3 qB = vertex_q(iB, face_id, f0, f1, f2);
    vec3 qC = vertex_q(iC, face_id, f0, f1, f2);
    float eA = edge_value(qD, iD, qA, iA), eB = edge_value(qD, iD, qB, iB), eC = edge_value(qD, iD, qC, iC);
    int pattern = (edge_sign(eA, qD, iD, qA, iA) > 0 ? 1 : 0) | (edge_sign(eB, qD, iD, qB, iB) > 0 ? 2 : 0) |
                  (edge_sign(eC, qD, iD, qC, iC) > 0 ? 4 : 0);
    int x = (kExitPacked >> (2 * pattern)) & 3;
    // Exit face (D, X, Y): x = 1: (A, B), 2: (B, C), 3: (C, A); the vertex left out is C, A, B.
    bool x1 = x == 1, x2 = x == 2;
    vec3 qX = x1 ? qA : (x2 ? qB : qC);
    vec3 qY = x1 ? qB : (x2 ? qC : qA);
    int iX = x1 ? iA : (x2 ? iB : iC);
    int iY = x1 ? iB : (x2 ? iC : iA);
    float eX = x1 ? eA : (x2 ? eB : eC);
    float eY = x1 ? eB : (x2 ? eC : eA);
    int next = wn[x1 ? lc : (x2 ? la : lb)];
    float wd = max(0.0, edge_value(qX, iX, qY, iY));
    float wx = max(0.0, -eY), wy = max(0.0, eX);
    float sum = wd + wx + wy;
    float t_out = t_in, s_out = s_in;
    bool nan_out = nan_in;
    vec3 l_out = l_in;
    if (sum > 0.0) {
      float inv = 1.0 / sum;
      t_out = (wd * qD.z + wx * qX.z + wy * qY.z) * inv;
      bool nan = false;
      float sd = scalar_at(iD, nan), sx = scalar_at(iX, nan), sy = scalar_at(iY, nan);
      s_out = (wd * sd + wx * sx + wy * sy) * inv;
      nan_out = nan;
      if (u_shading == 2) l_out = (wd * light_at(iD) + wx * light_at(iX) + wy * light_at(iY)) * inv;
    }
    int p_out = nan_out ? -1 : piece_near(s_out, p_in);
    if (t_out <= t_in) {
      t_out = t_in;
      if (++zero_steps > kMaxZeroLengthSteps) return t_out;
    } else {
      zero_steps = 0;
      // Only the part in front of the origin counts.
      float t0 = t_in, s0 = s_in, clip = 0.0;
      int p0 = p_in;
      if (t0 < 0.0 && t_out > 0.0) {
        clip = -t_in / (t_out - t_in);
        s0 = s_in + (s_out - s_in) * clip;
        t0 = 0.0;
        p0 = p_in < 0 ? -1 : piece_of(s0);
      }
      if (t_out > t0 && t0 >= 0.0) {
        if (p_out >= 0 && p0 >= 0 && !(p0 == p_out && piece_empty(p0))) {
          float phong = phong_factor(wv);
          integrate(s0, p0, s_out, p_out, t_out - t0, mix(l_in, l_out, clip) * phong, l_out * phong, rgb, T);
        }
        if (T < u_stop_transmittance) return t_out;
      }
    }
    t_in = t_out;
    s_in = s_out;
    p_in = p_out;
    l_in = l_out;
    face_id = ivec3(iD, iX, iY);
    f0 = qD;
    f1 = qX;
    f2 = qY;
    if (next < 0) break;
    tet = next >> 2;
    k = next & 3;
  }
  return t_in;
}

void main() {
  ivec2 local = ivec2(gl_GlobalInvocationID.xy);
  if (local.x >= u_tile_size.x || local.y >= u_tile_size.y) return;
  ivec2 px = u_tile_origin + local;
  float x = (2.0 * (float(px.x) + 0.5) / float(u_image_size.x) - 1.0) * u_half_extent.x;
  float y = (1.0 - 2.0 * (float(px.y) + 0.5) / float(u_image_size.y)) * u_half_extent.y;
  g_origin = u_eye;
  g_d = normalize(u_forward + u_right * x + u_up * y);
  float sgn = (floatBitsToUint(g_d.z) >> 31) != 0u ? -1.0 : 1.0;
  float fa = -1.0 / (sgn + g_d.z);
  float fb = g_d.x * g_d.y * fa;
  g_u = vec3(1.0 + sgn * g_d.x * g_d.x * fa, sgn * fb, -sgn * g_d.x);
  g_v = vec3(fb, sgn + g_d.y * g_d.y * fa, -g_d.y);

  vec3 rgb = vec3(0.0);
  float T = 1.0;
  float done = -kInf;
  float prev_t = -kInf;
  int prev_id = -1;
  float box_t0 = u_eye_outside != 0 ? 0.0 : -kInf;
  int run_count = 0;
  int run_base = (local.y * u_tile_size.x + local.x) * (1 + 2 * kMaxRayRuns);
  for (int n = 0; n < kMaxEntries; ++n) {
    int id;
    float t, s;
    bool nan;
    vec3 l;
    // An entry before the last exit lies on a stretch already walked (a grazing touch); the
    // slack keeps a re-entry at the same depth across unmatched faces (hanging nodes).
    float t_floor = done - u_reentry_slack;
    if (!next_entry(t_floor, prev_t, prev_id, max(box_t0, t_floor), id, t, s, nan, l)) break;
    prev_t = t;
    prev_id = id;
    int tet_face = triangles[id].w;
    vec3 rgb_before = rgb;
    float T_before = T;
    done = walk(tet_face >> 2, tet_face & 3, t, s, nan, l, rgb, T);
    if (u_runs != 0 && done > t) {
      // What this run alone adds: after = before + T_before x run, front to back.
      if (run_count < kMaxRayRuns) {
        bool seen = T_before > 0.0;
        runs[run_base + 1 + 2 * run_count] = vec4(t, done, 0.0, 0.0);
        runs[run_base + 2 + 2 * run_count] = seen ? vec4((rgb - rgb_before) / T_before, 1.0 - T / T_before) : vec4(0.0);
      }
      ++run_count;
    }
    if (T < u_stop_transmittance) break;
  }
  pixels[local.y * u_tile_size.x + local.x] = vec4(rgb, 1.0 - T);
  if (u_runs != 0) runs[run_base] = vec4(float(run_count), 0.0, 0.0, 0.0);
}
