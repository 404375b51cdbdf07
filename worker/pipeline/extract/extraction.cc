#include "worker/pipeline/extract/extraction.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/status_macros.h"
#include "worker/pipeline/extract/regrow.h"
#include "worker/pipeline/extract/scvd_of_set.h"
#include "worker/pipeline/scvd/scvd.h"
#include "worker/pipeline/voxel/components.h"
#include "worker/pipeline/voxel/morphology.h"
#include "worker/pipeline/voxel/thickness.h"

namespace sheetmesh {
namespace {

absl::StatusOr<uint32_t> CountComponents(const VoxelSet& set) {
  SM_ASSIGN_OR_RETURN(Components c, LabelComponents(set, Connectivity::k6));
  return c.count();
}

// Seconds since `start`.
double Since(absl::Time start) { return absl::ToDoubleSeconds(absl::Now() - start); }

void Count(const VoxelSet& before, const VoxelSet& after, ExtractionStep* s) {
  s->voxels_before = before.size();
  s->voxels_after = after.size();
  const uint64_t common = Intersection(before, after).size();
  s->added = after.size() - common;
  s->removed = before.size() - common;
}

}  // namespace

ExtendOptions Following(ExtendOptions e, const SeparationOptions& separation) {
  if (e.scvd_radius_voxels == 0) e.scvd_radius_voxels = separation.radius_voxels;
  return e;
}

namespace {

// The workflow of Fig. 3 on one input: each step reads what the one before made.
class Workflow {
 public:
  Workflow(const VoxelSet& input, const ExtractionOptions& o, const Progress& progress, uint64_t m)
      : input_(input), o_(o), progress_(progress), m_(m), refined_(input) {}

  // Runs `body` as step `name` (when `ran`), timing it and recording it in out_.
  template <class Body>
  absl::Status Step(const char* name, bool ran, Body body) {
    ExtractionStep s{name};
    const absl::Time start = absl::Now();
    s.ran = ran;
    SM_RETURN_IF_ERROR(body(&s));
    s.seconds = Since(start);
    if (s.ran) SM_RETURN_IF_ERROR(progress_.Stage(s.name).Update(1.0));
    out_.steps.push_back(s);
    return absl::OkStatus();
  }

  // 1. refine: a closing, then an opening.
  absl::Status Refine(ExtractionStep* s) {
    if (!s->ran) return absl::OkStatus();
    SM_ASSIGN_OR_RETURN(s->objects_before, CountComponents(input_));
    if (o_.refine_close_radius > 0) {
      SM_ASSIGN_OR_RETURN(refined_, Close(refined_, o_.refine_close_radius, Connectivity::k6,
                                          progress_.Stage("refine")));
    }
    if (o_.refine_open_radius > 0) {
      SM_ASSIGN_OR_RETURN(refined_, Open(refined_, o_.refine_open_radius, Connectivity::k6,
                                         progress_.Stage("refine")));
    }
    SM_ASSIGN_OR_RETURN(s->objects_after, CountComponents(refined_));
    Count(input_, refined_, s);
    return absl::OkStatus();
  }

  // 2. detect: objects are the components after extending; a major object has at least M
  // voxels of the image. Its fragments are kept, labelled as one object; the bridging
  // voxels are not (the model keeps to the image).
  absl::Status Detect(ExtractionStep* s) {
    SM_ASSIGN_OR_RETURN(Components refined_components, LabelComponents(refined_, Connectivity::k6));
    objects_ = LabelByComponents(refined_, refined_components);
    s->objects_before = refined_components.count();
    if (s->ran) {
      const ExtendOptions e = Following(o_.detect_extend, o_.separation);
      // Separation may flood detection's SCVD when it has the same radius and seed: the
      // major objects are whole components, so whole cells of it.
      const bool share = o_.separate && e.scvd_radius_voxels == o_.separation.radius_voxels &&
                         e.seed == o_.separation.seed;
      if (share) detected_ = std::make_unique<ScvdOfSet>();
      SM_ASSIGN_OR_RETURN(ExtendResult ext,
                          Extend(objects_, e, nullptr, progress_.Stage("detect"), detected_.get()));
      if (detected_ && detected_->scvd.num_generators() == 0) detected_.reset();
      SM_ASSIGN_OR_RETURN(Components merged, LabelComponents(ext.patch.set, Connectivity::k6));
      const std::vector<uint32_t> object_of = merged.VoxelLabels(ext.patch.set);
      std::map<uint32_t, uint64_t> original;
      std::vector<int32_t> label(refined_.size());
      uint64_t i = 0;
      refined_.ForEachVoxel([&](uint64_t, int32_t x, int32_t y, int32_t z) {
        const uint32_t obj = object_of[ext.patch.set.Find(x, y, z)];
        label[i++] = static_cast<int32_t>(obj);
        ++original[obj];
      });
      objects_.label = std::move(label);
      objects_ = objects_.Select([&](int32_t l) { return original[l] >= m_; });
      s->objects_after = objects_.CountLabels();
      s->added = ext.added;
      s->rounds = ext.rounds;
    } else {
      objects_ = objects_.Select([&](int32_t l) { return refined_components.sizes[l] >= m_; });
      s->objects_after = objects_.CountLabels();
    }
    s->voxels_before = refined_.size();
    s->voxels_after = objects_.set.size();
    s->removed = refined_.size() - objects_.set.size();
    return absl::OkStatus();
  }

