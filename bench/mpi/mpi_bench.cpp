// SPDX-License-Identifier: BSD-3-Clause
// bench/mpi/mpi_bench.cpp -- sort-last compositing of ray runs over MPI ranks, on a benchmark scene
// cut into slabs, METIS parts or cells dealt round-robin, against the scene rendered in one process
//
// Usage (under mpirun): pnb_bench_mpi --scene NAME --data-dir DIR [--frames N] [--sizes "512"]
//        [--partitions "slabs metis round-robin"] [--lit "none phong light-volume"] [--runs-memory-mb N]
//        [--write-parts DIR]
// Prints one JSON line per partition, lighting and image size, from rank 0:
//   render_ms        median over ranks of each rank's median local ray casting with runs (CPU),
//                    and render_ms_max, the slowest rank's
//   composite_ms     median compositing (the runs' exchange by image band, the merge in depth
//                    order, the gather to rank 0), slowest rank
//   bytes_per_rank   bytes each rank sends and receives in the exchange (runs 24 B, 8 B per pixel
//                    that has runs; median over ranks) and bytes_per_rank_max
//   messages_per_rank   point-to-point messages each rank sends and receives in the exchange
//                    besides the MPI_Alltoall of the counts: two (places, runs) per other rank
//                    whose band its runs reach or whose runs reach its band (median over ranks;
//                    messages_per_rank_max), against 4 (P − 1) for an MPI_Alltoallv that sends
//                    every pair a message, empty or not
//   runs_per_pixel   runs over every rank per image pixel; runs_mb_max the largest rank's runs,
//                    runs_peak_mb_max what they hold at their peak (28 B per pixel, 48 B per run:
//                    the per-pixel lists and the flat copy), which --runs-memory-mb bounds (default
//                    2048, the library's default): a frame over it prints a line with "refused"
//   rms_vs_serial_pct, max_level_diff   rank 0's composited image against the whole scene
//                    rendered by one CPU ray caster in this process
//   with lit "light-volume" also: light_ms (median over ranks) and light_ms_max, one rank's light
//                    solve (level 0 merged over the ranks, its walks, its shared points settled),
//                    light_ms_serial the whole scene's in one process, level0_merge_ms and
//                    settle_ms (slowest rank), shared_points_max
// With 2 cores, timings beyond 2 ranks measure oversubscription; bytes and runs do not.
//
// With --write-parts DIR it benchmarks nothing: for each partition, every rank writes its part as
// DIR/PARTITION-N/piece-R.vtu (VTK XML, raw appended binary: float64 points, int64 tets, the
// float32 point scalar "s") and rank 0 writes DIR/PARTITION-N.pvtu over the N pieces, DIR/scene.json
// (the transfer function, camera and background) and DIR/serial-W.png, the one-process picture
// (unlit) at each size; bench/mpi/pvbatch_peer.py renders those parts with ParaView.
#include <mpi.h>

#include <nlohmann/json.hpp>

#ifdef PNB_HAVE_METIS
#include <metis.h>
#endif

#include <algorithm>
#include <cmath>
#include <bit>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "bench_util.h"
#include "penumbra/core/error.h"
#include "penumbra/render/cpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "mpi_rank_group.h"
#include "penumbra/render/light_volume.h"
#include "rank_lighting.h"
#include "run_compositing.h"
#include "shared_points.h"
#include "scene.h"
#include "scene_views.h"

namespace pb = penumbra::bench;
namespace pr = penumbra::render;

