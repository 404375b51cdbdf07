#include "worker/pipeline/surface/radius_search.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/similarity/similarity.h"
#include "worker/pipeline/surface/error_density.h"

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

// Builds and scores the surface at each r tried. The surfaces the search may choose are
// held (at most two, besides the last one built), so the chosen one is handed back, not
// built again.
class Evaluator {
 public:
  // Which candidate a held surface is.
  enum Slot { kBest, kOther, kSlots };

  Evaluator(const SheetAnalysis& sheet, const SurfaceOptions& surface,
            std::span<const int32_t> piece_of_voxel, PrismHeight height, const Progress& progress)
      : sheet_(sheet),
        surface_(surface),
        piece_of_voxel_(piece_of_voxel),
        height_(height),
        progress_(progress) {}

  // Counts only, without the similarity, when `score` is false.
  // With `decimate_to`, the mesh is decimated to that many faces.
  absl::StatusOr<RadiusTrial> Eval(double r, bool score = true, uint64_t decimate_to = 0) {
    // A trial made before serves unless it was only counted and a score is wanted now.
    auto it = done_.find({r, decimate_to});
    if (it != done_.end() && (it->second.scored || !score)) return it->second;
    SM_RETURN_IF_ERROR(progress_.Update(0.0, absl::StrCat("trying r = ", r)));
    SurfaceOptions o = Options(r, decimate_to);
    // Counting needs no heights: the fits change no face.
    if (!score) o.fit_walls = false;
    auto built = std::make_shared<Built>();
    built->radius = r;
    built->decimate_to = decimate_to;
    built->whole = o.fit_walls == surface_.fit_walls;
    SM_ASSIGN_OR_RETURN(built->surface, BuildRequestedSurface(sheet_, o, piece_of_voxel_));
    const TriangleMesh& mesh = built->surface.mesh;
    RadiusTrial t;
    t.radius = r;
    t.triangles = mesh.num_faces();
    t.scored = score;
    if (t.triangles > 0 && score) {
      SM_ASSIGN_OR_RETURN(VoxelSet model, VoxelizePrisms(mesh, sheet_.set.dims(), height_));
      t.similarity = ScoreModel(model, sheet_.set).similarity;
    } else {
      t.similarity = 0.0;
    }
    t.decimated_to = decimate_to;
    done_[{r, decimate_to}] = t;
    trials_.push_back(t);
    last_ = std::move(built);
    return t;
  }

  // Keeps the surface of trial `t`, if it was the last built, as the candidate `slot`
  // (dropping the one held there).
  void Hold(Slot slot, const RadiusTrial& t) {
    if (last_ && last_->radius == t.radius && last_->decimate_to == t.decimated_to) {
      held_[slot] = last_;
    }
  }

  // The surface at (r, decimate_to) with the caller's settings: held or last built, else
  // built now (a trial that was only counted was built without its heights).
  absl::StatusOr<SurfaceResult> Take(double r, uint64_t decimate_to) {
    for (const std::shared_ptr<Built>& b : {held_[kBest], held_[kOther], last_}) {
      if (b && b->whole && b->radius == r && b->decimate_to == decimate_to) {
        SurfaceResult out = std::move(b->surface);
        held_ = {};
        last_.reset();
        return out;
      }
    }
    held_ = {};
    last_.reset();
    return BuildRequestedSurface(sheet_, Options(r, decimate_to), piece_of_voxel_);
  }

  std::vector<RadiusTrial> trials() const { return trials_; }

 private:
  struct Built {
    double radius = 0;
    uint64_t decimate_to = 0;
    bool whole = false;  // built with the caller's settings (heights fitted if they fit them)
    SurfaceResult surface;
  };

  SurfaceOptions Options(double r, uint64_t decimate_to) const {
    SurfaceOptions o = surface_;
    o.scvd.radius_voxels = r;
    o.triangles = decimate_to;
    return o;
  }

  const SheetAnalysis& sheet_;
  SurfaceOptions surface_;
  std::span<const int32_t> piece_of_voxel_;
  PrismHeight height_;
  Progress progress_;
  std::map<std::pair<double, uint64_t>, RadiusTrial> done_;
  std::vector<RadiusTrial> trials_;
  std::shared_ptr<Built> last_;
  std::array<std::shared_ptr<Built>, kSlots> held_;
};