  // 3. separate (Algorithm 2).
  absl::Status Separate(ExtractionStep* s) {
    pieces_ = objects_;
    s->objects_before = objects_.CountLabels();
    if (s->ran) {
      SeparationResult sep;
      if (detected_) {
        // The cells of major objects (a cell lies in one component, so its generator tells).
        const Scvd& scvd = detected_->scvd;
        std::vector<uint8_t> major(scvd.num_generators(), 0);
        for (uint32_t g = 0; g < major.size(); ++g) {
          const Index3& z = scvd.generators[g];
          major[g] = objects_.set.Contains(z.x, z.y, z.z);
        }
        SM_ASSIGN_OR_RETURN(
            sep, SeparateOver(*detected_, major, o_.separation, progress_.Stage("separate")));
        detected_.reset();
      } else {
        SM_ASSIGN_OR_RETURN(
            sep, sheetmesh::Separate(objects_.set, o_.separation, progress_.Stage("separate")));
      }
      pieces_ = std::move(sep.pieces);
      cells_ = std::move(sep.cells);
      Count(objects_.set, pieces_.set, s);
    } else {
      s->voxels_before = s->voxels_after = objects_.set.size();
    }
    s->objects_after = pieces_.CountLabels();
    separated_ = pieces_.set;
    return absl::OkStatus();
  }

  // Separation's cells (taken: recovery is their last use), with the cell of every voxel of
  // the pieces that remain.
  CellPlanes CellsOfPieces() {
    CellPlanes c;
    c.centroid = std::move(cells_.centroid);
    c.normal = std::move(cells_.normal);
    c.thickest = std::move(cells_.thickest);
    c.cell_of_voxel.reserve(pieces_.set.size());
    pieces_.set.ForEachVoxel([&](uint64_t, int32_t x, int32_t y, int32_t z) {
      c.cell_of_voxel.push_back(cells_.cell_of_voxel[separated_.Find(x, y, z)]);
    });
    return c;
  }

  // Where each voxel of the input went (the model is final and labelled).
  void Account(const LabelledVoxels& model) {
    ExtractionRetention& r = out_.retention;
    r.input_voxels = input_.size();
    const VoxelSet lost = Difference(input_, model.set);
    r.kept = r.input_voxels - lost.size();
    const VoxelSet by_refine = Difference(lost, refined_);
    const VoxelSet detected = Intersection(lost, refined_);
    const VoxelSet specks = Difference(detected, objects_.set);
    const VoxelSet separated = Intersection(detected, objects_.set);
    const VoxelSet at_crossings = Difference(separated, separated_);
    const VoxelSet minor = Intersection(separated, separated_);
    r.dropped_by_refine = by_refine.size();
    r.dropped_specks = specks.size();
    r.dropped_at_crossings = at_crossings.size();
    r.dropped_minor_pieces = minor.size();
    // The same, as one labelled set (the four are disjoint and make up `lost`).
    out_.dropped.set = lost;
    out_.dropped.label.reserve(lost.size());
    lost.ForEachVoxel([&](uint64_t, int32_t x, int32_t y, int32_t z) {
      DroppedBy why = DroppedBy::kMinorPiece;
      if (by_refine.Contains(x, y, z)) {
        why = DroppedBy::kRefine;
      } else if (specks.Contains(x, y, z)) {
        why = DroppedBy::kSpeck;
      } else if (at_crossings.Contains(x, y, z)) {
        why = DroppedBy::kCrossing;
      }
      out_.dropped.label.push_back(static_cast<int32_t>(why));
    });
    r.kept_per_piece.assign(model.CountLabels(), 0);
    model.set.ForEachVoxel([&](uint64_t i, int32_t x, int32_t y, int32_t z) {
      if (input_.Contains(x, y, z)) ++r.kept_per_piece[model.label[i]];
    });
  }

