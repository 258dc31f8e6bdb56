// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/occlusion.h
//
// Directional ambient occlusion and shadows by Gaussian cone tracing (Campagnolo, ch. 3; on
// unstructured meshes through a resampled grid, sec. 4.2).
//
// Pipeline.
//  1. ExtinctionGrid: the transfer function's extinction tau(s) (per world unit) at the nodes of a
//     regular grid over the mesh bounds; nodes in no tet (outside, holes) have tau = 0.
//  2. ExtinctionPyramid: level 0 is the grid (its nodes on the bounds at half weight, the half cell
//     of medium they stand for; extinction, or opacity per cell converted back
//     afterwards, as in the thesis; opt-in, PyramidQuantity::step_opacity) convolved with a
//     Gaussian of sigma0 (default: the mean grid spacing, sec. 4.2); level l+1 is level l
//     convolved with a Gaussian of sqrt(3) sigma_l, so sigma_{l+1} = 2 sigma_l, and kept at every
//     second node. Built from extinction only; the grid
//     is zero-padded (tau = 0 beyond the mesh bounds, never clamp-to-edge) and every level carries a
//     margin of 3 sigma_l so the blur that leaks past the bounds is kept, not cut.
//  3. ConeTracer: samples along the axis from the gap h0 = 3 sigma0, spaced 2.5 sigma; when the
//     section radius r = d tan(theta) exceeds r_c = 2 sigma0 the cone first splits 1 -> 3 -> 7
//     (circle packing in a circle, thesis fig. 3.5: sub-cones inherit the parent's optical depth;
//     at 3 -> 7 the centre takes the mean of the three and each border pair the closest of the
//     three); beyond that it reads the continuous level lambda = log2(r / (2 sigma0)), i.e.
//     sigma_lambda = r / 2, blending levels floor(lambda) and floor(lambda) + 1 linearly (clamped to
//     the top level); samples are 2.5 sigma_lambda apart. The optical depth is the trapezoid rule
//     over the sample amplitudes
//     tau'_s = alpha * kappa(r, sigma) * tau_s; the result is the cosine-weighted mean of exp(-depth)
//     over the final cones.
//
// Level selection. The thesis climbs a whole level when r exceeds r_c = 2 sigma_l, so the level read
// has sigma anywhere in [r / 2, r): up to twice the section's own width (a uniform disc of radius r
// has per-axis standard deviation r / 2). The wider filter pulls extinction from outside the cone
// into it -- near walls and holes, exactly where occlusion matters -- and the error does not
// average out: on the hole block (bench/occlusion, 20 deg cones) the section-mean optical depth
// came out +0.10 too high with a mean |error| of 0.42 (depth 2.3 on average) for one cone. The
// continuous level gives the filter the section's second moment for every r, in any scene: mean
// |depth error| 0.17, and per point the mean transmittance error against Monte Carlo drops from
// 0.160 / 0.068 / 0.048 to 0.107 / 0.045 / 0.033 (splits 1 / 3 / 7). Cost: about 2.3x the
// thesis's fetches per cone (two per blended sample, and 2.5 sigma_lambda steps are shorter than
// 2.5 sigma of the coarser level). Reading only the nearest level (round(lambda), one fetch, 1.4x)
// measured as well on that scene but undersizes the filter by up to sqrt(2): a thin plate then
// reads brighter with 7 cones than with 3, and one cone in a uniform block brighter than Monte
// Carlo (both tests below catch it). r_c = 2 sigma0 still decides the splits, all on level 0.
// LevelSelection::thesis keeps the thesis's schedule for comparison (bench/occlusion --level thesis):
// whole levels, level 0 below r_c = 2 sigma0 as well, one fetch per sample, steps of 2.5 sigma_l.
//
// Below level 0. A section narrower than level 0's filter (r < 2 sigma0: near every apex, and
// along most of a narrow shadow cone) would read extinction from up to twice its own width
// around it. It reads the resampled grid itself instead (ExtinctionPyramid::fine(): trilinear,
// a tent of per-axis standard deviation h / sqrt 6 for spacing h), blended toward level 0 as r / 2
// grows from that to sigma0, linearly in log2 sigma like the levels above, with steps of 2.5
// times the blended sigma (a few more samples near the apex). Measured on bench/occlusion (mean
// Delta E against Monte Carlo, CPU, with the lateral variance below), before -> after:
// hexblock-hole 2.18 -> 1.76 (3 cones, per point), 2.03 -> 1.62 (3, object space), 1.84 -> 1.41
// (7, object space), AO + 2 deg shadow 2.97 -> 1.56; plate-shadow 0.62 -> 0.59, AO + shadow 0.66
// -> 0.59; disk-out-ref 0.29 -> 0.21, AO + shadow 0.38 -> 0.19. AO with 3 cones in object space
// on the 1M-tet holeblock: 1.71x the unlit frame. ConeOptions::unfiltered_grid = false reads
// level 0 there, as the thesis does.
//
// Section weight kappa. Eq. 3-15 takes kappa = (p_r sigma sqrt(2 pi))^2 / (pi r^2), p_r the share
// of a 1D Gaussian within [-r, r]: the Gaussian integral truncated to the square around the cone
// section, divided by the disc area. In a uniform medium that gives kappa between 0.46 and 1.27
// depending on r / sigma, not 1 -- the thesis compensates with the user's alpha. SectionWeight::mean
// (the default) instead reads the Gaussian-filtered tau_s as the mean extinction over the section
// (kappa = 1), so a homogeneous medium gives exactly exp(-tau (L - h0)) for every aperture and
// split count; SectionWeight::thesis is eq. 3-15 literally.
//
// Lateral variance. exp(-mean depth) is darker than the mean of exp(-depth) over the rays of a
// cone (Jensen) wherever the rays see different depths; cosine-weighted Monte Carlo averages the
// latter. With 3 or 7 final cones, the spread of their depths is a measure of that variation
// that only lateral structure produces: a plate across the cone or a uniform medium gives every
// sub-cone the same depth. For a depth that varies linearly across the cone, the variance within
// a sub-cone of radius r_s (a uniform disc: r_s^2 / 4 per unit gradient squared) relates to the
// variance of the sub-cone centres at offset rho (3 on a circle: rho^2 / 2; 7: 6/7 of that) by a
// fixed ratio from the packing: r_s^2 / (2 rho^2) = 0.375 for 3 cones and 7/48 = 0.146 for 7.
// Each sub-cone then lets through the mean transmittance of a gamma-distributed depth with its
// own mean mu and that variance V, (1 + V / mu)^(-mu^2 / V) = exp(-mu ln(1 + x) / x), x = V / mu:
// between exp(-mu) (V = 0) and 1, monotone, never above 1. Measured on bench/occlusion (20 deg
// cones, image mean Delta E against Monte Carlo), hexblock-hole: 2.68 -> 2.18 (3 cones, per
// point), 2.53 -> 2.03 (3, object space), 2.32 -> 2.00 (7), 2.16 -> 1.84 (7, object space);
// plate-shadow: 0.79 -> 0.62 (3), 0.70 -> 0.58 (7). The ratios are not fitted: a larger one
// (2.5x) lowers hexblock-hole further but overshoots on plate-shadow with 7 cones. Depths enter
// the spread clamped at 10 (exp(-10) lets nothing visible through): otherwise how far an opaque
// sub-cone's depth runs past that would brighten its neighbours, and an opaque ball on the axis
// would read darker at 60 deg than at 45.
//
// The axis integral runs over [h0, L] (the same interval as the Monte Carlo reference, eq. 3-7);
// the thesis's extra half Gaussian before the first sample (eq. 3-16, first term) is left out for
// that reason.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "penumbra/core/vec3.h"
#include "penumbra/render/tet_mesh.h"
#include "penumbra/render/transfer_function.h"