namespace {

// The rank of each tet of `scene`; METIS's parts are computed on rank 0 and broadcast.
std::vector<int> owners(const pb::Scene& scene, const std::string& kind, int rank, int ranks) {
  const std::size_t nt = scene.tet_count();
  std::vector<int> owner(nt, 0);
  if (ranks == 1) return owner;
  if (kind == "round-robin") {
    for (std::size_t t = 0; t < nt; ++t) owner[t] = static_cast<int>(t % static_cast<std::size_t>(ranks));
    return owner;
  }
  if (kind == "metis") {
#ifdef PNB_HAVE_METIS
    if (rank == 0) {
      std::vector<idx_t> eptr(nt + 1), eind(scene.tets.begin(), scene.tets.end());
      for (std::size_t t = 0; t <= nt; ++t) eptr[t] = static_cast<idx_t>(4 * t);
      idx_t ne = static_cast<idx_t>(nt), nn = static_cast<idx_t>(scene.point_count()), common = 3, parts = ranks, cut = 0;
      std::vector<idx_t> epart(nt), npart(scene.point_count());
      idx_t options[METIS_NOPTIONS];
      METIS_SetDefaultOptions(options);
      penumbra::require(METIS_PartMeshDual(&ne, &nn, eptr.data(), eind.data(), nullptr, nullptr, &common, &parts, nullptr,
                                           options, &cut, epart.data(), npart.data()) == METIS_OK,
                        "pnb_bench_mpi: METIS_PartMeshDual failed");
      for (std::size_t t = 0; t < nt; ++t) owner[t] = static_cast<int>(epart[t]);
    }
    MPI_Bcast(owner.data(), static_cast<int>(nt), MPI_INT, 0, MPI_COMM_WORLD);
    return owner;
#else
    throw penumbra::Error(penumbra::ErrorCode::invalid_argument, "pnb_bench_mpi: built without METIS (libmetis-dev)");
#endif
  }
  penumbra::require(kind == "slabs", "pnb_bench_mpi: partition '" + kind + "'; expected slabs, metis or round-robin");
  double lo = 1e300, hi = -1e300;
  for (std::size_t p = 0; p < scene.point_count(); ++p) lo = std::min(lo, scene.points[3 * p]), hi = std::max(hi, scene.points[3 * p]);
  for (std::size_t t = 0; t < nt; ++t) {
    double x = 0;
    for (int k = 0; k < 4; ++k) x += scene.points[3 * static_cast<std::size_t>(scene.tets[4 * t + static_cast<std::size_t>(k)])];
    owner[t] = std::min(ranks - 1, static_cast<int>((x / 4 - lo) / (hi - lo) * ranks));
  }
  return owner;
}

// This rank's tets over the points they use, and the scalars there.
struct Part {
  std::vector<double> xyz;
  std::vector<std::int64_t> tets;
  std::vector<float> scalars;
};

Part part_of(const pb::Scene& scene, const std::vector<int>& owner, int rank) {
  Part part;
  std::map<std::int64_t, std::int64_t> local;
  for (std::size_t t = 0; t < scene.tet_count(); ++t) {
    if (owner[t] != rank) continue;
    for (int k = 0; k < 4; ++k) {
      const std::int64_t g = scene.tets[4 * t + static_cast<std::size_t>(k)];
      auto [it, added] = local.try_emplace(g, static_cast<std::int64_t>(part.scalars.size()));
      if (added) {
        part.xyz.insert(part.xyz.end(), {scene.points[3 * g], scene.points[3 * g + 1], scene.points[3 * g + 2]});
        part.scalars.push_back(scene.scalars[static_cast<std::size_t>(g)]);
      }
      part.tets.push_back(it->second);
    }
  }
  return part;
}

std::shared_ptr<const pr::TetMesh> prepare(const std::vector<double>& xyz, const std::vector<std::int64_t>& tets) {
  static const std::uint8_t kTetra = 10;
  penumbra::MeshView v;
  v.points = {reinterpret_cast<const std::byte*>(xyz.data()), xyz.size() / 3, 3 * sizeof(double)};
  v.point_type = penumbra::ScalarType::float64;
  v.connectivity = {tets.data(), tets.size(), penumbra::ScalarType::int64};
  v.cell_types = &kTetra;
  v.cell_type_count = 1;
  v.topology_version = 1;
  return std::make_shared<const pr::TetMesh>(pr::prepare_tet_mesh(v, "pnb_bench_mpi"));
}

// What this rank sends to and receives from the others in one composite of `runs`: for each other
// rank's band, its runs (24 B) and, per pixel that has runs, its place and count (8 B); and the
// messages that carry them, two per rank and direction with anything to carry.
struct Exchanged {
  double bytes = 0, messages = 0;
};
Exchanged exchanged(const pr::RayRuns& runs, int width, int height, int rank, int ranks) {
  auto band = [&](int b) { return static_cast<std::size_t>(static_cast<long long>(height) * b / ranks) * static_cast<std::size_t>(width); };
  std::vector<double> sent(static_cast<std::size_t>(ranks), 0.0), received(static_cast<std::size_t>(ranks), 0.0);
  for (int b = 0; b < ranks; ++b) {
    if (b == rank) continue;
    double covered = 0;
    for (std::size_t p = band(b); p < band(b + 1); ++p) covered += runs.offsets[p + 1] > runs.offsets[p] ? 1 : 0;
    sent[static_cast<std::size_t>(b)] = 24.0 * (runs.offsets[band(b + 1)] - runs.offsets[band(b)]) + 8.0 * covered;
  }
  MPI_Alltoall(sent.data(), 1, MPI_DOUBLE, received.data(), 1, MPI_DOUBLE, MPI_COMM_WORLD);
  Exchanged total;
  for (std::size_t r = 0; r < static_cast<std::size_t>(ranks); ++r) {
    total.bytes += sent[r] + received[r];
    total.messages += (sent[r] > 0 ? 2 : 0) + (received[r] > 0 ? 2 : 0);
  }
  return total;
}

struct Stats {
  double median = 0, max = 0;
};
Stats over_ranks(double mine) {
  int ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  std::vector<double> all(static_cast<std::size_t>(ranks));
  MPI_Allgather(&mine, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, MPI_COMM_WORLD);
  return {pb::median(all), *std::max_element(all.begin(), all.end())};
}

// A part as a VTK XML unstructured grid whose arrays follow the header as raw appended blocks,
// each a UInt64 byte count then the bytes: 1M tets read back in a fraction of a second.
void write_vtu(const std::string& path, const Part& part) {
  static_assert(std::endian::native == std::endian::little, "the pieces say LittleEndian");
  const std::size_t np = part.scalars.size(), nc = part.tets.size() / 4;
  std::vector<std::int64_t> offsets(nc);
  for (std::size_t c = 0; c < nc; ++c) offsets[c] = static_cast<std::int64_t>(4 * (c + 1));
  const std::vector<std::uint8_t> types(nc, 10);  // VTK_TETRA
  struct Block {
    const void* data;
    std::uint64_t bytes;
  };
  const Block blocks[] = {{part.scalars.data(), np * sizeof(float)},
                          {part.xyz.data(), 3 * np * sizeof(double)},
                          {part.tets.data(), 4 * nc * sizeof(std::int64_t)},
                          {offsets.data(), nc * sizeof(std::int64_t)},
                          {types.data(), nc}};
  std::uint64_t at[5], next = 0;
  for (int b = 0; b < 5; ++b) at[b] = next, next += sizeof(std::uint64_t) + blocks[b].bytes;
  std::ofstream out(path, std::ios::binary);
  out << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
      << "<UnstructuredGrid>\n<Piece NumberOfPoints=\"" << np << "\" NumberOfCells=\"" << nc << "\">\n"
      << "<PointData Scalars=\"s\"><DataArray type=\"Float32\" Name=\"s\" format=\"appended\" offset=\"" << at[0]
      << "\"/></PointData>\n"
      << "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"" << at[1]
      << "\"/></Points>\n<Cells>\n"
      << "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"" << at[2] << "\"/>\n"
      << "<DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"" << at[3] << "\"/>\n"
      << "<DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"" << at[4] << "\"/>\n"
      << "</Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_";
  for (const Block& b : blocks) {
    out.write(reinterpret_cast<const char*>(&b.bytes), sizeof(b.bytes));
    out.write(static_cast<const char*>(b.data), static_cast<std::streamsize>(b.bytes));
  }
  out << "\n</AppendedData>\n</VTKFile>\n";
  penumbra::require(static_cast<bool>(out), "pnb_bench_mpi: cannot write '" + path + "'");
}

// The pieces of one partition as one data set: piece R is read by rank R of as many ranks.
void write_pvtu(const std::string& path, const std::string& piece_dir, int ranks) {
  std::ofstream out(path);
  out << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
      << "<PUnstructuredGrid GhostLevel=\"0\">\n"
      << "<PPointData Scalars=\"s\"><PDataArray type=\"Float32\" Name=\"s\"/></PPointData>\n"
      << "<PPoints><PDataArray type=\"Float64\" NumberOfComponents=\"3\"/></PPoints>\n";
  for (int r = 0; r < ranks; ++r) out << "<Piece Source=\"" << piece_dir << "/piece-" << r << ".vtu\"/>\n";
  out << "</PUnstructuredGrid>\n</VTKFile>\n";
  penumbra::require(static_cast<bool>(out), "pnb_bench_mpi: cannot write '" + path + "'");
}

// What a peer needs to render the scene as this program does, and the picture to compare with.
void write_scene(const std::string& dir, const pb::Scene& scene, const pr::TransferFunction& tf,
                 const std::vector<std::string>& sizes) {
  nlohmann::ordered_json j;
  j["scene"] = scene.name;
  j["tets"] = scene.tet_count();
  j["tf"] = nlohmann::json::array();
  for (const pb::TfNode& n : scene.tf) j["tf"].push_back({n.x, n.r, n.g, n.b, n.extinction});
  const pb::SceneCamera& c = scene.camera;
  j["camera"] = {{"eye", {c.eye.x, c.eye.y, c.eye.z}}, {"target", {c.target.x, c.target.y, c.target.z}},
                 {"up", {c.up.x, c.up.y, c.up.z}}, {"fov_y_deg", c.fov_y_deg}};
  j["background"] = {scene.background[0], scene.background[1], scene.background[2]};
  std::ofstream(dir + "/scene.json") << j.dump() << "\n";
  pr::CpuRayCaster whole(prepare(scene.points, scene.tets));
  for (const std::string& size : sizes) {
    const int side = std::stoi(size);
    const pr::Image image = whole.render(scene.scalars, tf, pb::camera(scene, side, side), pr::RenderOptions{});
    pr::write_png(dir + "/serial-" + size + ".png", pr::to_rgb8(image, scene.background), side, side);
  }
}

void write_parts(const std::string& dir, const pb::Scene& scene, const pr::TransferFunction& tf,
                 std::istringstream& partitions, const std::vector<std::string>& sizes, int rank, int ranks) {
  for (std::string partition; partitions >> partition;) {
    const std::string piece_dir = partition + "-" + std::to_string(ranks);
    if (rank == 0) std::filesystem::create_directories(dir + "/" + piece_dir);
    const std::vector<int> owner = owners(scene, partition, rank, ranks);
    MPI_Barrier(MPI_COMM_WORLD);
    write_vtu(dir + "/" + piece_dir + "/piece-" + std::to_string(rank) + ".vtu", part_of(scene, owner, rank));
    if (rank == 0) write_pvtu(dir + "/" + piece_dir + ".pvtu", piece_dir, ranks);
  }
  if (rank == 0) write_scene(dir, scene, tf, sizes);
  MPI_Barrier(MPI_COMM_WORLD);
}

// The light volume's settings for lit "light-volume": one directional light, level 0 at 128
// nodes, and sigma_a that halves the light at the median point (as the light benchmark picks it),
// from exact optical depths at a fixed sample of points, found on rank 0.
struct LightSetup {
  pr::Light light{pr::Light::Kind::directional, {0.8, -0.45, -0.4}, {1, 1, 1}};
  pr::LightVolumeOptions options;
};

LightSetup light_setup(const pb::Scene& scene, const std::shared_ptr<const pr::TetMesh>& whole, const pr::TransferFunction& tf) {
  LightSetup s;
  s.options.level0_resolution = 128;
  double sigma_a = 1.0;
  if (whole) {
    const pr::LightTransmittanceReference reference(whole);
    std::vector<double> depth;
    const std::size_t step = std::max<std::size_t>(1, scene.point_count() / 2000);
    for (std::size_t p = 0; p < scene.point_count(); p += step)
      depth.push_back(reference.optical_depth(scene.scalars, tf, s.light, whole->points[p]));
    const double median = pb::median(depth);
    sigma_a = median > 0 ? std::log(2.0) / median : 1.0;
  }
  MPI_Bcast(&sigma_a, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  s.options.sigma_a = sigma_a;
  return s;
}

// This rank's light per point, as a run over the ranks makes it: level 0 over the scene's
// bounds merged over the ranks, the walks solved locally, the shared points settled.
struct RankLight {
  std::vector<float> rgb;
  double solve_ms = 0;   ///< set_field, merge, update, settle
  double merge_ms = 0;   ///< the level-0 reduction (MPI_Allreduce of extinction and mask)
  double settle_ms = 0;  ///< finding the shared points and settling them
  std::size_t shared_points = 0;
};

RankLight solve_light(penumbra::insitu::RankGroup& group, const std::shared_ptr<const pr::TetMesh>& mesh,
                      const std::vector<float>& scalars, const pr::TransferFunction& tf, const LightSetup& setup,
                      const penumbra::Bounds& bounds) {
  RankLight out;
  pr::LightVolumeOptions o = setup.options;
  o.level0_bounds = bounds;
  MPI_Barrier(MPI_COMM_WORLD);
  pb::Stopwatch total;
  pr::LightVolume lv(mesh, o);
  lv.set_lights({setup.light});
  lv.set_field(scalars, tf);
  pb::Stopwatch merge;
  lv.combine_level0(penumbra::insitu::level0_merge(group));
  out.merge_ms = merge.ms();
  lv.update();
  pb::Stopwatch settle;
  const penumbra::insitu::SharedPoints shared(group, *mesh, {setup.light});
  const penumbra::insitu::SharedPoints::Rho rho{&lv.light_rho(0)};
  out.rgb = lv.light_rgb();
  shared.settle(group, group.exchange(shared.messages(group, rho)), rho, out.rgb);
  out.settle_ms = settle.ms();
  out.solve_ms = total.ms();
  out.shared_points = shared.size();
  return out;
}

// What a rank's runs of one frame hold at their peak, as RenderOptions::ray_runs_memory_bytes
// counts it: each pixel's list while the frame renders, and the flat copy.
double runs_peak_bytes(double pixels, double runs) { return pixels * 28.0 + runs * 48.0; }

// Whether some rank's frame went over the runs' memory bound (collective): then rank 0 prints one
// line naming the first such rank's error instead of timings.
bool agreed_refusal(const std::string& error, int rank, const std::string& partition, const std::string& lit, int side) {
  int mine = error.empty() ? -1 : rank, first = -1;
  int ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  int key = mine < 0 ? ranks : mine;
  MPI_Allreduce(&key, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (first == ranks) return false;
  std::vector<char> text(4096, '\0');
  if (rank == first) error.copy(text.data(), text.size() - 1);
  MPI_Bcast(text.data(), static_cast<int>(text.size()), MPI_CHAR, first, MPI_COMM_WORLD);
  if (rank == 0) {
    nlohmann::ordered_json line;
    line["bench"] = "mpi";
    line["ranks"] = ranks;
    line["partition"] = partition;
    line["lit"] = lit;
    line["width"] = side;
    line["refused"] = true;
    line["error"] = "rank " + std::to_string(first) + ": " + std::string(text.data());
    std::cout << line.dump() << std::endl;
  }
  return true;
}

int run(int argc, char** argv) {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  const std::string name = pb::option(argc, argv, "scene", "holeblock-1m");
  const std::string data_dir = pb::option(argc, argv, "data-dir", "");
  const int frames = std::stoi(pb::option(argc, argv, "frames", "5"));
  const std::size_t runs_memory_bytes = static_cast<std::size_t>(std::stod(pb::option(argc, argv, "runs-memory-mb", "2048")) * (1 << 20));
  penumbra::require(!data_dir.empty(), "pnb_bench_mpi: --data-dir DIR is required");
  const pb::Scene scene = pb::load_scene(name, data_dir);
  const pr::TransferFunction tf = pb::transfer_function(scene);
  std::istringstream partitions(pb::option(argc, argv, "partitions", "slabs metis round-robin"));
  std::vector<std::string> lits, sizes;
  for (std::istringstream in(pb::option(argc, argv, "lit", "none phong")); in;) {
    std::string s;
    if (in >> s) lits.push_back(s);
  }
  for (std::istringstream in(pb::option(argc, argv, "sizes", "512")); in;) {
    std::string s;
    if (in >> s) sizes.push_back(s);
  }
  const std::string parts_dir = pb::option(argc, argv, "write-parts", "");
  if (!parts_dir.empty()) {
    write_parts(parts_dir, scene, tf, partitions, sizes, rank, ranks);
    return 0;
  }
  // The whole scene in one process, on rank 0: the reference picture of every line, and with
  // the light volume, the reference light.
  std::shared_ptr<const pr::TetMesh> whole_mesh;
  std::unique_ptr<pr::CpuRayCaster> whole;
  if (rank == 0) {
    whole_mesh = prepare(scene.points, scene.tets);
    whole = std::make_unique<pr::CpuRayCaster>(whole_mesh);
  }
  const bool light_volume = std::find(lits.begin(), lits.end(), "light-volume") != lits.end();
  LightSetup setup;
  std::vector<float> whole_light;
  double whole_light_ms = 0;
  penumbra::insitu::MpiRankGroup group(MPI_COMM_WORLD);
  penumbra::Bounds bounds;
  for (std::size_t p = 0; p < scene.point_count(); ++p)
    bounds.extend({scene.points[3 * p], scene.points[3 * p + 1], scene.points[3 * p + 2]});
  if (light_volume) {
    setup = light_setup(scene, whole_mesh, tf);
    if (rank == 0) {
      pb::Stopwatch t;
      pr::LightVolume lv(whole_mesh, setup.options);
      lv.set_lights({setup.light});
      lv.set_field(scene.scalars, tf);
      lv.update();
      whole_light = lv.light_rgb();
      whole_light_ms = t.ms();
    }
  }
  for (std::string partition; partitions >> partition;) {
    const Part part = part_of(scene, owners(scene, partition, rank, ranks), rank);
    const auto mesh = prepare(part.xyz, part.tets);
    pr::CpuRayCaster caster(mesh);
    RankLight light;
    if (light_volume) light = solve_light(group, mesh, part.scalars, tf, setup, bounds);
    for (const std::string& size : sizes)
      for (const std::string& lit : lits) {
        const int side = std::stoi(size);
        const pr::Camera camera = pb::camera(scene, side, side);
        pr::RenderOptions options, whole_options;
        if (lit == "phong") options.shading.model = pr::LightingModel::phong;
        if (lit == "light-volume") {
          options.shading.model = pr::LightingModel::light_volume;
          options.shading.light_direction = -normalize(setup.light.vector);
          options.shading.light_rgb = &light.rgb;
        }
        whole_options = options;
        if (lit == "light-volume") whole_options.shading.light_rgb = &whole_light;
        pr::RenderOptions with_runs = options;
        with_runs.ray_runs = true;
        std::vector<double> render, composite;
        pr::RenderOutput out;
        pr::Image image;
        with_runs.ray_runs_memory_bytes = runs_memory_bytes;
        bool refused = false;
        for (int f = 0; f < frames && !refused; ++f) {
          MPI_Barrier(MPI_COMM_WORLD);
          pb::Stopwatch r;
          std::string error;
          try {
            caster.render(part.scalars, tf, camera, with_runs, out);
          } catch (const penumbra::Error& e) {
            if (e.code() != penumbra::ErrorCode::out_of_memory) throw;
            error = e.what();
          }
          render.push_back(r.ms());
          refused = agreed_refusal(error, rank, partition, lit, side);
          if (refused) break;
          MPI_Barrier(MPI_COMM_WORLD);
          pb::Stopwatch c;
          image = penumbra::insitu::composite_runs(MPI_COMM_WORLD, out.runs, side, side);
          composite.push_back(c.ms());
        }
        if (refused) continue;
        const double runs_here = static_cast<double>(out.runs.runs.size());
        double runs_total = 0;
        MPI_Reduce(&runs_here, &runs_total, 1, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
        const Stats render_s = over_ranks(pb::median(render)), composite_s = over_ranks(pb::median(composite));
        const Exchanged moved = exchanged(out.runs, side, side, rank, ranks);
        const Stats bytes = over_ranks(moved.bytes), messages = over_ranks(moved.messages);
        const Stats runs_mb = over_ranks(runs_here * sizeof(pr::RayRun) / (1 << 20));
        const Stats runs_peak_mb = over_ranks(runs_peak_bytes(side * side, runs_here) / (1 << 20));
        const Stats light_s = over_ranks(light.solve_ms), merge_s = over_ranks(light.merge_ms),
                    settle_s = over_ranks(light.settle_ms), shared_s = over_ranks(static_cast<double>(light.shared_points));
        if (rank != 0) continue;
        const auto serial = pr::to_rgb8(whole->render(scene.scalars, tf, camera, whole_options), scene.background);
        const pb::ImageError e = pb::compare_rgb8(pr::to_rgb8(image, scene.background), serial);
        nlohmann::ordered_json line;
        line["bench"] = "mpi";
        line["scene"] = scene.name;
        line["tets"] = scene.tet_count();
        line["ranks"] = ranks;
        line["partition"] = partition;
        line["lit"] = lit;
        line["width"] = side;
        line["render_ms"] = pb::rounded(render_s.median, 1);
        line["render_ms_max"] = pb::rounded(render_s.max, 1);
        line["composite_ms"] = pb::rounded(composite_s.max, 1);
        line["bytes_per_rank"] = pb::rounded(bytes.median, 0);
        line["bytes_per_rank_max"] = pb::rounded(bytes.max, 0);
        line["messages_per_rank"] = pb::rounded(messages.median, 1);
        line["messages_per_rank_max"] = messages.max;
        line["runs_per_pixel"] = pb::rounded(runs_total / (static_cast<double>(side) * side), 3);
        line["runs_mb_max"] = pb::rounded(runs_mb.max, 1);
        line["runs_peak_mb_max"] = pb::rounded(runs_peak_mb.max, 1);
        line["rms_vs_serial_pct"] = pb::rounded(e.rms_pct, 4);
        line["max_level_diff"] = e.max_abs;
        if (lit == "light-volume") {
          line["light_ms"] = pb::rounded(light_s.median, 1);
          line["light_ms_max"] = pb::rounded(light_s.max, 1);
          line["light_ms_serial"] = pb::rounded(whole_light_ms, 1);
          line["level0_merge_ms"] = pb::rounded(merge_s.max, 1);
          line["settle_ms"] = pb::rounded(settle_s.max, 1);
          line["shared_points_max"] = shared_s.max;
        }
        line["frames"] = frames;
        line["load_avg"] = pb::load_average();
        std::cout << line.dump() << std::endl;
      }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  const int status = pb::guarded_main("pnb_bench_mpi", run, argc, argv);
  if (status != 0) MPI_Abort(MPI_COMM_WORLD, status);
  MPI_Finalize();
  return status;
}
