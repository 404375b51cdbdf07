// The improvement pass: rounds of flips, insertion and smoothing (tet_improve.h), each
// operation in its own file over one TetMeshEditor.
#include "worker/pipeline/tet/tet_improve.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "absl/time/clock.h"
#include "worker/pipeline/tet/tet_contraction.h"
#include "worker/pipeline/tet/tet_flips.h"
#include "worker/pipeline/tet/tet_insertion.h"
#include "worker/pipeline/tet/tet_mesh_editor.h"
#include "worker/pipeline/tet/tet_smoothing.h"
#include "worker/pipeline/tet/vertex_freedom.h"

namespace sheetmesh {

absl::Status ImproveTetMesh(TetMesh* mesh, const Vec3& box_lo, const Vec3& box_hi,
                            uint32_t input_nodes, const TetImproveOptions& options,
                            TetImproveReport* report, const Progress& progress) {
  const absl::Time start = absl::Now();
  *report = {};
  TetMeshEditor ed(mesh);
  VertexFreedom freedom(*mesh, box_lo, box_hi, input_nodes,
                        options.split_sheets_below_degrees > 0 ? options.sheet_move_voxels : 0);
  VertexInserter inserter(ed, freedom, options);
  const SmoothingOptions smoothing{options.smoothing_floor_degrees, options.radius_weight};
  report->movable_vertices = freedom.movable();
  std::vector<uint32_t> balls;  // the PLC sheet vertices that may move, as they began
  for (uint32_t v = 0; v < ed.num_nodes(); ++v) {
    if (freedom.in_ball(v)) balls.push_back(v);
  }
  report->sliding_vertices = freedom.sliding();
  std::tie(report->min_dihedral_before, report->mean_dihedral_before) = ed.MinMean();
  absl::Status status;
  // Under a budget: whether an insertion fits (into a cavity of k it adds at most k + 2,
  // and cavities hold at most 128, tet_cavity.cc), and how many tetrahedra a flip may add
  // (3 is any flip; at the budget only those that add none, 3-2 and 4-4, are tried).
  constexpr uint64_t kInsertAdds = 130;
  auto fits = [&](uint64_t added) {
    if (options.max_tetrahedra == 0 || ed.live() + added <= options.max_tetrahedra) return true;
    ++report->over_budget;
    return false;
  };
  auto flip_room = [&]() -> int {
    if (options.max_tetrahedra == 0) return 3;
    const uint64_t live = ed.live();
    const uint64_t room = live < options.max_tetrahedra ? options.max_tetrahedra - live : 0;
    return static_cast<int>(std::min<uint64_t>(room, 3));
  };
  // One flip on tetrahedron t, for its worst (mean < 0) or for the mesh's mean; counts it.
  auto flip = [&](uint32_t t, double mean) {
    switch (FlipAround(ed, t, mean, flip_room())) {
      case Flip::kEdge:
        ++report->edge_removals;
        return true;
      case Flip::kFace:
        ++report->face_removals;
        return true;
      case Flip::kNone:
        break;
    }
    return false;
  };
  // The work list: the clock at a tetrahedron's or vertex's last failed try (0: none). A try
  // whose neighbourhood has not changed since would fail again (tet_mesh_editor.h), so it is
  // skipped; a flip that failed for want of room under the budget is tried again.
  std::vector<uint64_t> worst_tried, mean_tried, move_tried(ed.num_nodes(), 0);
  auto skip = [&](std::vector<uint64_t>& tried, uint32_t t) {
    if (t >= tried.size()) tried.resize(t + 1 + t / 4, 0);
    if (tried[t] == 0 || !ed.UnchangedSince(ed.tet(t), tried[t])) return false;
    ++report->retries_skipped;
    return true;
  };
  auto remember_failure = [&](std::vector<uint64_t>& tried, uint32_t t) {
    if (flip_room() == 3) tried[t] = ed.clock();
  };
  for (int pass = 0; pass < options.passes && status.ok(); ++pass) {
    uint64_t changes = 0;
    const double insert_below =
        pass == 0 ? options.insert_below_degrees
                  : std::min(options.insert_below_degrees, options.insert_again_below_degrees);
    // No vertex on a sheet in the first pass: a split freezes the sheet's own vertices at
    // the split face (its pieces must stay in one plane), and the smoothing after the first
    // pass may yet move them out of the sliver (the rough network at r = 3: 1.1° with
    // splits from the first pass, 15.0° without).
    const bool splits = pass > 0 || options.passes == 1;
    inserter.AllowSheetSplits(splits);
    std::vector<uint32_t> bad = ed.Bad(options.target_degrees);
    for (size_t i = 0; i < bad.size() && status.ok(); ++i) {
      status = progress.Tick(i, bad.size(), 4096);
      const uint32_t t = bad[i];
      if (!ed.alive(t) || ed.quality(t) >= options.target_degrees) continue;
      if (!skip(worst_tried, t)) {
        if (flip(t, -1)) {
          ++changes;
          continue;
        }
        remember_failure(worst_tried, t);
      }
      // A sheet vertex the sheets can do without goes before another is added beside it.
      if (ed.quality(t) < options.split_sheets_below_degrees &&
          ContractSheetEdgeOf(ed, freedom, t)) {
        ++report->contracted_sheet_edges;
        ++changes;
      } else if (ed.quality(t) < insert_below && fits(kInsertAdds) && inserter.InsertNear(t)) {
        ++report->inserted_vertices;
        ++changes;
      } else if (ed.alive(t) && ed.quality(t) < options.split_sheets_below_degrees &&
                 ContractEdgeOf(ed, freedom, t)) {
        ++report->contracted_edges;
        ++changes;
      }
    }
    // Then flips that raise the mean (a try that failed at an earlier pass's mean is not
    // made again while its neighbourhood stands: the mean moves little between passes).
    const double mean = ed.MinMean().second;
    bad = ed.Bad(options.target_degrees);
    for (size_t i = 0; i < bad.size() && status.ok(); ++i) {
      status = progress.Tick(i, bad.size(), 4096);
      const uint32_t t = bad[i];
      if (!ed.alive(t) || skip(mean_tried, t)) continue;
      if (flip(t, mean)) {
        ++changes;
      } else {
        remember_failure(mean_tried, t);
      }
    }
    // Then the smoothing, on all cores (tet_smoothing.h).
    move_tried.resize(ed.num_nodes(), 0);
    std::vector<uint32_t> todo;
    for (uint32_t v = 0; v < ed.num_nodes(); ++v) {
      if (freedom.may_move(v)) todo.push_back(v);
    }
    auto wants = [&](uint32_t v) {
      const double worst = ed.StarMin(v);
      if (worst >= options.target_degrees) return false;
      if (freedom.in_ball(v) && worst >= options.split_sheets_below_degrees) return false;
      if (move_tried[v] == 0 || !ed.UnchangedSince(v, move_tried[v])) return true;
      ++report->retries_skipped;
      return false;
    };
    auto done = [&](uint32_t v, bool moved) {
      if (moved) {
        ++report->smoothing_moves;
        ++changes;
      } else {
        move_tried[v] = ed.clock();
      }
    };
    if (status.ok()) {
      status = SmoothVertices(ed, freedom, std::move(todo), smoothing, wants, done, progress);
    }
    report->passes = pass + 1;
    if (status.ok()) status = progress.Update(static_cast<double>(pass + 1) / options.passes);
    if (changes == 0 && splits) break;
  }
  // The sheet moves the angles do not need go back, in quarters towards where they began:
  // as far as the vertex's star stays at the mesh's minimum, so the minimum stays what the
  // passes reached (at the aim where the minimum is under it: a move that lifts a sliver
  // towards the aim stays, for the sliver rounds that may follow). A vertex whose face was
  // split since it moved stays (its face's pieces lie in the plane it made).
  const double keep_above = std::max(options.aim_degrees, ed.MinMean().first);
  for (uint32_t v : balls) {
    const Vec3 now = ed.node(v), anchor = freedom.anchor(v);
    if (now == anchor || !freedom.in_ball(v)) continue;
    for (const double share : {0.0, 0.25, 0.5, 0.75}) {
      ed.node(v) = anchor + (now - anchor) * share;
      double worst = 1e300;
      for (uint32_t t : ed.star(v)) worst = std::min(worst, ed.Quality(ed.tet(t)));
      if (worst >= keep_above) {
        for (uint32_t t : ed.star(v)) ed.Remeasure(t);
        if (share == 0) ++report->returned_sheet_vertices;
        break;
      }
      ed.node(v) = now;
    }
  }
  std::tie(report->min_dihedral_after, report->mean_dihedral_after) = ed.MinMean();
  for (uint32_t v : balls) {
    const double moved = Norm(ed.node(v) - freedom.anchor(v));
    if (!(moved > 0)) continue;
    ++report->moved_sheet_vertices;
    report->max_sheet_move = std::max(report->max_sheet_move, moved);
  }
  report->sheet_face_splits = inserter.facet_splits();
  report->box_face_splits = inserter.box_splits();
  report->sheet_edge_splits = inserter.edge_splits();
  ed.Finish();
  report->seconds = absl::ToDoubleSeconds(absl::Now() - start);
  return status;
}

}  // namespace sheetmesh