namespace penumbra::render {

/// A regular grid of extinction: node (i, j, k) at lo + (i, j, k) * spacing, value index
/// i + dims[0] * (j + dims[1] * k).
struct ExtinctionGrid {
  std::array<int, 3> dims{0, 0, 0};
  Vec3d lo, spacing;
  std::vector<float> tau;

  std::size_t size() const { return tau.size(); }
  std::size_t index(int i, int j, int k) const {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(dims[0]) * (static_cast<std::size_t>(j) + static_cast<std::size_t>(dims[1]) * static_cast<std::size_t>(k));
  }
  Vec3d position(int i, int j, int k) const { return {lo.x + i * spacing.x, lo.y + j * spacing.y, lo.z + k * spacing.z}; }
  /// Mean of the three spacings: the default sigma0 (sec. 4.2).
  double mean_spacing() const { return (spacing.x + spacing.y + spacing.z) / 3.0; }
  /// Throws Error(invalid_argument) for fewer than 2 nodes per axis, bad spacing or a wrong size.
  void validate(const char* call) const;
};

/// Resamples `tf`'s extinction at the nodes of a grid over the mesh bounds with `resolution` nodes
/// along the longest axis (others in proportion). A node takes the scalar of the tet containing it
/// (interpolated linearly); nodes in no tet and NaN scalars give 0. Throws Error(invalid_argument)
/// for resolution < 2, a scalar count different from the point count or an invalid tf.
ExtinctionGrid resample_extinction(const TetMesh& mesh, const std::vector<float>& point_scalars,
                                   const TransferFunction& tf, int resolution);

/// Spacing of the cone's axis samples in units of the sigma of the level they read (thesis
/// appendix A); also the slab thickness of PyramidQuantity::step_opacity.
inline constexpr double kConeStepSigmas = 2.5;

/// What the Gaussian filters average.
enum class PyramidQuantity {
  /// The default. Opacity a = 1 - exp(-tau l) per grid cell (l = the mean spacing), converted back to
  /// tau = -ln(1 - a) / l after filtering (thesis sec. 3.2.1): an opaque occluder stays bounded
  /// instead of bleeding huge extinction into its neighbourhood.
  opacity,
  /// Extinction itself: every level is exactly tau convolved with the level's Gaussian.
  extinction,
  /// Level l filters the opacity a = 1 - exp(-tau D_l) of a slab as thick as the
  /// cone step that reads the level, D_l = kConeStepSigmas sigma_l, and converts back with the
  /// same thickness, tau_l = -ln(1 - a_filtered) / D_l. A step of D_l through tau_l then lets
  /// through the section's mean transmittance exp(-tau D_l) -- what cosine-weighted rays average --
  /// instead of exp(-mean tau D_l), which is darker wherever the section is heterogeneous
  /// (Jensen). Exact in uniform media, like the others. Each level is filtered from the grid.
  /// Not the default: it assumes the medium fills the slab along the axis, so an occluder thinner
  /// than D_l (a plate across the cone, the far side of a block) is diluted along the axis too
  /// and lets light through -- a thin opaque plate reads about 1 - thickness / D_l. Measured on the
  /// hole block (20 deg cones, per mesh point against Monte Carlo): mean |T error| 0.039 / 0.023 /
  /// 0.019 for splits 1 / 3 / 7 against 0.107 / 0.045 / 0.033 with opacity -- the floor set by
  /// exp(-mean depth) within each final cone is 0.077 / 0.028 / 0.015 -- but a thin opaque plate
  /// seen through it transmits 0.31 where opacity gives < 0.1.
  step_opacity,
};

/// resample_extinction with the node location kept: locating the grid nodes in the tets is done
/// once per mesh, so a new field or transfer function only re-evaluates the nodes.
class ExtinctionResampler {
public:
  /// Throws Error(invalid_argument) for resolution < 2 or a mesh without tets.
  ExtinctionResampler(std::shared_ptr<const TetMesh> mesh, int resolution);
  ~ExtinctionResampler();
  ExtinctionResampler(ExtinctionResampler&&) noexcept;
  ExtinctionResampler& operator=(ExtinctionResampler&&) noexcept;
  /// Not thread-safe (reuses one scratch grid).
  ExtinctionGrid resample(const std::vector<float>& point_scalars, const TransferFunction& tf);
  std::array<int, 3> dims() const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

struct PyramidOptions {
  PyramidQuantity quantity = PyramidQuantity::opacity;
  /// Standard deviation of level 0 in world units; 0 = the grid's mean spacing (sec. 4.2).
  double sigma0 = 0.0;
  /// Most levels to build (>= 1); levels also stop once a level has at most 2 nodes per axis
  /// inside the bounds.
  int max_levels = 16;
};

/// One pyramid level: tau filtered with a Gaussian of `sigma`, on nodes lo + n * spacing.
struct PyramidLevel {
  std::array<int, 3> dims{0, 0, 0};
  Vec3d lo, spacing;
  double sigma = 0;
  std::vector<float> tau;
  /// 0 outside the box of the nodes themselves, instead of interpolating toward zero padding one
  /// spacing beyond them (see ExtinctionPyramid::fine()).
  bool empty_beyond_nodes = false;
  /// Trilinear interpolation; 0 beyond the level's nodes.
  double sample(const Vec3d& p) const;
};

/// The mip pyramid of Gaussian-filtered extinction (thesis sec. 3.2.1 and 3.2.3).
class ExtinctionPyramid {
public:
  ExtinctionPyramid() = default;
  /// Throws Error(invalid_argument) for an invalid grid, sigma0 < 0 or non-finite, max_levels < 1.
  explicit ExtinctionPyramid(const ExtinctionGrid& grid, const PyramidOptions& options = {});