  // 4. remove the minor pieces.
  absl::Status RemoveMinor(ExtractionStep* s) {
    s->objects_before = pieces_.CountLabels();
    s->voxels_before = pieces_.set.size();
    if (s->ran) {
      std::map<int32_t, uint64_t> size;
      for (int32_t l : pieces_.label) ++size[l];
      pieces_ = pieces_.Select([&](int32_t l) { return size[l] >= m_; });
    }
    s->voxels_after = pieces_.set.size();
    s->removed = s->voxels_before - s->voxels_after;
    s->objects_after = pieces_.CountLabels();
    return absl::OkStatus();
  }

  // 5. recover, within the refined image.
  absl::Status Recover(ExtractionStep* s) {
    s->objects_before = pieces_.CountLabels();
    s->voxels_before = pieces_.set.size();
    if (s->ran) {
      const ExtendOptions e = Following(o_.recover_extend, o_.separation);
      // Separation's cells serve when they have recovery's radius: the pieces are made of
      // whole cells of them.
      const bool reuse = o_.separate && e.scvd_radius_voxels == o_.separation.radius_voxels &&
                         e.seed == o_.separation.seed;
      CellPlanes known;
      if (reuse) known = CellsOfPieces();
      SM_ASSIGN_OR_RETURN(ExtendResult ext, Regrow(pieces_, e, refined_, reuse ? &known : nullptr,
                                                   progress_.Stage("recover")));
      s->rounds = ext.rounds;
      s->added = ext.added;
      pieces_ = std::move(ext.patch);
    }
    s->voxels_after = pieces_.set.size();
    s->objects_after = pieces_.CountLabels();
    return absl::OkStatus();
  }

  absl::StatusOr<ExtractionResult> Run() {
    out_.min_object_voxels = m_;
    SM_RETURN_IF_ERROR(Step("refine", o_.refine, [&](ExtractionStep* s) { return Refine(s); }));
    if (refined_.empty()) {
      return absl::InvalidArgumentError(
          "refinement erased the whole sheet phase; lower refine.open_radius");
    }
    SM_RETURN_IF_ERROR(Step("detect", o_.detect, [&](ExtractionStep* s) { return Detect(s); }));
    if (objects_.set.empty()) {
      return absl::InvalidArgumentError(
          absl::StrCat("no object has M = ", m_,
                       " voxels or more; lower M, or mesh every sheet voxel without the "
                       "extraction (extract = false)"));
    }
    SM_RETURN_IF_ERROR(
        Step("separate", o_.separate, [&](ExtractionStep* s) { return Separate(s); }));
    SM_RETURN_IF_ERROR(
        Step("remove_minor", o_.remove_minor, [&](ExtractionStep* s) { return RemoveMinor(s); }));
    if (pieces_.set.empty()) {
      return absl::InvalidArgumentError(
          absl::StrCat("no piece has M = ", m_,
                       " voxels or more after separation; lower M or raise separate.D_ang, or "
                       "mesh every sheet voxel without the extraction (extract = false)"));
    }
    SM_RETURN_IF_ERROR(Step("recover", o_.recover, [&](ExtractionStep* s) { return Recover(s); }));
    pieces_.RelabelBySize();
    Account(pieces_);
    out_.model = std::move(pieces_);
    out_.model_voxels = out_.model.set.size();
    out_.pieces = out_.model.CountLabels();
    return std::move(out_);
  }

