// Builds the SCVD and its dual triangles of a volume's non-zero voxels whole or brick by
// brick (worker/pipeline/surface/bricked_surface.h) and prints one JSON line: counts, the
// similarity of the vertex-thickness prisms, seconds, peak memory. Run by
// bench/bricked_surface_bench.py, each mode in a process of its own so the peaks compare.
//   --mode=whole    one brick: the whole volume's local SCVD and triangles
//   --mode=bricked  both passes in bricks of --brick voxels with --halo (0: SurfaceHalo)
//   --mode=check    the whole volume's generators, then pass 2 in bricks: are the faces
//                   the whole volume's?
//   --mode=stream   today's one-process surface (BuildSurface: generators from one random
//                   stream, Lloyd until the energy settles) with the same dual options and
//                   no fitting, smoothing or orientation, for the same figures
#include <sys/resource.h>

#include <algorithm>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/time/clock.h"
#include "worker/pipeline/similarity/mesh_model.h"
#include "worker/pipeline/similarity/similarity.h"
#include "worker/pipeline/surface/bricked_surface.h"
#include "worker/pipeline/surface/surface_builder.h"
#include "worker/pipeline/volume/volume_open.h"
#include "worker/pipeline/voxel/phase_selection.h"
#include "worker/pipeline/voxel/sheet_analysis.h"

ABSL_FLAG(std::string, mode, "whole", "whole, bricked or check");
ABSL_FLAG(double, r, 7.0, "the SCVD's cell radius, voxels");
ABSL_FLAG(int, lloyd, 8, "Lloyd steps");
ABSL_FLAG(uint64_t, seed, 1, "seed of the generators' hash");
ABSL_FLAG(std::string, draw, "spaced",
          "the local draw: spaced (blue noise, the default) or bernoulli (one by one)");
ABSL_FLAG(int, brick, 128, "brick side, voxels");
ABSL_FLAG(int, halo, 0, "halo, voxels (0: SurfaceHalo(r, t_max))");
ABSL_FLAG(double, t, 0, "the sheet's mean thickness t (0: measured on the whole volume)");
ABSL_FLAG(double, t_max, 0, "the sheet's longest thickness run (0: measured likewise)");