// kTriangles: the count falls about as r^-2; a secant in log r, log count from two trials
// on, until a count within 5% of the target.
absl::StatusOr<RadiusChoice> SearchTriangles(Evaluator& eval, double start, double lo, double hi,
                                             uint64_t target, bool coarsest_below) {
  constexpr int kMaxTrials = 14;
  auto within = [&](uint64_t n) {
    return std::abs(double(n) - double(target)) <= kTriangleTolerance * target;
  };
  std::vector<RadiusTrial> seen;
  double r = std::clamp(start, lo, hi);
  RadiusChoice choice;
  for (int i = 0; i < kMaxTrials; ++i) {
    SM_ASSIGN_OR_RETURN(RadiusTrial t, eval.Eval(r, false));
    seen.push_back(t);
    if (within(t.triangles)) break;
    // The two trials nearest the target in log count give the slope (−2 until there are two).
    double slope = -2;
    std::vector<RadiusTrial> near = seen;
    std::sort(near.begin(), near.end(), [&](const RadiusTrial& a, const RadiusTrial& b) {
      return std::abs(std::log(double(std::max<uint64_t>(a.triangles, 1)) / target)) <
             std::abs(std::log(double(std::max<uint64_t>(b.triangles, 1)) / target));
    });
    const RadiusTrial& a = near[0];
    if (near.size() >= 2 && near[1].radius != a.radius && near[1].triangles != a.triangles &&
        a.triangles > 0 && near[1].triangles > 0) {
      slope =
          std::log(double(near[1].triangles) / a.triangles) / std::log(near[1].radius / a.radius);
      if (!(slope < -0.5) || !(slope > -8)) slope = -2;
    }
    double next =
        a.radius * std::pow(double(target) / std::max<uint64_t>(a.triangles, 1), 1 / slope);
    next = std::clamp(next, lo, hi);
    auto tried = [&](double x) {
      return std::any_of(seen.begin(), seen.end(),
                         [&](const RadiusTrial& s) { return std::abs(s.radius - x) < 1e-3 * x; });
    };
    // Tried already (at a bound, or between two counts the target falls between): halfway
    // from the nearest, or stop.
    if (tried(next)) next = std::clamp(0.5 * (next + a.radius), lo, hi);
    if (tried(next)) break;
    r = next;
  }
  const RadiusTrial* best = &seen[0];
  for (const RadiusTrial& t : seen) {
    if (std::abs(double(t.triangles) - target) < std::abs(double(best->triangles) - target)) {
      best = &t;
    }
  }
  // Fewer than the coarsest mesh has: the outline needs that many.
  const auto coarsest = std::max_element(seen.begin(), seen.end(),
                                         [](auto& x, auto& y) { return x.radius < y.radius; });
  if (coarsest_below && !within(best->triangles) && double(target) < coarsest->triangles) {
    choice.radius = coarsest->radius;  // the decimation goes on from there
    return choice;
  }
  if (!within(best->triangles) && double(target) < best->triangles && coarsest->radius >= hi) {
    return absl::InvalidArgumentError(
        absl::StrCat("triangles = ", target,
                     " is below the fewest this sheet can be meshed with: ", coarsest->triangles,
                     " at the largest r tried, ", hi, " (raise triangles or radius_search.r_max)"));
  }
  choice.radius = best->radius;
  choice.target_reached = within(best->triangles);
  if (!choice.target_reached) {
    choice.message =
        absl::StrCat("no r gave ", target, " triangles within ", 100 * kTriangleTolerance,
                     "%: the nearest, ", best->triangles, ", at r = ", best->radius);
  }
  return choice;
}

}  // namespace