  int levels() const { return static_cast<int>(m_levels.size()); }
  const PyramidLevel& level(int l) const { return m_levels[static_cast<std::size_t>(l)]; }
  double sigma0() const { return m_levels.empty() ? 0.0 : m_levels[0].sigma; }
  /// Bounds of the source grid (the mesh bounds).
  const Bounds& bounds() const { return m_bounds; }
  /// Wall-clock time of the construction (filtering only), in milliseconds.
  double build_ms() const { return m_build_ms; }
  /// The resampled grid itself, unfiltered (extinction; `sigma` is the per-axis standard deviation
  /// of trilinear interpolation, mean spacing / sqrt 6): what sections narrower than level 0's
  /// filter read (occlusion.h, "Below level 0"). 0 beyond its outermost nodes, which lie on the
  /// mesh bounds (PyramidLevel::empty_beyond_nodes).
  const PyramidLevel& fine() const { return m_fine; }

private:
  PyramidLevel m_fine;
  std::vector<PyramidLevel> m_levels;
  Bounds m_bounds;
  double m_build_ms = 0;
};

/// Which pyramid level a cone section of radius r reads (see "Level selection").
enum class LevelSelection {
  continuous,  ///< sigma = r / 2, the two levels around it blended: the default
  /// One whole level: the finest with r <= r_c = 2 sigma_l (sec. 3.2.3), stepping at r_c; level 0
  /// for sections narrower than 2 sigma0 too (unfiltered_grid does not apply): the thesis's schedule.
  thesis,
};

enum class SectionWeight {
  mean,    ///< kappa = 1: tau_s is the section's mean extinction (exact in uniform media)
  thesis,  ///< kappa = (p_r sigma sqrt(2 pi))^2 / (pi r^2), eq. 3-15
};

struct ConeOptions {
  /// Half-angle theta of the cone, in degrees, in (0, 89].
  double aperture_deg = 15.0;
  /// Most cones per section: 1, 3 or 7.
  int splits = 1;
  /// Cone length L in world units; 0 = fraction_of_diagonal * the bounds' diagonal.
  double length = 0.0;
  /// Default length as a fraction of the diagonal: thesis 0.5 for occlusion, 0.75 for shadows.
  double fraction_of_diagonal = 0.5;
  /// Initial gap h0 in world units; negative = 3 sigma0.
  double gap = -1.0;
  /// Global attenuation alpha (eq. 3-17), > 0.
  double attenuation = 1.0;
  SectionWeight weight = SectionWeight::mean;
  LevelSelection level = LevelSelection::continuous;
  /// Sections narrower than level 0's filter read the unfiltered grid, blended toward level 0
  /// (see "Below level 0" above); false: level 0, as the thesis. Continuous levels only.
  bool unfiltered_grid = true;
  /// Unresolved lateral variance (see "Lateral variance" above): each final sub-cone lets through
  /// the mean transmittance of a gamma-distributed depth whose variance is estimated from the
  /// spread between the sub-cones, instead of exp(-mean depth). No effect with one cone, in
  /// uniform media or where every sub-cone sees the same depth. false: the thesis's exp(-depth).
  bool lateral_variance = true;