namespace sheetmesh {
namespace {

double PeakMiB() {
  struct rusage u;
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;
}

int Measure(const std::string& path) {
  nlohmann::json j;
  absl::Time t0 = absl::Now();
  auto source = OpenVolume(path);
  if (!source.ok()) {
    std::cerr << source.status() << "\n";
    return 1;
  }
  auto set = SelectPhase(**source, PhaseSelection::NonZero());
  if (!set.ok()) {
    std::cerr << set.status() << "\n";
    return 1;
  }
  j["read_seconds"] = absl::ToDoubleSeconds(absl::Now() - t0);
  j["voxels"] = set->size();
  const std::string mode = absl::GetFlag(FLAGS_mode);
  double t = absl::GetFlag(FLAGS_t), t_max = absl::GetFlag(FLAGS_t_max);
  t0 = absl::Now();
  if (t <= 0 || t_max <= 0) {
    auto a = AnalyzeSheet(*set);
    if (!a.ok()) {
      std::cerr << a.status() << "\n";
      return 1;
    }
    t = a->thickness_stats.mean;
    t_max = *std::max_element(a->thickness.begin(), a->thickness.end());
  }
  j["t"] = t;
  j["t_max"] = t_max;
  j["measure_seconds"] = absl::ToDoubleSeconds(absl::Now() - t0);
  SurfaceOptions so;
  so.scvd.radius_voxels = absl::GetFlag(FLAGS_r);
  so.scvd.lloyd_max_iter = absl::GetFlag(FLAGS_lloyd);
  so.scvd.seed = absl::GetFlag(FLAGS_seed);
  so.scvd.local_spacing = absl::GetFlag(FLAGS_draw) != "bernoulli";
  j["draw"] = so.scvd.local_spacing ? "spaced" : "bernoulli";
  BrickedSurfaceOptions whole;
  whole.brick = set->dims();
  whole.halo = 0;
  BrickedSurfaceOptions bricks;
  const int side = absl::GetFlag(FLAGS_brick);
  bricks.brick = {side, side, side};
  bricks.halo = absl::GetFlag(FLAGS_halo) > 0 ? absl::GetFlag(FLAGS_halo)
                                              : SurfaceHalo(so.scvd.radius_voxels, t_max);
  t0 = absl::Now();
  absl::StatusOr<BrickedSurface> s;
  if (mode == "whole") {
    s = BuildBrickedSurface(*set, t, so, whole);
  } else if (mode == "bricked") {
    s = BuildBrickedSurface(*set, t, so, bricks);
  } else if (mode == "check") {
    s = BuildBrickedSurface(*set, t, so, whole);
    if (s.ok()) {
      j["whole_seconds"] = absl::ToDoubleSeconds(absl::Now() - t0);
      t0 = absl::Now();
      absl::StatusOr<BrickedSurface> b = BuildBrickedSurface(*set, t, so, bricks, s->generators);
      if (!b.ok()) {
        std::cerr << b.status() << "\n";
        return 1;
      }
      const std::vector<SurfaceFaceKey> want = FaceKeys(*s), got = FaceKeys(*b);
      std::vector<SurfaceFaceKey> missing, extra;
      std::set_difference(want.begin(), want.end(), got.begin(), got.end(),
                          std::back_inserter(missing));
      std::set_difference(got.begin(), got.end(), want.begin(), want.end(),
                          std::back_inserter(extra));
      j["faces_missing"] = missing.size();
      j["faces_extra"] = extra.size();
      j["same_faces"] = missing.empty() && extra.empty() && b->disagreeing_vertices == 0;
      // The same, with no second pass allowed: does the halo rule alone suffice?
      s = std::move(b);
    }
  } else if (mode == "stream") {
    auto a = AnalyzeSheet(*set);
    if (!a.ok()) {
      std::cerr << a.status() << "\n";
      return 1;
    }
    SurfaceOptions plain = so;
    plain.scvd.lloyd_max_iter = 20;  // the default: up to 20, stopped by lloyd_tol
    plain.thickness = ThicknessMeasure::kAxisRuns;
    plain.orient = false;
    plain.fit_walls = false;
    plain.smooth_iterations = 0;
    auto built = BuildSurface(*a, plain);
    if (!built.ok()) {
      std::cerr << built.status() << "\n";
      return 1;
    }
    BrickedSurface b;
    b.mesh = std::move(built->mesh);
    b.generators = built->scvd.generators;
    b.bricks = 1;
    b.largest_crop_voxels = set->size();
    s = std::move(b);
  } else {
    std::cerr << "--mode=" << mode << ": give whole, bricked, check or stream\n";
    return 2;
  }
  if (!s.ok()) {
    std::cerr << s.status() << "\n";
    return 1;
  }
  j["build_seconds"] = absl::ToDoubleSeconds(absl::Now() - t0);
  j["peak_mib_after_build"] = PeakMiB();
  t0 = absl::Now();
  auto model = VoxelizePrisms(s->mesh, set->dims(), PrismHeight::kVertex);
  if (!model.ok()) {
    std::cerr << model.status() << "\n";
    return 1;
  }
  j["similarity"] = ScoreModel(*model, *set).similarity;
  j["score_seconds"] = absl::ToDoubleSeconds(absl::Now() - t0);
  j["mode"] = mode;
  j["r"] = so.scvd.radius_voxels;
  j["brick"] = side;
  j["halo"] = bricks.halo;
  j["faces"] = s->mesh.faces.size();
  j["vertices"] = s->mesh.vertices.size();
  j["generators"] = s->generators.size();
  j["bricks"] = s->bricks;
  j["largest_crop_voxels"] = s->largest_crop_voxels;
  j["disagreeing_vertices"] = s->disagreeing_vertices;
  j["seam_mismatches"] = s->seam_mismatches;
  j["retries"] = s->retries;
  j["halo_used"] = s->halo;
  j["peak_mib"] = PeakMiB();
  std::cout << j.dump() << std::endl;
  return 0;
}

}  // namespace
}  // namespace sheetmesh

int main(int argc, char** argv) {
  std::vector<char*> args = absl::ParseCommandLine(argc, argv);
  if (args.size() != 2) {
    std::cerr << "usage: sheetmesh-bricked-surface-bench VOLUME [--mode=whole|bricked|check] "
                 "[--r=7] [--brick=128] [--halo=0] [--lloyd=8] [--t=T --t_max=T]\n";
    return 2;
  }
  return sheetmesh::Measure(args[1]);
}