namespace {

absl::StatusOr<RadiusChoice> Search(Evaluator& eval, const SheetAnalysis& sheet,
                                    const SurfaceOptions& surface,
                                    const RadiusSearchOptions& options) {
  const Dims& d = sheet.set.dims();
  const double hi = options.max_radius_voxels > 0
                        ? options.max_radius_voxels
                        : std::max(3.0, std::max({d.nx, d.ny, d.nz}) / 4.0);
  const double lo = options.min_radius_voxels;
  if (!(lo > 0) || !(hi >= lo)) {
    return absl::InvalidArgumentError(
        absl::StrCat("radius search range [", lo, ", ", hi, "] must be positive and not inverted"));
  }
  if (options.goal == RadiusGoal::kTargetSimilarity &&
      !(options.target_similarity > 0 && options.target_similarity < 1.0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("target_similarity = ", options.target_similarity,
                     " must be in (0, 1): 1 is a perfect model"));
  }
  if (options.goal == RadiusGoal::kTriangles && options.triangles == 0) {
    return absl::InvalidArgumentError("triangles = 0: a mesh needs at least one triangle");
  }
  if (options.goal == RadiusGoal::kTriangles) {
    const uint64_t n = options.triangles;
    absl::StatusOr<RadiusChoice> plain =
        SearchTriangles(eval, surface.scvd.radius_voxels, lo, hi, n, false);
    if (!options.decimate) {
      return plain;
    }
    if (!plain.ok() && plain.status().code() != absl::StatusCode::kInvalidArgument) {
      return plain.status();
    }
    // The dual mesh with about kOversample times the count, decimated to it, against the
    // dual mesh at the count: the one that scores higher (a plain mesh below the count's
    // reach does not compete).
    SM_ASSIGN_OR_RETURN(RadiusChoice fine,
                        SearchTriangles(eval, plain.ok() ? plain->radius : hi, lo, hi,
                                        static_cast<uint64_t>(std::ceil(kOversample * n)), true));
    SM_ASSIGN_OR_RETURN(RadiusTrial decimated, eval.Eval(fine.radius, true, n));
    eval.Hold(Evaluator::kOther, decimated);
    RadiusChoice c = fine;
    c.decimated_to = n;
    c.target_reached = std::abs(double(decimated.triangles) - n) <= kTriangleTolerance * n;
    if (!c.target_reached) {
      c.message =
          decimated.triangles > n
              ? absl::StrCat("decimation stopped at ", decimated.triangles, " triangles")
              : absl::StrCat("no r gave ", n, " triangles within ", 100 * kTriangleTolerance,
                             "%: the finest, ", decimated.triangles, ", at r = ", c.radius);
    }
    if (plain.ok() && plain->target_reached) {
      SM_ASSIGN_OR_RETURN(RadiusTrial t, eval.Eval(plain->radius, true));
      if (t.similarity >= decimated.similarity || !c.target_reached) c = *plain;
    }
    return c;
  }
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
      eval.Hold(Evaluator::kBest, t);
      since_best = 0;
    } else {
      ++since_best;
    }
    if (options.goal == RadiusGoal::kBestSimilarity) {
      if (since_best >= options.patience) break;
    } else {
      if (t.similarity >= options.target_similarity) {
        good = t.radius;
        eval.Hold(Evaluator::kOther, t);
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
      if (t.similarity > best.similarity) {
        best = t;
        eval.Hold(Evaluator::kBest, t);
      }
    }
    choice.radius = best.radius;
  } else if (good < 0) {
    choice.radius = best.radius;
    choice.target_reached = false;
    choice.message =
        absl::StrCat("no r reached similarity ", options.target_similarity,
                     ": the best mesh found, at r = ", best.radius, ", scores ", best.similarity);
  } else {
    // Bisect the integers between the last success and the first failure above it.
    if (bad > 0) {
      double a = good, b = bad;
      while (b - a > 1) {
        const double m = std::floor((a + b) / 2);
        SM_ASSIGN_OR_RETURN(RadiusTrial t, eval.Eval(m));
        if (t.similarity >= options.target_similarity) {
          a = m;
          eval.Hold(Evaluator::kOther, t);
        } else {
          b = m;
        }
      }
      good = a;
    }
    choice.radius = good;
  }
  return choice;
}

}  // namespace

absl::StatusOr<RadiusSearchResult> SearchRadius(const SheetAnalysis& sheet,
                                                const SurfaceOptions& surface,
                                                const RadiusSearchOptions& options,
                                                std::span<const int32_t> piece_of_voxel,
                                                const Progress& progress) {
  Evaluator eval(sheet, surface, piece_of_voxel, options.height, progress);
  RadiusSearchResult out;
  if (options.goal == RadiusGoal::kTriangles && surface.method == SurfaceMethod::kMid) {
    // The mid-surface is decimated to any count: no r to search, the count given is made.
    out.choice.radius = surface.scvd.radius_voxels;
    out.choice.decimated_to = options.triangles;
    SM_ASSIGN_OR_RETURN(out.surface, eval.Take(out.choice.radius, out.choice.decimated_to));
    const double faces = static_cast<double>(out.surface.mesh.num_faces());
    out.choice.target_reached = std::abs(faces - options.triangles) <= 0.05 * options.triangles;
    if (!out.choice.target_reached) {
      out.choice.message =
          absl::StrCat("the mid-surface gives ", out.surface.mesh.num_faces(), " triangles where ",
                       options.triangles, " were asked: its outline and junctions need them");
    }
    SM_RETURN_IF_ERROR(progress.Update(1.0));
    return out;
  }
  SM_ASSIGN_OR_RETURN(out.choice, Search(eval, sheet, surface, options));
  out.choice.trials = eval.trials();
  SM_ASSIGN_OR_RETURN(out.surface, eval.Take(out.choice.radius, out.choice.decimated_to));
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return out;
}

}  // namespace sheetmesh
