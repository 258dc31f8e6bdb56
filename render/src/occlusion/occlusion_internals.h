// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/occlusion_internals.h -- directional ambient occlusion and shadows by
// Gaussian cone tracing through a filtered pyramid of extinction (Campagnolo, ch. 3; on
// tetrahedral meshes through a resampled grid, sec. 4.2)
//
// Pipeline: resample_extinction / ExtinctionResampler give an ExtinctionGrid; ExtinctionPyramid
// filters it into Gaussian levels (sigma doubling per level); a ConeTracer samples a cone along
// its axis through them (splits 1 -> 3 -> 7, trapezoid rule), for directional_occlusion and
// shadow_transmittance at mesh points, in a PreIlluminationVolume or per sample. The GPU tracer
// is occlusion/gpu_occlusion.h; the public face of it all is render::OcclusionLighting
// (penumbra/render/occlusion.h).
//
// docs/cone_tracing.md derives the method and gives each departure from the thesis with the
// measurements behind it; the sections the comments below name are there: "Section weight",
// "Level selection", "Below level 0", "Lateral variance", "Mass at the bounds", "Shadows, and
// the gap integrated exactly".
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "penumbra/core/vec3.h"
#include "penumbra/render/occlusion.h"
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
  /// same thickness, tau_l = -ln(1 - a_filtered) / D_l, so that a step of D_l lets through the
  /// section's mean transmittance rather than exp(-mean depth). Exact in uniform media, like the
  /// others. Each level is filtered from the grid. Not the default: it assumes the medium fills
  /// the slab along the axis, so an occluder thinner than D_l is diluted and lets light through
  /// (a thin opaque plate reads about 1 - thickness / D_l); docs/cone_tracing.md.
  step_opacity,
};

/// resample_extinction with the node location kept: locating the grid nodes in the tets is done
/// once per mesh, so a new field or transfer function only re-evaluates the nodes.
class ExtinctionResampler {
public:
  /// Nodes over the mesh's bounds and `span` (the union of every rank's, when the ranks' grids are
  /// merged; empty: the mesh's alone). Throws Error(invalid_argument) for resolution < 2 or a
  /// mesh without tets.
  ExtinctionResampler(std::shared_ptr<const TetMesh> mesh, int resolution, const Bounds& span = {});
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

/// The mip pyramid of Gaussian-filtered extinction (thesis sec. 3.2.1 and 3.2.3). Level 0 is the
/// grid filtered with sigma0 (its nodes on the bounds at half weight: "Mass at the bounds"); level
/// l + 1 is level l filtered with sqrt(3) sigma_l and kept at every second node, so sigma doubles.
/// Filters read zeros beyond the grid (never clamp-to-edge), and every level keeps a margin of
/// 3 sigma_l beyond the bounds, so the blur that leaks past them is kept.
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
  /// filter read (docs/cone_tracing.md, "Below level 0"). 0 beyond its outermost nodes, which lie on the
  /// mesh bounds (PyramidLevel::empty_beyond_nodes).
  const PyramidLevel& fine() const { return m_fine; }

private:
  PyramidLevel m_fine;
  std::vector<PyramidLevel> m_levels;
  Bounds m_bounds;
  double m_build_ms = 0;
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
  /// (docs/cone_tracing.md, "Below level 0"); false: level 0, as the thesis. Continuous levels only.
  bool unfiltered_grid = true;
  /// Unresolved lateral variance (docs/cone_tracing.md, "Lateral variance"): each final sub-cone lets through
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
  /// it exactly. A gap of 0 would read the grid at the point, which smears extinction across the
  /// mesh boundary.
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

/// Traces cones through an ExtinctionPyramid. Samples run along the axis from the gap h0 to the
/// length L, kConeStepSigmas apart in the sigma they read; the cone splits 1 -> 3 -> 7 while its
/// sections outgrow 2 sigma0, then reads the level `level` selects; the optical depth is the
/// trapezoid rule over alpha kappa tau, and the result the cosine-weighted mean over the final
/// cones. The schedule depends only on the options and sigma0 and is built once. Immutable;
/// transmittance() is thread-safe.
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
  /// (0 with one cone or with lateral_variance off); docs/cone_tracing.md, "Lateral variance".
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
/// transfer function): what a shadow cone's initial gap h0 holds. The gap keeps a cone from
/// reading the extinction the grid smears around its apex, across the mesh boundary too; for
/// occlusion skipping it is the definition, but the medium right next to x does attenuate a
/// light (docs/cone_tracing.md, "Shadows, and the gap integrated exactly").
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
  /// `covered`, when given, receives the length of the segment inside the tets (less than
  /// `length` where it leaves them: a hole, the boundary, or another rank's cells). Thread-safe.
  double depth(const Vec3d& x, const Vec3d& direction, double length, double* covered = nullptr) const;

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
