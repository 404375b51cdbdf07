#include "worker/pipeline/tet/volume_mesher.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "common/status_macros.h"
#include "worker/pipeline/mesh/mesh_io.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/tet_regions.h"
#include "worker/pipeline/tet/volume_mesh_checks.h"

namespace sheetmesh {
namespace {

// Under a tetrahedron budget, TetGen's mesh may use this much of it; the rest is the
// improvement's room to insert vertices (at the paper's scale it adds 40%).
constexpr double kBudgetRoom = 0.75;
constexpr double kMaxLattice = 8.0;  // the coarsest lattice plc.lattice allows
// The sizing's prediction: TetGen's Delaunay mesh of well-spaced points has about 6
// tetrahedra per point (a BCC lattice's exactly 6; measured 5.97 on a planar sheet at the
// default lattice, 6.46 at grading 2). Where the lattice is sparse or off, TetGen's own
// refinement adds points and the count comes out higher (12 per PLC point with no lattice).
constexpr double kTetsPerPoint = 6.0;

// A bound on tetrahedron volume so small that TetGen could never hold the mesh it asks for
// is refused before TetGen starts (it would run until killed).
absl::Status CheckMaxVolume(const TetgenOptions& o, double box_volume, const Dims& dims) {
  if (o.max_volume <= 0) return absl::OkStatus();
  // TetGen holds a tetrahedron, its share of the points and its neighbours in about this.
  constexpr double kBytesPerTet = 320;
  const double implied = box_volume / o.max_volume;
  const double room = double(o.memory_limit_bytes) / kBytesPerTet;
  if (implied <= room) return absl::OkStatus();
  const double voxel_volume = box_volume / std::max<double>(1, double(dims.num_voxels()));
  return absl::InvalidArgumentError(absl::StrCat(
      "tet.max_volume ", o.max_volume, " asks for about ", std::llround(implied),
      " tetrahedra in a box of volume ", box_volume, " (one voxel: ", voxel_volume,
      "), more than TetGen's memory limit (tet.memory_limit_bytes ", o.memory_limit_bytes,
      ") holds (about ", std::llround(room), "); raise it to at least ", box_volume / room));
}

// A try of TetGen that crashed (a signal, not an error it reports) runs again with the
// same switches and the lattice seeds moved (MoveSeeds), this many times, before the
// switches give way: on the rough network at r = 3 two of four such moves let -Y mesh what
// it crashed on.
constexpr uint32_t kSeedMoves = 2;
constexpr double kSeedMoveVoxels = 2e-3;
// After the seeds, the sheet vertices themselves, this far (JitterSheetVertices).
constexpr double kSheetJitterVoxels = 2e-6;

// TetGen 1.5 can crash, or give up recovering a facet, on a PLC it meshes with other
// switches: asked to add no point on the facets (-Y), it segfaults where recovering a sheet
// triangle whole needs one (the DPM junction at r = 3). TetGen runs again, first without
// its own quality refinement (the improvement does that; its Steiner points are where
// it crashes most), then also free to add points on the sheet triangles where recovering
// them needs one (each is still covered exactly by tetrahedron faces, its added points
// sliding in it during the improvement); its refinement, free on the sheets, would split
// them many times over (a tenfold count on the DPM junction). Where every try fails and
// `repair` allows, TetGen's own exact check (-d) names the sheet triangles that cut
// through each other though sheetmesh's checks passed them (a sheet crumpled within a
// voxel, nearly flat on itself: the rough network at r = 3): the smaller of each pair is
// removed from *plc, counted with the PLC's repairs, and the tries run again. A try that
// crashed runs again with the lattice seeds moved (kSeedMoves), then with the sheet vertices
// moved a millionth of a voxel (JitterSheetVertices). What failed is said
// in r->tetgen_recovery; the PLC it failed on is kept (TetgenOptions::failed_plc_path).
absl::StatusOr<TetMesh> RunTetgenRecovering(Plc* plc, const TetgenOptions& options, bool repair,
                                            const Progress& progress, VolumeMeshResult* r) {
  std::vector<TetgenOptions> tries = {options};
  if (options.max_radius_edge_ratio > 0) {  // no -q: the constrained Delaunay mesh alone
    tries.push_back(options);
    tries.back().max_radius_edge_ratio = 0;
  }
  if (!options.steiner_on_sheets) {  // and free to add the points recovery needs
    tries.push_back(tries.back());
    tries.back().steiner_on_sheets = true;
  }
  constexpr int kRepairRounds = 3;
  absl::Status last;
  for (int round = 0; round <= kRepairRounds; ++round) {
    for (size_t i = 0; i < tries.size(); ++i) {
      for (uint32_t moved = 0; moved <= kSeedMoves + 1; ++moved) {
        const bool jitter = moved == kSeedMoves + 1;
        if (moved > 0 && !jitter) {
          if (plc->seed_points == 0) continue;
          MoveSeeds(++r->seed_moves, kSeedMoveVoxels, plc);
        }
        if (jitter) JitterSheetVertices(++r->seed_moves, kSheetJitterVoxels, plc);
        absl::StatusOr<TetMesh> mesh = RunTetgen(*plc, tries[i], progress);
        // Only a crash or an error of TetGen's own is tried again; limits and cancels are
        // final.
        if (mesh.ok() || mesh.status().code() != absl::StatusCode::kInternal) {
          if (mesh.ok() && (i > 0 || round > 0)) r->tetgen_switches = TetgenSwitches(tries[i]);
          return mesh;
        }
        last = mesh.status();
        r->tetgen_recovery.push_back(absl::StrCat(TetgenSwitches(tries[i]),
                                                  jitter      ? " (sheet vertices moved)"
                                                  : moved > 0 ? " (lattice seeds moved)"
                                                              : "",
                                                  ": ", last.message().substr(0, 160)));
        // An error TetGen reports (an exit code) is the PLC's, wherever the seeds are.
        if (!absl::StrContains(last.message(), "crashed with signal")) break;
      }
    }
    if (!repair || round == kRepairRounds) break;
    absl::StatusOr<std::vector<std::pair<uint32_t, uint32_t>>> pairs =
        FindFacetIntersections(*plc, options, progress);
    if (!pairs.ok() || pairs->empty()) break;
    const size_t first = plc->facets.size() - plc->sheet_triangles.size();
    auto area = [&](uint32_t facet) {
      const Face& f = plc->sheet_triangles[facet - first];
      return Area({plc->vertices[f[0]], plc->vertices[f[1]], plc->vertices[f[2]]});
    };
    std::vector<uint8_t> drop(plc->sheet_triangles.size(), 0);
    double dropped_area = 0;
    for (const auto& [a, b] : *pairs) {
      if (b < first || (a >= first && drop[a - first]) || drop[b - first]) continue;
      const uint32_t smaller = (a < first || area(b) < area(a)) ? b : a;
      drop[smaller - first] = 1;
      dropped_area += area(smaller);
    }
    const uint32_t dropped = DropSheetTriangles(drop, plc);
    if (dropped == 0) break;
    plc->repaired_triangles += dropped;
    plc->repaired_area_voxels += dropped_area / (plc->voxel_length * plc->voxel_length);
    r->tetgen_recovery.push_back(absl::StrCat("TetGen's intersection check (-d): ", pairs->size(),
                                              " pairs of facets cut through each other; ", dropped,
                                              " sheet triangles removed"));
  }
  return last;
}

// Builds the PLC and runs TetGen into r->mesh, sizing the lattice for the budget, if any:
// the lattice coarsens by the prediction (up to three PLCs), then by TetGen's count (two
// runs); then no lattice, which gives the improvement the best start (kept if within the
// budget); then the coarsest lattice, the least count there is. The first that leaves the
// improvement its room is kept; past the least the budget is refused, naming it.
absl::Status MeshWithinBudget(const TriangleMesh& sheets, const Dims& dims,
                              const Placement& placement, const VolumeMeshOptions& options,
                              const Progress& progress, PlcOptions* plc_options, Plc* plc,
                              VolumeMeshResult* r) {
  const uint64_t budget = options.max_tetrahedra;
  const double room = kBudgetRoom * static_cast<double>(budget);
  for (;;) {
    SM_ASSIGN_OR_RETURN(*plc, BuildPlc(sheets, dims, placement, *plc_options));
    r->predicted_tetrahedra = static_cast<uint64_t>(kTetsPerPoint * plc->vertices.size());
    if (budget > 0 && plc->seed_points > 0 && r->predicted_tetrahedra > room &&
        plc_options->lattice < kMaxLattice && ++r->sizing_predictions < 4) {
      plc_options->lattice = std::min(
          kMaxLattice, plc_options->lattice * std::cbrt(r->predicted_tetrahedra / room) * 1.05);
      continue;
    }
    const Vec3 ext = plc->box_hi - plc->box_lo;
    r->box_volume = std::abs(ext.x * ext.y * ext.z);
    SM_RETURN_IF_ERROR(CheckMaxVolume(options.tetgen, r->box_volume, dims));
    const absl::Time start = absl::Now();
    ++r->sizing_attempts;
    SM_ASSIGN_OR_RETURN(r->mesh, RunTetgenRecovering(plc, options.tetgen, plc_options->repair,
                                                     progress.Sub(0, 0.9), r));
    r->tetgen_seconds = absl::ToDoubleSeconds(absl::Now() - start);
    const uint64_t made = r->mesh.tets.size();
    if (budget == 0 || made <= room) return absl::OkStatus();
    const bool asked_none = options.plc.lattice == 0;
    if (asked_none || plc_options->lattice >= kMaxLattice) {
      if (made <= budget) return absl::OkStatus();
      return absl::InvalidArgumentError(absl::StrCat(
          "max_tetrahedra = ", budget, " is below the least this volume's sheets need: ", made,
          " tetrahedra (TetGen ", r->tetgen_switches, " with ",
          asked_none ? "no lattice, as plc.lattice = 0 asks"
                     : "the coarsest lattice, plc.lattice = 8",
          "); raise it to at least ", made));
    }
    if (plc_options->lattice == 0) {
      if (made <= budget) return absl::OkStatus();  // less room, the better start
      plc_options->lattice = kMaxLattice;
    } else if (r->sizing_attempts >= 2) {
      plc_options->lattice = 0;
    } else {
      // Assuming the seeded points' share scales with the spacing cubed.
      plc_options->lattice =
          std::min(kMaxLattice, plc_options->lattice * std::cbrt(made / room) * 1.1);
    }
  }
}

// The PLC sheet triangles around the tetrahedra under `aim` degrees that have two or more
// corners on the sheets (what the improvement left there it cannot mend: it moves no sheet
// vertex, and a point it adds in a narrow gap between sheets lands as flat): every sheet
// triangle with a face at such a corner. Counts those tetrahedra into *slivers.
std::vector<uint8_t> SheetTrianglesAtSlivers(const Plc& plc, const TetMesh& mesh, double aim,
                                             uint32_t* slivers) {
  std::vector<std::vector<uint32_t>> sheet_of(mesh.nodes.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const int64_t t = int64_t{mesh.face_marker[f]} - kFirstSheetMarker;
    if (t < 0 || t >= static_cast<int64_t>(plc.sheet_triangles.size())) continue;
    for (uint32_t v : mesh.faces[f]) sheet_of[v].push_back(static_cast<uint32_t>(t));
  }
  std::vector<uint8_t> marked(plc.sheet_triangles.size(), 0);
  *slivers = 0;
  for (const Tet& t : mesh.tets) {
    int on = 0;
    for (uint32_t v : t) on += !sheet_of[v].empty();
    if (on < 2) continue;
    const Vec3 &a = mesh.nodes[t[0]], &b = mesh.nodes[t[1]], &c = mesh.nodes[t[2]],
               &d = mesh.nodes[t[3]];
    if (!(MeasureTet(a, b, c, d).min_dihedral_degrees < aim)) continue;
    ++*slivers;
    for (uint32_t v : t) {
      for (uint32_t s : sheet_of[v]) marked[s] = 1;
    }
  }
  return marked;
}

// TetGen's mesh made ready: sheet faces taken again where TetGen listed them wrongly, then
// the improvement within the budget.
absl::Status Finish(const Plc& plc, const VolumeMeshOptions& options, const Progress& progress,
                    TetMesh* mesh, uint32_t* rederived, TetImproveReport* report) {
  *rederived = RederiveFacetFaces(plc, mesh);
  TetImproveOptions improve = options.improve;
  improve.max_tetrahedra = options.max_tetrahedra;
  improve.aim_degrees = options.tetgen.min_dihedral_degrees;
  // Sheet vertices move only where the mesh's nodes of them have the PLC's numbers (TetGen
  // drops a point that coincides with another, and numbers the rest again).
  constexpr double kSamePoint = 1e-6;  // voxels: TetGen's output keeps 16 digits
  if (!NodesFollowPlc(plc, *mesh, kSamePoint)) improve.sheet_move_voxels = 0;
  return ImproveTetMesh(mesh, plc.box_lo, plc.box_hi, static_cast<uint32_t>(plc.vertices.size()),
                        improve, report, progress);
}

// Where slivers pinned by the sheets are left (under tet.min_dihedral), the sheet
// triangles around them are bisected and TetGen and the improvement run again on the finer
// PLC; a round is kept while it raises the smallest angle (by kMinGain) within the budget,
// its tetrahedra filling the box. The sheets
// keep their shape exactly (each new vertex is an edge's midpoint); only their edges there
// get shorter.
absl::Status RefineAtSlivers(const VolumeMeshOptions& options, const Progress& progress, Plc* plc,
                             VolumeMeshResult* r) {
  const int rounds = options.sliver_rounds;
  constexpr double kMinGain = 0.1;           // degrees: a round that gains less is not kept
  constexpr double kMinRoundSeconds = 10.0;  // TetGen's least time limit in a round
  constexpr double kWedgeTolerance = 1e-6;   // degrees
  const double aim = options.tetgen.min_dihedral_degrees;
  double worst = MeasureQuality(r->mesh).min_dihedral.min;
  r->sliver_refinement.min_dihedral_before = worst;
  // Where the smallest angle is the input's own (two facets meeting in an edge at that
  // angle), no round can raise it, and none would be kept: none is run. The wedge is the
  // sheets' as the mesh has them: the improvement may have moved sheet vertices, opening a
  // wedge of the PLC (the phantom sample at r = 2: 6.9° in the PLC, 19.5° in the mesh).
  // Each round starts from the sheets where the mesh has them, so a wedge the moves opened
  // stays open in the finer PLC (each round's improvement may move them again as far).
  auto as_meshed = [&](const Plc& from, const VolumeMeshResult& at) {
    Plc out = from;
    if (at.improvement.moved_sheet_vertices > 0 &&
        NodesFollowPlc(from, at.mesh, options.improve.sheet_move_voxels + 1e-6)) {
      SheetVerticesFromMesh(at.mesh, &out);
    }
    return out;
  };
  const double wedge = MeasureWedges(as_meshed(*plc, *r), aim).narrowest_degrees;
  if (aim > 0 && worst < aim && worst >= wedge - kWedgeTolerance) {
    r->sliver_refinement.stopped =
        absl::StrCat("the input's narrowest wedge (", wedge, " degrees) is the minimum");
    return absl::OkStatus();
  }
  for (int round = 0; round < rounds && aim > 0 && worst < aim; ++round) {
    const Progress step = progress.Sub(double(round) / rounds, double(round + 1) / rounds);
    uint32_t slivers = 0;
    const std::vector<uint8_t> marked = SheetTrianglesAtSlivers(*plc, r->mesh, aim, &slivers);
    if (round == 0) r->sliver_refinement.slivers_on_sheets = slivers;
    Plc finer = as_meshed(*plc, *r);
    const uint32_t split = RefineSheetTriangles(marked, &finer);
    if (split == 0) break;
    // A finer PLC meshes about as fast: TetGen's refinement that does not end on it (the
    // grazing sheet at r = 11 ran into the 600 s limit) is cut short, the mesh there is
    // kept. A round that fails leaves no tetgen_failed.poly beside a mesh that succeeded.
    TetgenOptions tetgen = options.tetgen;
    tetgen.time_limit_seconds =
        std::min(tetgen.time_limit_seconds, std::max(kMinRoundSeconds, 20 * r->tetgen_seconds));
    tetgen.failed_plc_path.clear();
    VolumeMeshResult trial;
    absl::StatusOr<TetMesh> mesh =
        RunTetgenRecovering(&finer, tetgen, /*repair=*/false, step.Sub(0, 0.7), &trial);
    if (!mesh.ok()) {
      if (mesh.status().code() == absl::StatusCode::kCancelled) return mesh.status();
      r->sliver_refinement.stopped =
          absl::StrCat("TetGen: ", mesh.status().message().substr(0, 160));
      break;
    }
    uint32_t rederived = 0;
    TetImproveReport report;
    SM_RETURN_IF_ERROR(Finish(finer, options, step.Sub(0.7, 1), &*mesh, &rederived, &report));
    if (options.max_tetrahedra > 0 && mesh->tets.size() > options.max_tetrahedra) {
      r->sliver_refinement.stopped = "the budget";
      break;
    }
    const TetQuality quality = MeasureQuality(*mesh);
    if (quality.inverted > 0 || std::abs(quality.volume - r->box_volume) > 1e-6 * r->box_volume) {
      r->sliver_refinement.stopped = "a mesh that did not fill the box";
      break;
    }
    const double now = quality.min_dihedral.min;
    if (!(now > worst + kMinGain)) {
      r->sliver_refinement.stopped = absl::StrCat("no gain (", now, " degrees)");
      break;
    }
    worst = now;
    *plc = std::move(finer);
    r->mesh = *std::move(mesh);
    r->rederived_facets = rederived;
    r->improvement = report;
    r->tetgen_tetrahedra = trial.tetgen_tetrahedra;
    ++r->sliver_refinement.rounds;
    r->sliver_refinement.split_edges += split;
  }
  return absl::OkStatus();
}

// Where the mesh stays under tet.min_dihedral, the improvement is on and the input does not
// force it (its narrowest wedge is wider), TetGen, the improvement and the sliver rounds run once
// more on the PLC TetGen began with, its lattice seeds moved (a twentieth of a voxel: the lattice's
// points lie on common spheres, so TetGen's mesh of them changes throughout), and the
// better mesh is kept. What the improvement reaches turns on details no rule foresees (the
// rough network at r = 4: 12.8° from one mesh of its PLC, 5.9° from another), so a second
// draw finds a mesh above the aim where the first did not. A second try that fails for
// TetGen, the budget or the box leaves the first as it was; only a cancel (or the time
// limit) ends the stage.
absl::Status TryAgainFromMovedSeeds(const Plc& first_plc, const VolumeMeshOptions& options,
                                    const Progress& progress, Plc* plc, VolumeMeshResult* r) {
  constexpr double kSeedVoxels = 0.05;
  constexpr uint32_t kSalt = 1u << 20;  // apart from the salts of TetGen's crash retries
  constexpr double kMinGain = 0.1;      // degrees: a second mesh gaining less is not kept
  constexpr double kWedgeTolerance = 1e-6;
  const double aim = options.tetgen.min_dihedral_degrees;
  const double first = MeasureQuality(r->mesh).min_dihedral.min;
  if (!(aim > 0) || !(first < aim) || first_plc.seed_points == 0 || r->mesh.tets.empty() ||
      options.improve.passes == 0) {
    return absl::OkStatus();
  }
  if (first >= MeasureWedges(first_plc, aim).narrowest_degrees - kWedgeTolerance) {
    return absl::OkStatus();
  }
  r->second_try.tried = true;
  r->second_try.min_dihedral_first = first;
  Plc again = first_plc;
  MoveSeeds(kSalt, kSeedVoxels, &again);
  VolumeMeshResult second = *r;
  second.sliver_refinement = {};
  TetgenOptions tetgen = options.tetgen;
  tetgen.failed_plc_path.clear();
  absl::StatusOr<TetMesh> mesh =
      RunTetgenRecovering(&again, tetgen, /*repair=*/false, progress.Sub(0, 0.3), &second);
  if (!mesh.ok()) {
    if (mesh.status().code() == absl::StatusCode::kCancelled) return mesh.status();
    r->second_try.stopped = absl::StrCat("TetGen: ", mesh.status().message().substr(0, 160));
    return absl::OkStatus();
  }
  second.mesh = *std::move(mesh);
  second.tetgen_tetrahedra = second.mesh.tets.size();
  SM_RETURN_IF_ERROR(Finish(again, options, progress.Sub(0.3, 0.7), &second.mesh,
                            &second.rederived_facets, &second.improvement));
  SM_RETURN_IF_ERROR(RefineAtSlivers(options, progress.Sub(0.7, 1), &again, &second));
  if (options.max_tetrahedra > 0 && second.mesh.tets.size() > options.max_tetrahedra) {
    r->second_try.stopped = "the budget";
    return absl::OkStatus();
  }
  const TetQuality quality = MeasureQuality(second.mesh);
  if (quality.inverted > 0 || std::abs(quality.volume - r->box_volume) > 1e-6 * r->box_volume) {
    r->second_try.stopped = "a mesh that did not fill the box";
    return absl::OkStatus();
  }
  r->second_try.min_dihedral_second = quality.min_dihedral.min;
  if (!(quality.min_dihedral.min > first + kMinGain)) return absl::OkStatus();
  second.second_try = r->second_try;
  second.second_try.kept = true;
  *r = std::move(second);
  *plc = std::move(again);
  return absl::OkStatus();
}

// BuildVolumeMesh in the units `placement` gives (see there).
absl::StatusOr<VolumeMeshResult> BuildInPlacement(const TriangleMesh& surface, const Dims& dims,
                                                  const Placement& placement,
                                                  const VolumeMeshOptions& options,
                                                  const Progress& progress) {
  // The sheet faces carry their aperture into the volume mesh, where a flow model takes it.
  TriangleMesh with_apertures;
  if (surface.face_aperture_voxels.size() == surface.faces.size() && !surface.faces.empty()) {
    with_apertures = surface;
    with_apertures.face_thickness_voxels = surface.face_aperture_voxels;
  }
  const TriangleMesh& sheets = with_apertures.faces.empty() ? surface : with_apertures;
  VolumeMeshResult r;
  // A TetGen that may add no points on facets needs the box faces seeded, else they
  // stay two triangles each.
  PlcOptions plc_options = options.plc;
  plc_options.seed_box = plc_options.seed_box || !options.tetgen.steiner_on_sheets;
  r.max_tetrahedra = options.max_tetrahedra;
  r.tetgen_switches = TetgenSwitches(options.tetgen);
  // tet.time_limit_seconds bounds the whole stage: TetGen, the improvement and the sliver
  // rounds (the improvement alone ran 43 s past a 20 s limit). The improvement and a round
  // stop between operations, so a mesh cut short there is whole and kept; TetGen cut short
  // leaves none.
  const absl::Time start = absl::Now();
  DeadlineObserver clock(progress.observer(),
                         absl::Now() + absl::Seconds(options.tetgen.time_limit_seconds));
  const Progress timed = progress.WithObserver(&clock);
  const auto at_limit = [&](const absl::Status& st) {
    return st.code() == absl::StatusCode::kCancelled && clock.expired_in().has_value();
  };
  Plc plc;
  if (absl::Status st =
          MeshWithinBudget(sheets, dims, placement, options, timed, &plc_options, &plc, &r);
      !st.ok()) {
    if (!at_limit(st)) return st;
    return absl::DeadlineExceededError(absl::StrCat(
        "the volume stage went past tet.time_limit_seconds = ", options.tetgen.time_limit_seconds,
        " s while TetGen ran"));
  }
  r.lattice = plc_options.lattice;
  r.grading = plc_options.grading;
  r.tetgen_tetrahedra = r.mesh.tets.size();
  const std::string limit_reached =
      absl::StrCat("tet.time_limit_seconds = ", options.tetgen.time_limit_seconds, " s");
  const Plc surface_plc = plc;  // the sheets where the surface put them
  if (absl::Status st =
          Finish(plc, options, timed.Sub(0.9, 0.95), &r.mesh, &r.rederived_facets, &r.improvement);
      !st.ok()) {
    if (!at_limit(st)) return st;
    r.improvement.time_limited = true;
    r.sliver_refinement.stopped = limit_reached;
  } else if (absl::Status st = RefineAtSlivers(options, timed.Sub(0.95, 0.99), &plc, &r);
             !st.ok()) {
    if (!at_limit(st)) return st;
    r.sliver_refinement.stopped = limit_reached;
  }
  // A second try is made only where the time limit leaves room for one as long as the first.
  const absl::Duration took = absl::Now() - start;
  if (took > absl::Seconds(options.tetgen.time_limit_seconds) - took) {
    if (MeasureQuality(r.mesh).min_dihedral.min < options.tetgen.min_dihedral_degrees) {
      r.second_try.stopped = absl::StrCat("no room for it within ", limit_reached);
    }
  } else if (absl::Status st =
                 TryAgainFromMovedSeeds(surface_plc, options, timed.Sub(0.99, 0.995), &plc, &r);
             !st.ok()) {
    if (!at_limit(st)) return st;
    r.second_try.stopped = limit_reached;
  }
  // Where the mesh stays under the aim after every round, the sheet moves that did not
  // lift its minimum go back (the improvement keeps those that lift a sliver towards the
  // aim, for the rounds that may follow).
  const double aim = options.tetgen.min_dihedral_degrees;
  const bool follows = NodesFollowPlc(plc, r.mesh, options.improve.sheet_move_voxels + 1e-6);
  const bool moved = r.improvement.moved_sheet_vertices > 0 && follows;
  if (moved && aim > 0 && !r.mesh.tets.empty()) {
    const double worst = MeasureQuality(r.mesh).min_dihedral.min;
    if (worst < aim) r.improvement.returned_sheet_vertices += TakeBackSheetMoves(plc, worst, &r);
  }
  // A kept sliver round began from the sheets as the improvement had moved them: the moves
  // are counted from where the surface put them (a round keeps those vertices' numbers).
  if (r.sliver_refinement.rounds > 0 && follows) {
    CountSheetMoves(surface_plc, r.mesh, &r.improvement);
  }
  // The improvement may have moved sheet vertices of the PLC within their reach
  // (improve.sheet_move_voxels): the PLC is what the mesh has, for the checks below.
  if (moved) SheetVerticesFromMesh(r.mesh, &plc);
  static_cast<PlcStats&>(r) = plc;
  r.wedges = MeasureWedges(plc, options.tetgen.min_dihedral_degrees);
  r.conformity = CheckConformity(plc, r.mesh);
  if (r.conformity.orphan_faces > 0) {
    return absl::InternalError(
        absl::StrCat("the volume mesh does not conform: ", r.conformity.orphan_faces,
                     " facet faces are faces of no tetrahedron"));
  }
  if (r.conformity.conforming != r.conformity.sheet_triangles) {
    return absl::InternalError(absl::StrCat(
        "the volume mesh does not conform: ",
        r.conformity.sheet_triangles - r.conformity.conforming, " of ",
        r.conformity.sheet_triangles, " sheet triangles are not made of tetrahedron faces (first: ",
        r.conformity.missing.empty() ? -1 : static_cast<int64_t>(r.conformity.missing[0]),
        ", area error ", r.conformity.worst_area_error, ")"));
  }
  // Contracted edges leave nodes in no tetrahedron; a solver must not see them.
  r.mesh.RemoveUnusedNodes();
  r.mesh.body_pieces = sheets.body_pieces;
  r.mesh.tet_region = AssignRegions(r.mesh, sheets, placement);
  for (const int32_t piece : sheets.body_pieces) r.bodies.push_back({piece, 0, 0.0});
  for (size_t t = 0; t < r.mesh.tet_region.size(); ++t) {
    const int32_t piece = r.mesh.tet_region[t];
    if (piece < 0) continue;
    auto it = std::lower_bound(
        r.bodies.begin(), r.bodies.end(), piece,
        [](const VolumeMeshStats::BodyRegion& b, int32_t p) { return b.piece < p; });
    const Tet& q = r.mesh.tets[t];
    ++it->tetrahedra;
    it->volume += std::abs(
        TetVolume(r.mesh.nodes[q[0]], r.mesh.nodes[q[1]], r.mesh.nodes[q[2]], r.mesh.nodes[q[3]]));
  }
  // The nodes are physical; a voxel's length makes the thickness so where it is written.
  r.mesh.voxel_length = PhysicalLength(1.0, placement);
  r.mesh.unit = placement.unit;
  r.quality = MeasureQuality(r.mesh);
  if (aim > 0 && r.quality.min_dihedral.min < aim && !r.mesh.tets.empty()) {
    r.angle_warning = DescribeWorst(r.mesh, r.quality.min_dihedral.min, aim,
                                    r.wedges.narrowest_degrees, placement);
  }
  r.nodes = r.mesh.nodes.size();
  r.tetrahedra = r.mesh.tets.size();
  r.sheet_faces = r.mesh.num_sheet_faces();
  r.voxels_per_tet = r.tetrahedra > 0 ? double(dims.num_voxels()) / r.tetrahedra : 0.0;
  if (r.quality.inverted > 0) {
    return absl::InternalError(
        absl::StrCat("the volume mesh has ", r.quality.inverted, " inverted tetrahedra"));
  }
  if (std::abs(r.quality.volume - r.box_volume) > 1e-6 * r.box_volume) {
    return absl::InternalError(absl::StrCat("the tetrahedra's volume ", r.quality.volume,
                                            " differs from the box's ", r.box_volume));
  }
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return r;
}

}  // namespace

absl::StatusOr<VolumeMeshResult> BuildVolumeMesh(const TriangleMesh& surface, const Dims& dims,
                                                 const Placement& placement,
                                                 const VolumeMeshOptions& options,
                                                 const Progress& progress) {
  // Meshed in units of the smallest voxel edge, the first voxel's centre at 0, then placed:
  // TetGen's and the improvement's tolerances are partly absolute, so a box of 1e-10 m (a
  // spacing of 1e-12 m) made TetGen abort, and meshes of one volume differed a little from
  // one unit to another. Angles and counts do not depend on the unit; lengths, volumes and
  // places are scaled back.
  const Vec3& h = placement.spacing;
  const double s = std::min({h.x, h.y, h.z});
  if (!(s > 0) || !std::isfinite(s) || !std::isfinite(std::max({h.x, h.y, h.z}))) {
    return absl::InvalidArgumentError(
        absl::StrCat("the volume mesh needs a positive spacing, not ", h.x, ",", h.y, ",", h.z));
  }
  Placement unit = placement;
  unit.spacing = {h.x / s, h.y / s, h.z / s};
  unit.origin = {0, 0, 0};
  VolumeMeshOptions o = options;
  o.tetgen.max_volume /= s * s * s;  // unit^3 (0 stays 0: none)
  absl::StatusOr<VolumeMeshResult> built = BuildInPlacement(surface, dims, unit, o, progress);
  if (!built.ok() && built.status().code() == absl::StatusCode::kInternal &&
      absl::StrContains(built.status().message(), "does not conform") &&
      o.improve.sheet_move_voxels > 0) {
    // A mesh whose moved sheet vertices left it not conforming (seen once, on the
    // rough_network preset at r = 5, cause not yet found) is made again with the PLC's
    // vertices held, as before the moves existed; the report says so.
    const std::string why(built.status().message().substr(0, 120));
    o.improve.sheet_move_voxels = 0;
    built = BuildInPlacement(surface, dims, unit, o, progress);
    if (built.ok()) {
      built->tetgen_recovery.push_back(
          absl::StrCat("meshed again with improve.sheet_move_voxels = 0: ", why));
    }
  }
  if (!built.ok() && built.status().code() == absl::StatusCode::kInternal &&
      absl::StrContains(built.status().message(), "TetGen") && o.plc.zip_rims) {
    // TetGen refusing the PLC with its rims zipped onto the sheets they run along (seen
    // once in the developers' sweep before the join was limited to rims standing on a
    // sheet) meshes the PLC as before the zipping existed; the report says so.
    const std::string why(built.status().message().substr(0, 120));
    o.plc.zip_rims = false;
    built = BuildInPlacement(surface, dims, unit, o, progress);
    if (built.ok()) {
      built->tetgen_recovery.push_back(
          absl::StrCat("meshed again with the rims not zipped (plc zip_rims off): ", why));
    }
  }
  SM_ASSIGN_OR_RETURN(VolumeMeshResult r, std::move(built));
  const Vec3& origin = placement.origin;
  auto place = [&](Vec3& p) { p = {p.x * s + origin.x, p.y * s + origin.y, p.z * s + origin.z}; };
  for (Vec3& p : r.mesh.nodes) place(p);
  for (Vec3& p : r.contact_places) place(p);
  if (r.angle_warning) place(r.angle_warning->at);
  const double cube = s * s * s;
  r.lattice_spacing *= s;
  r.lattice_coarsest *= s;
  r.box_volume *= cube;
  r.quality.volume *= cube;
  for (VolumeMeshStats::BodyRegion& b : r.bodies) b.volume *= cube;
  r.mesh.voxel_length = PhysicalLength(1.0, placement);
  r.mesh.unit = placement.unit;
  return r;
}

}  // namespace sheetmesh