 private:
  const VoxelSet& input_;
  const ExtractionOptions& o_;
  const Progress& progress_;
  const uint64_t m_;
  VoxelSet refined_;
  LabelledVoxels objects_;
  LabelledVoxels pieces_;
  VoxelSet separated_;                   // the pieces as separation left them
  CellPlanes cells_;                     // separation's cells over them
  std::unique_ptr<ScvdOfSet> detected_;  // detection's SCVD, for separation
  ExtractionResult out_;
};

}  // namespace

absl::StatusOr<ExtractionResult> ExtractFeatures(const VoxelSet& input, const ExtractionOptions& o,
                                                 const Progress& progress) {
  if (input.empty())
    return absl::InvalidArgumentError("feature extraction of an empty sheet phase");
  if (o.refine_close_radius < 0 || o.refine_open_radius < 0) {
    return absl::InvalidArgumentError(absl::StrCat("refine radii ", o.refine_close_radius, " and ",
                                                   o.refine_open_radius, " must not be negative"));
  }
  // The lengths left at 0 follow the measured mean thickness t̄ of the sheet phase.
  ExtractionOptions scaled = o;
  std::vector<DerivedValue> derived;
  double mean_thickness = 0;
  if (o.separation.radius_voxels == 0 || o.min_object_voxels == 0) {
    SM_ASSIGN_OR_RETURN(std::vector<uint16_t> tau, ComputeThickness(input));
    mean_thickness = SummarizeThickness(tau).mean;
  }
  // Separation's cells must be wider than the sheet is thick, or they stack across it and
  // their triangles fold (paper §3: r near the thickness breaks a sheet into pieces).
  if (o.separation.radius_voxels == 0) {
    scaled.separation.radius_voxels = std::max(kSeparationRadiusFloor, mean_thickness / 2);
    derived.push_back({"separate.r", scaled.separation.radius_voxels,
                       absl::StrCat("max(5, t/2) with the mean thickness t = ", mean_thickness)});
  } else {
    derived.push_back({"separate.r", o.separation.radius_voxels, "set"});
  }
  // M: three cells of the separation SCVD; a piece smaller than that cannot give a triangle.
  uint64_t m = o.min_object_voxels;
  if (m == 0) {
    m = static_cast<uint64_t>(
        std::ceil(3 * CellVolume(mean_thickness, scaled.separation.radius_voxels)));
    derived.push_back(
        {"M", double(m),
         absl::StrCat("3 t (1 + 2 r (r - 1)) with t = ", mean_thickness, ", r = separate.r")});
  } else {
    derived.push_back({"M", double(m), "set"});
  }
  // Detection's cylinder follows the cells: from a rim cell's centroid it must reach past
  // the rim to bridge a gap, and a cell's centroid lies about r inside it.
  const double r_sep = scaled.separation.radius_voxels;
  ExtendOptions& detect = scaled.detect_extend;
  const bool t_set = detect.half_thickness_voxels > 0, cap_set = detect.radius_voxels > 0;
  if (!cap_set) {
    detect.radius_voxels =
        std::max(kDetectRadiusPerRadius * r_sep, t_set ? detect.half_thickness_voxels : 0.0);
  }
  if (!t_set) {
    detect.half_thickness_voxels =
        std::min(kDetectHalfThicknessPerRadius * r_sep, detect.radius_voxels);
  }
  derived.push_back({"detect.t", detect.half_thickness_voxels,
                     t_set ? "set" : "0.3 r with r = separate.r (1.5 at the paper's r = 5)"});
  derived.push_back({"detect.R", detect.radius_voxels,
                     cap_set ? "set" : "1.4 r with r = separate.r (7 at the paper's r = 5)"});
  for (const auto& [key, radius] : {std::pair{"refine.close_radius", o.refine_close_radius},
                                    std::pair{"refine.open_radius", o.refine_open_radius}}) {
    derived.push_back({key, double(radius),
                       "as given, not scaled (0: none; a closing adds voxels the image does not "
                       "have, an opening erases sheets thinner than twice its radius)"});
  }
  derived.push_back({"recover.t", o.recover_extend.half_thickness_voxels,
                     "set: the least half-thickness; each cell's plane takes max(t, half its "
                     "thickest run + 0.5), the local thickness"});
  SM_ASSIGN_OR_RETURN(ExtractionResult r, Workflow(input, scaled, progress, m).Run());
  r.derived = std::move(derived);
  return r;
}

}  // namespace sheetmesh
