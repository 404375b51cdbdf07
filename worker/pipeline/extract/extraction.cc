#include "worker/pipeline/extract/extraction.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/status_macros.h"
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

// An extension's SCVD radius of 0 follows the separation's.
ExtendOptions Following(ExtendOptions e, const SeparationOptions& separation) {
  if (e.scvd_radius_voxels == 0) e.scvd_radius_voxels = separation.radius_voxels;
  return e;
}

}  // namespace

absl::StatusOr<ExtractionResult> ExtractFeatures(const VoxelSet& input, const ExtractionOptions& o,
                                                 const Progress& progress) {
  if (input.empty())
    return absl::InvalidArgumentError("feature extraction of an empty sheet phase");
  if (o.refine_close_radius < 0 || o.refine_open_radius < 0) {
    return absl::InvalidArgumentError(absl::StrCat("refine radii ", o.refine_close_radius, " and ",
                                                   o.refine_open_radius, " must not be negative"));
  }
  ExtractionResult out;
  // M defaults to three cells of the separation SCVD: a piece smaller than that cannot
  // give a triangle.
  uint64_t m = o.min_object_voxels;
  if (m == 0) {
    SM_ASSIGN_OR_RETURN(std::vector<uint16_t> tau, ComputeThickness(input));
    m = static_cast<uint64_t>(
        std::ceil(3 * CellVolume(SummarizeThickness(tau).mean, o.separation.radius_voxels)));
  }
  out.min_object_voxels = m;

  // 1. refine
  VoxelSet refined = input;
  {
    ExtractionStep s{"refine"};
    const absl::Time start = absl::Now();
    if (o.refine) {
      s.ran = true;
      SM_ASSIGN_OR_RETURN(s.objects_before, CountComponents(input));
      if (o.refine_close_radius > 0) {
        SM_ASSIGN_OR_RETURN(refined, Close(refined, o.refine_close_radius, Connectivity::k6,
                                           progress.Stage("refine")));
      }
      if (o.refine_open_radius > 0) {
        SM_ASSIGN_OR_RETURN(refined, Open(refined, o.refine_open_radius, Connectivity::k6,
                                          progress.Stage("refine")));
      }
      SM_ASSIGN_OR_RETURN(s.objects_after, CountComponents(refined));
      Count(input, refined, &s);
    }
    s.seconds = Since(start);
    if (s.ran) SM_RETURN_IF_ERROR(progress.Stage(s.name).Update(1.0));
    out.steps.push_back(s);
  }
  if (refined.empty()) {
    return absl::InvalidArgumentError(
        "refinement erased the whole sheet phase; lower refine_open_radius");
  }
  SM_ASSIGN_OR_RETURN(Components refined_components, LabelComponents(refined, Connectivity::k6));

  // 2. detect: objects are the components after extending; a major object has at least M
  // voxels of the image. Its fragments are kept, labelled as one object; the bridging
  // voxels are not (the model keeps to the image).
  LabelledVoxels objects = LabelByComponents(refined, refined_components);
  {
    ExtractionStep s{"detect"};
    const absl::Time start = absl::Now();
    s.objects_before = refined_components.count();
    if (o.detect) {
      s.ran = true;
      SM_ASSIGN_OR_RETURN(ExtendResult ext,
                          Extend(objects, Following(o.detect_extend, o.separation), nullptr, progress.Stage("detect")));
      SM_ASSIGN_OR_RETURN(Components merged, LabelComponents(ext.patch.set, Connectivity::k6));
      const std::vector<uint32_t> object_of = merged.VoxelLabels(ext.patch.set);
      std::map<uint32_t, uint64_t> original;
      std::vector<int32_t> label(refined.size());
      uint64_t i = 0;
      refined.ForEachVoxel([&](uint64_t, int32_t x, int32_t y, int32_t z) {
        const uint32_t obj = object_of[ext.patch.set.Find(x, y, z)];
        label[i++] = static_cast<int32_t>(obj);
        ++original[obj];
      });
      objects.label = std::move(label);
      objects = objects.Select([&](int32_t l) { return original[l] >= m; });
      s.objects_after = objects.CountLabels();
      s.added = ext.added;
    } else {
      objects = objects.Select([&](int32_t l) { return refined_components.sizes[l] >= m; });
      s.objects_after = objects.CountLabels();
    }
    s.voxels_before = refined.size();
    s.voxels_after = objects.set.size();
    s.removed = refined.size() - objects.set.size();
    s.seconds = Since(start);
    if (s.ran) SM_RETURN_IF_ERROR(progress.Stage(s.name).Update(1.0));
    out.steps.push_back(s);
  }
  if (objects.set.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat("no object has M = ", m, " voxels or more; lower min_object_voxels"));
  }

  // 3. separate
  LabelledVoxels pieces = objects;
  {
    ExtractionStep s{"separate"};
    const absl::Time start = absl::Now();
    s.objects_before = objects.CountLabels();
    if (o.separate) {
      s.ran = true;
      SM_ASSIGN_OR_RETURN(SeparationResult sep,
                          Separate(objects.set, o.separation, progress.Stage("separate")));
      pieces = std::move(sep.pieces);
      Count(objects.set, pieces.set, &s);
    } else {
      s.voxels_before = s.voxels_after = objects.set.size();
    }
    s.objects_after = pieces.CountLabels();
    s.seconds = Since(start);
    if (s.ran) SM_RETURN_IF_ERROR(progress.Stage(s.name).Update(1.0));
    out.steps.push_back(s);
  }

  // 4. remove minor
  {
    ExtractionStep s{"remove_minor"};
    const absl::Time start = absl::Now();
    s.objects_before = pieces.CountLabels();
    s.voxels_before = pieces.set.size();
    if (o.remove_minor) {
      s.ran = true;
      std::map<int32_t, uint64_t> size;
      for (int32_t l : pieces.label) ++size[l];
      pieces = pieces.Select([&](int32_t l) { return size[l] >= m; });
    }
    s.voxels_after = pieces.set.size();
    s.removed = s.voxels_before - s.voxels_after;
    s.objects_after = pieces.CountLabels();
    s.seconds = Since(start);
    if (s.ran) SM_RETURN_IF_ERROR(progress.Stage(s.name).Update(1.0));
    out.steps.push_back(s);
  }
  if (pieces.set.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat("no piece has M = ", m,
                     " voxels or more after separation; lower min_object_voxels or "
                     "raise D_ang"));
  }

  // 5. recover, within the refined image.
  {
    ExtractionStep s{"recover"};
    const absl::Time start = absl::Now();
    s.objects_before = pieces.CountLabels();
    s.voxels_before = pieces.set.size();
    if (o.recover) {
      s.ran = true;
      SM_ASSIGN_OR_RETURN(ExtendResult ext,
                          Extend(pieces, Following(o.recover_extend, o.separation), &refined, progress.Stage("recover")));
      s.added = ext.added;
      pieces = std::move(ext.patch);
    }
    s.voxels_after = pieces.set.size();
    s.objects_after = pieces.CountLabels();
    s.seconds = Since(start);
    if (s.ran) SM_RETURN_IF_ERROR(progress.Stage(s.name).Update(1.0));
    out.steps.push_back(s);
  }
  pieces.RelabelBySize();
  out.model = std::move(pieces);
  out.model_voxels = out.model.set.size();
  out.pieces = out.model.CountLabels();
  return out;
}

nlohmann::json ExtractionStep::Fields() const {
  return {{"step", name},
          {"ran", ran},
          {"voxels_before", voxels_before},
          {"voxels_after", voxels_after},
          {"added", added},
          {"removed", removed},
          {"objects_before", objects_before},
          {"objects_after", objects_after},
          {"seconds", seconds}};
}

nlohmann::json ExtractionSummary::Fields() const {
  nlohmann::json s = nlohmann::json::array();
  for (const ExtractionStep& step : steps) s.push_back(step.Fields());
  return {{"steps", s},
          {"min_object_voxels", min_object_voxels},
          {"model_voxels", model_voxels},
          {"pieces", pieces}};
}

}  // namespace sheetmesh