  static ConeOptions occlusion(double aperture_deg = 15.0, int splits = 3) {
    ConeOptions o;
    o.aperture_deg = aperture_deg;
    o.splits = splits;
    return o;
  }
  /// Shadow cones keep the gap of 3 sigma0; pass a GapDepth to shadow_transmittance to integrate
  /// it exactly. Starting the cone at the point instead (gap 0) reads the grid there, which smears
  /// extinction across the mesh boundary: against the exact shadow on bench/occlusion it measured
  /// better than skipping the gap on plate-shadow (mean Delta E 1.38 -> 0.47) but not on
  /// hexblock-hole (3.20 -> 3.30 per point), where the gap integrated exactly gives 0.89.
  static ConeOptions shadow(double aperture_deg = 1.0, int splits = 1) {
    ConeOptions o;
    o.aperture_deg = aperture_deg;
    o.splits = splits;
    o.fraction_of_diagonal = 0.75;
    return o;
  }
};

/// ConeSample::level of samples that read ExtinctionPyramid::fine().
inline constexpr int kFineLevel = -1;

/// One axis sample of the precomputed cone schedule (the thesis's 1D texture, appendix A).
struct ConeSample {
  double distance;   ///< along the cone axis from the apex
  double weight;     ///< trapezoid weight of (previous + this amplitude); first sample: 0
  double kappa;      ///< section weight times alpha
  int level;         ///< pyramid level fetched; kFineLevel: ExtinctionPyramid::fine(), blended toward level 0
  int cones;         ///< 1, 3 or 7 cones in this section
  double blend = 0;  ///< weight of level + 1, mixed linearly with `level` (continuous level)
};

/// Traces cones through an ExtinctionPyramid. Immutable; transmittance() is thread-safe.
class ConeTracer {
public:
  /// Throws Error(invalid_argument) for bad options or an empty pyramid. The pyramid must
  /// outlive the tracer.
  ConeTracer(const ExtinctionPyramid& pyramid, const ConeOptions& options);

