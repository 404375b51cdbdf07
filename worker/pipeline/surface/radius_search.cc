#include "worker/pipeline/surface/radius_search.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/similarity/similarity.h"

namespace sheetmesh {
namespace {

// Integer radii from lo to hi, every one up to 10, then growing by about 15% per step.
std::vector<double> Ladder(double lo, double hi) {
  std::vector<double> out;
  double r = std::max(1.0, std::ceil(lo));
  while (r <= hi) {
    out.push_back(r);
    r = r < 10 ? r + 1 : std::max(r + 1, std::round(r * 1.15));
  }
  if (out.empty() || out.back() < hi) out.push_back(std::floor(hi));
  return out;
}

class Evaluator {
 public:
  Evaluator(const SheetAnalysis& sheet, const SurfaceOptions& surface, PrismHeight height,
            const Progress& progress)
      : sheet_(sheet), surface_(surface), height_(height), progress_(progress) {}

  absl::StatusOr<RadiusTrial> Eval(double r) {
    auto it = done_.find(r);
    if (it != done_.end()) return it->second;
    SM_RETURN_IF_ERROR(progress_.Update(0.0, absl::StrCat("trying r = ", r)));
    SurfaceOptions o = surface_;
    o.scvd.radius_voxels = r;
    SM_ASSIGN_OR_RETURN(SurfaceResult s, BuildSurface(sheet_, o));
    RadiusTrial t;
    t.radius = r;
    t.triangles = s.mesh.num_faces();
    if (t.triangles > 0) {
      SM_ASSIGN_OR_RETURN(VoxelSet model, VoxelizePrisms(s.mesh, sheet_.set.dims(), height_));
      t.similarity = ScoreModel(model, sheet_.set).similarity;
    } else {
      t.similarity = 0.0;
    }
    done_[r] = t;
    trials_.push_back(t);
    return t;
  }
  std::vector<RadiusTrial> trials() const { return trials_; }

 private:
  const SheetAnalysis& sheet_;
  SurfaceOptions surface_;
  PrismHeight height_;
  Progress progress_;
  std::map<double, RadiusTrial> done_;
  std::vector<RadiusTrial> trials_;
};

}  // namespace

absl::StatusOr<RadiusChoice> SearchRadius(const SheetAnalysis& sheet, const SurfaceOptions& surface,
                                          const RadiusSearchOptions& options,
                                          const Progress& progress) {
  const Dims& d = sheet.set.dims();
  const double hi = options.max_radius_voxels > 0
                        ? options.max_radius_voxels
                        : std::max(3.0, std::max({d.nx, d.ny, d.nz}) / 4.0);
  const double lo = options.min_radius_voxels;
  if (!(lo > 0) || !(hi >= lo)) {
    return absl::InvalidArgumentError(
        absl::StrCat("radius search range [", lo, ", ", hi, "] must be positive and not inverted"));
  }
  if (options.goal == RadiusGoal::kTargetSimilarity && !(options.target_similarity <= 1.0)) {
    return absl::InvalidArgumentError(absl::StrCat("target similarity ", options.target_similarity,
                                                   " is above 1, the best possible"));
  }
  Evaluator eval(sheet, surface, options.height, progress);
  const std::vector<double> ladder = Ladder(lo, hi);
  RadiusChoice choice;
  RadiusTrial best;
  best.similarity = -1e300;
  int since_best = 0;
  // The last r that reached the target, and the first r above it that did not.
  double good = -1, bad = -1;
  int misses = 0;
  for (size_t i = 0; i < ladder.size(); ++i) {
    SM_ASSIGN_OR_RETURN(RadiusTrial t, eval.Eval(ladder[i]));
    if (t.similarity > best.similarity) {
      best = t;
      since_best = 0;
    } else {
      ++since_best;
    }
    if (options.goal == RadiusGoal::kBestSimilarity) {
      if (since_best >= options.patience) break;
    } else {
      if (t.similarity >= options.target_similarity) {
        good = t.radius;
        bad = -1;
        misses = 0;
      } else if (good > 0) {
        if (bad < 0) bad = t.radius;
        if (++misses >= options.patience) break;
      }
      // Still rising towards the target, or not reached yet: keep climbing while it helps.
      if (good < 0 && since_best >= options.patience) break;
    }
  }
  if (options.goal == RadiusGoal::kBestSimilarity) {
    // Refine between the ladder steps around the best.
    const auto it = std::find(ladder.begin(), ladder.end(), best.radius);
    const double below = it == ladder.begin() ? best.radius : *(it - 1);
    const double above = it + 1 == ladder.end() ? best.radius : *(it + 1);
    for (double r = below + 1; r < above; r += 1) {
      if (r == best.radius) continue;
      SM_ASSIGN_OR_RETURN(RadiusTrial t, eval.Eval(r));
      if (t.similarity > best.similarity) best = t;
    }
    choice.radius = best.radius;
  } else if (good < 0) {
    choice.radius = best.radius;
    choice.target_reached = false;
  } else {
    // Bisect the integers between the last success and the first failure above it.
    if (bad > 0) {
      double a = good, b = bad;
      while (b - a > 1) {
        const double m = std::floor((a + b) / 2);
        SM_ASSIGN_OR_RETURN(RadiusTrial t, eval.Eval(m));
        if (t.similarity >= options.target_similarity) {
          a = m;
        } else {
          b = m;
        }
      }
      good = a;
    }
    choice.radius = good;
  }
  choice.trials = eval.trials();
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return choice;
}

}  // namespace sheetmesh