  /// Transparency T_Psi in [0, 1] of the cone with apex `apex` along `axis` (any length > 0).
  double transmittance(const Vec3d& apex, const Vec3d& axis) const;
  /// As transmittance(), but stops at `max_length` (< the cone length) when the target is closer.
  double transmittance(const Vec3d& apex, const Vec3d& axis, double max_length) const;

  const ConeOptions& options() const { return m_options; }
  double length() const { return m_length; }
  double gap() const { return m_gap; }
  const std::vector<ConeSample>& schedule() const { return m_schedule; }
  /// Variance of the depth within one of `cones` final sub-cones per unit variance between them
  /// (0 with one cone or with lateral_variance off); see "Lateral variance".
  double lateral_variance_ratio(int cones) const;

private:
  const ExtinctionPyramid* m_pyramid;
  ConeOptions m_options;
  double m_length = 0, m_gap = 0;
  std::vector<ConeSample> m_schedule;
  // Sub-cone directions in the cone frame (x, y across, z along) for 3 and 7 cones.
  std::array<Vec3d, 3> m_dir3;
  std::array<Vec3d, 7> m_dir7;
};

/// A light for cone-traced shadows.
struct ShadowLight {
  enum class Kind { directional, point, spot };
  Kind kind = Kind::directional;
  /// directional: direction the light travels; point / spot: position.
  Vec3d vector{0, 0, -1};
  /// spot: direction the spot points (any length > 0).
  Vec3d spot_direction{0, 0, -1};
  /// spot: half-angle of the lit cone, degrees; points outside get no light.
  double spot_angle_deg = 30.0;
};

/// Directional ambient occlusion at x: the transparency of a cone from x towards the eye (thesis
/// sec. 3.3.1); 1 = unoccluded. For an orthographic view pass a far-away eye along the view axis.
double directional_occlusion(const ConeTracer& tracer, const Vec3d& x, const Vec3d& eye);
/// Light reaching x from `light` (thesis sec. 3.3.2): the transparency of a narrow cone towards it;
/// for point and spot lights the cone stops at the light; 0 outside a spot's cone. The cone starts
/// at its gap h0: what lies between x and h0 is left out.
double shadow_transmittance(const ConeTracer& tracer, const ShadowLight& light, const Vec3d& x);

/// Exact optical depth along short segments through the tets (double precision; a BVH over the
/// tets, each segment clipped against every tet it meets, tau integrated piece by piece of the
/// transfer function): what a shadow cone's initial gap h0 holds.
///
/// Why. The gap keeps a cone from reading the extinction around its own apex, which the grid
/// smears over a cell on either side -- across the mesh boundary too, so a point on a lit surface
/// would read the medium behind it. For occlusion that is the thesis's definition (the Monte
/// Carlo reference skips the same gap). For a shadow it is an error: the medium right next to x
/// does attenuate the light. Measured on bench/occlusion (2 deg cones, mean |transmittance error|
/// per mesh point against the exact single ray to a directional light): hexblock-hole 0.021 with
/// the gap skipped, 0.017 with no gap (the grid's smear across the surface: 0.037 at boundary
/// points), 0.009 with the gap integrated here; plate-shadow 0.014 / 0.008 / 0.007; disk-out-ref
/// 0.034 / 0.0014 / 0.0011.
class GapDepth {
public:
  /// Throws Error(invalid_argument) for a null mesh or one without tets.
  explicit GapDepth(std::shared_ptr<const TetMesh> mesh);
  ~GapDepth();
  GapDepth(GapDepth&&) noexcept;
  GapDepth& operator=(GapDepth&&) noexcept;
  /// Binds a field: one scalar per point (NaN: no extinction), extinction from `tf`. Throws
  /// Error(invalid_argument) for a wrong size or an invalid tf.
  void set_field(const std::vector<float>& point_scalars, const TransferFunction& tf);
  /// Integral of tau over x + t u, t in [0, length], u = direction / |direction|; parts outside
  /// the mesh or in holes add nothing. 0 before set_field, for length <= 0 or a zero direction.
  /// Thread-safe.
  double depth(const Vec3d& x, const Vec3d& direction, double length) const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

/// The light let through by the medium between x and the start of `tracer`'s cone towards
/// `light` (its gap h0, or the light when closer): exp(-gap.depth(...)).
double gap_transmittance(const ConeTracer& tracer, const ShadowLight& light, const Vec3d& x, const GapDepth& gap);
/// As above, with the gap [0, h0] integrated exactly by `gap` instead of left out: the light
/// that reaches x, for comparison with a hard shadow. shadow_transmittance(tracer, light, x) times
/// gap_transmittance(tracer, light, x, gap).
double shadow_transmittance(const ConeTracer& tracer, const ShadowLight& light, const Vec3d& x, const GapDepth& gap);

/// Object space (thesis sec. 3.3.3): values precomputed on a regular grid over the bounds and
/// interpolated trilinearly (clamped to the grid) wherever rendering samples them.
class PreIlluminationVolume {
public:
  PreIlluminationVolume() = default;
  /// `resolution` nodes along the longest axis of `bounds` (others in proportion), >= 2; each node
  /// gets value(position), evaluated in parallel. Throws Error(invalid_argument) on bad input.
  PreIlluminationVolume(const Bounds& bounds, int resolution, const std::function<double(const Vec3d&)>& value);

  double sample(const Vec3d& p) const;
  const std::array<int, 3>& dims() const { return m_dims; }
  const std::vector<float>& values() const { return m_values; }
  double build_ms() const { return m_build_ms; }

private:
  std::array<int, 3> m_dims{0, 0, 0};
  Vec3d m_lo, m_h;
  std::vector<float> m_values;
  double m_build_ms = 0;
};

/// value(point) at every mesh point, in parallel (points no tet uses get 1): a per-point field
/// the renderer interpolates like the light volume's.
std::vector<float> evaluate_at_points(const TetMesh& mesh, const std::function<double(const Vec3d&)>& value);
/// Grey RGB light field (3 floats per point) for Shading::light_rgb: factor per point, scaled.
std::vector<float> grey_light_rgb(const std::vector<float>& factor, double scale = 1.0);

/// Monte Carlo ground truth for one cone: K cosine-weighted rays within the aperture, each
/// integrated exactly through the tets in double precision from h0 to L (eq. 3-6, 3-7 without
/// step error), K doubled from min_rays until the standard error is below `tolerance` or
/// max_rays is reached.
struct MonteCarloResult {
  double transmittance = 0;
  double standard_error = 0;
  int rays = 0;
  bool converged = false;
};
class ConeMonteCarlo {
public:
  ConeMonteCarlo(std::shared_ptr<const TetMesh> mesh, const std::vector<float>& point_scalars,
                 const TransferFunction& tf);
  ~ConeMonteCarlo();
  /// `length` and `gap` in world units (use ConeTracer::length() / gap() to compare like with
  /// like); `seed` makes the result reproducible.
  MonteCarloResult transmittance(const Vec3d& apex, const Vec3d& axis, double aperture_deg, double gap,
                                 double length, double tolerance = 2e-3, int min_rays = 64,
                                 int max_rays = 1 << 16, std::uint64_t seed = 1) const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace penumbra::render
