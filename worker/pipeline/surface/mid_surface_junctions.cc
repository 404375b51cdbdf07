#include "worker/pipeline/surface/mid_surface_junctions.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <tuple>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/surface/mid_surface_lines.h"
#include "worker/pipeline/voxel/components.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A chart whose plane lies between those of two charts it meets, closer to each than they
// are to one another and within kBandDegrees of both, is where two sheets ran together (the
// runs of a shallow crossing merged), not a sheet: its voxels are the junction's.
constexpr double kBandDegrees = 20;

bool MergeBand(int32_t c, const std::vector<std::unique_ptr<Chart>>& charts,
               const std::map<std::pair<int32_t, int32_t>, Contact>& contacts,
               const JunctionOptions& options) {
  auto degrees = [&](int32_t a, int32_t b) {
    const double cosine =
        std::min(1.0, std::abs(Dot(charts[a]->info().normal, charts[b]->info().normal)));
    return std::acos(cosine) * 180 / kPi;
  };
  std::vector<int32_t> partners;
  for (const auto& [pair, contact] : contacts) {
    if (contact.count < options.min_contact) continue;
    if (pair.first == c) partners.push_back(pair.second);
    if (pair.second == c) partners.push_back(pair.first);
  }
  for (size_t p = 0; p < partners.size(); ++p) {
    for (size_t q = p + 1; q < partners.size(); ++q) {
      // A band is a strip along the junction, about as large as the sheets on either side
      // at most (at 15 degrees a merge of two 3-voxel sheets is 23 voxels wide): a sheet
      // more than twice as large as one of them is a sheet (the fragments a junction's cut
      // leaves beside it may be tilted between it and the other).
      const uint64_t own = charts[c]->info().voxels;
      if (own > 2 * charts[partners[p]]->info().voxels ||
          own > 2 * charts[partners[q]]->info().voxels) {
        continue;
      }
      const double between = degrees(partners[p], partners[q]);
      const double to_p = degrees(c, partners[p]), to_q = degrees(c, partners[q]);
      const double off = std::max(to_p, to_q);
      // A band lies along both (they ran together there at a shallow angle): its plane is
      // nearer each than they are to one another, or lies in their pencil strictly between
      // them (its angles to the two sum to theirs, as the plane of two merged sheets' voxels
      // does, however unequal their shares); a sheet that meets two others steeply is a
      // sheet of a network, whatever the angles between, and one along either is that
      // sheet's continuation.
      const bool nearer = between > off + 3;
      const bool in_pencil = to_p + to_q <= between + 3 && std::min(to_p, to_q) >= 2;
      // A small one in the pencil is a band however unequal its angles to the two (at 30
      // degrees the merge of two sheets may lie 24 degrees from one of them).
      const bool small = 4 * own <= std::min(charts[partners[p]]->info().voxels,
                                             charts[partners[q]]->info().voxels);
      if ((nearer || in_pencil) && between > options.min_degrees &&
          (off <= kBandDegrees || (in_pencil && small))) {
        return true;
      }
    }
  }
  return false;
}

// Columns beyond a line along its extent that make a chart run on across it (not end there).
constexpr uint64_t kPassing = 16;

// A chart far smaller than every chart it meets (a twentieth or less) is a fragment the
// separation cut off at their junction, not a sheet: a chart of it would meet them in lines
// of its own beside the true one.
constexpr uint64_t kFragmentRatio = 20;

bool Fragment(int32_t c, const std::vector<std::unique_ptr<Chart>>& charts,
              const std::map<std::pair<int32_t, int32_t>, Contact>& contacts,
              const JunctionOptions& options) {
  bool meets = false;
  for (const auto& [pair, contact] : contacts) {
    if (contact.count < options.min_contact || (pair.first != c && pair.second != c)) continue;
    const int32_t other = pair.first == c ? pair.second : pair.first;
    if (charts[c]->info().voxels * kFragmentRatio > charts[other]->info().voxels) return false;
    meets = true;
  }
  return meets;
}

// The chart other than `self` that `voxels` touch (6-neighbours) whose plane is within
// `degrees` of theirs and that `may_join` allows, the one they touch most; -1 when none.
int32_t CoplanarNeighbour(const std::vector<Index3>& voxels, int32_t self,
                          const std::vector<std::unique_ptr<Chart>>& charts, const Dims& dims,
                          double degrees, const std::function<bool(int32_t)>& may_join) {
  absl::flat_hash_set<uint64_t> own;
  std::vector<Vec3> points;
  for (const Index3& p : voxels) {
    own.insert(VoxelKey(p, dims));
    points.emplace_back(p.x, p.y, p.z);
  }
  Vec3 centroid, normal;
  FitPlanePoints(points, &centroid, &normal);
  int32_t best = -1;
  uint64_t most = 0;
  for (int32_t k = 0; k < static_cast<int32_t>(charts.size()); ++k) {
    if (k == self || !charts[k]) continue;
    if (std::abs(Dot(charts[k]->info().normal, normal)) < std::cos(degrees * kPi / 180)) continue;
    if (!may_join(k)) continue;
    uint64_t touching = 0;
    charts[k]->ForEachVoxel([&](const Index3& p, bool) {
      for (const auto& s : kStep) {
        if (own.contains(VoxelKey(Index3{p.x + s[0], p.y + s[1], p.z + s[2]}, dims))) {
          ++touching;
          break;
        }
      }
    });
    if (touching > most) {
      most = touching;
      best = k;
    }
  }
  return best;
}

// Whether most of `voxels` lie across `line` from most of `chart` (in its plane, along the
// line's extent): joined to it, they would make a chart the line runs through.
bool AcrossLine(const std::vector<Index3>& voxels, const Chart& chart, const JunctionLine& line) {
  const Vec3 across = Cross(chart.info().normal, line.direction);
  if (Norm2(across) < 1e-12) return false;
  const Vec3 w = Normalized(across);
  int64_t chart_side = 0;
  chart.ForEachVoxel([&](const Index3& p, bool) {
    chart_side += Dot(Vec3(p.x, p.y, p.z) - line.point, w) >= 0 ? 1 : -1;
  });
  const double sign = chart_side >= 0 ? 1 : -1;
  uint64_t across_count = 0;
  for (const Index3& p : voxels) {
    const Vec3 q(p.x, p.y, p.z);
    const double t = Dot(q - line.point, line.direction);
    if (t < line.t0 - 0.5 || t > line.t1 + 0.5) continue;
    across_count += sign * Dot(q - line.point, w) < 0;
  }
  return 2 * across_count > voxels.size();
}

// The squared distance from `line` of the farthest of `voxels` (0: none).
double Farthest2(const std::vector<Index3>& voxels, const JunctionLine& line) {
  double farthest2 = 0;
  for (const Index3& p : voxels) {
    farthest2 = std::max(farthest2, line.Distance2(Vec3(p.x, p.y, p.z)));
  }
  return farthest2;
}

// What a split takes beyond a line, as parts: the voxels within `core` of the line along its
// extent and `merge` past its ends (where two sheets' voxels are one: the junction's, and the
// cut fills the chart up to the line; farther past the ends the sheet goes on whole), and
// the 6-connected components of the others (a separation's part may hold a strip along the
// line and a patch of a sheet far from it, joined only through the junction). The first
// part is the near voxels.
constexpr size_t kMinPart = 32;  // voxels: a smaller part beyond a line is the junction's

std::vector<std::vector<Index3>> PartsBeyond(std::vector<Index3> voxels, const JunctionLine& line,
                                             double core, double merge, const Dims& dims) {
  std::vector<std::vector<Index3>> parts(1);
  std::vector<Index3> far;
  for (const Index3& p : voxels) {
    const Vec3 q(p.x, p.y, p.z);
    const double t = Dot(q - line.point, line.direction);
    (line.Distance2(q) <= core * core && t >= line.t0 - merge && t <= line.t1 + merge ? parts[0]
                                                                                      : far)
        .push_back(p);
  }
  const VoxelSet set = VoxelSet::FromIndices(dims, std::move(far));
  const absl::StatusOr<Components> components = LabelComponents(set, Connectivity::k6);
  if (!components.ok()) {  // cannot fail without a progress to cancel: one part then
    parts.push_back(set.ToIndices());
    return parts;
  }
  const std::vector<uint32_t> label = components->VoxelLabels(set);
  parts.resize(1 + components->count());
  set.ForEachVoxel([&](uint64_t index, int32_t x, int32_t y, int32_t z) {
    parts[1 + label[index]].push_back({x, y, z});
  });
  return parts;
}

// Whether `chart` ends at `line`: nine in ten of its columns on one side, and one of them
// within the junction's extent no farther from the line than a zipped rim may lie.
bool EndsAt(const Chart& chart, const JunctionLine& line, int index) {
  const ChartCut trace = chart.Trace(line, index, chart.info().centroid);
  uint64_t kept = 0, beyond = 0;
  chart.Sides(trace, &kept, &beyond);
  if (std::min(kept, beyond) * 10 > kept + beyond) return false;
  const double side = kept >= beyond ? 1 : -1;
  for (int32_t i = 0; i < chart.ni(); ++i) {
    for (int32_t j = 0; j < chart.nj(); ++j) {
      const ChartColumn* c = chart.At(i, j);
      if (c == nullptr || c->filled || side * trace.Side(i, j) < 0) continue;
      const Vec3 p = chart.Point(i, j, c->mid());
      const double t = Dot(p - line.point, line.direction);
      if (t < line.t0 || t > line.t1) continue;
      if (line.Distance2(p) <= kZipSpan * kZipSpan) return true;
    }
  }
  return false;
}

}  // namespace

std::vector<JunctionLine> JoinCharts(std::vector<std::unique_ptr<Chart>>* charts,
                                     const std::vector<Index3>& loose_in, const Dims& dims,
                                     const JunctionOptions& options, int32_t* next_piece) {
  // In order (the layers' junctions arrive in a hash map's): the components of the loose
  // voxels and their contacts the same every run.
  std::vector<Index3> loose = loose_in;
  std::sort(loose.begin(), loose.end(), [](const Index3& a, const Index3& b) {
    return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
  });
  // Lines first, and the charts they run through split there (a chart that is two sheets
  // folded at a T gives a line between its planes' mixture and the next: once split, its
  // parts' planes give the line again, better), until none is split.
  LineSet set;
  for (int round = 0;; ++round) {
    std::map<std::pair<int32_t, int32_t>, Contact> contacts = FindContacts(*charts, loose, dims);
    // Merge bands and fragments out, then the contacts again (a fragment may show only once
    // the bands it touched are junction voxels).
    for (int pass = 0; pass < 3; ++pass) {
      std::vector<int32_t> bands;
      for (int32_t c = 0; c < static_cast<int32_t>(charts->size()); ++c) {
        if (MergeBand(c, *charts, contacts, options) || Fragment(c, *charts, contacts, options)) {
          bands.push_back(c);
        }
      }
      if (bands.empty()) break;
      for (int32_t c : bands) {
        (*charts)[c]->ForEachVoxel([&](const Index3& p, bool) { loose.push_back(p); });
        (*charts)[c].reset();
      }
      charts->erase(std::remove(charts->begin(), charts->end(), nullptr), charts->end());
      contacts = FindContacts(*charts, loose, dims);
    }
    set = MakeLines(*charts, contacts, dims, options);
    if (round == 3) break;
    bool split = false;
    for (size_t l = 0; l < set.lines.size(); ++l) {
      for (const auto& [c, plane] : set.planes[l]) {
        Chart& chart = *(*charts)[c];
        const ChartCut trace = chart.Trace(set.lines[l], static_cast<int>(l), plane.first);
        // Split where much of it lies beyond along the line's extent (what lies beyond only
        // past the line's end is not split off: the chart touched the line's sheets where
        // another junction ends it, at the end of a T's line on the sheet the T stops at).
        uint64_t kept = 0, beyond = 0;
        chart.Sides(trace, &kept, &beyond);
        const uint64_t along = chart.SidesAlong(trace, set.lines[l]).beyond;
        if (along * 10 <= kept + beyond || along < 32) continue;
        std::vector<Index3> rest = chart.TakeBeyond(trace);
        if (rest.size() < 3) continue;
        split = true;
        // What lies beyond only within the width over which two sheets of their thickness
        // run together at the line's angle is the other sheet's edge or the merge, not a
        // sheet: it joins the junction's voxels (a chart of it would be a sliver tilted
        // between the two, meeting both in lines of its own beside the true one).
        const JunctionLine& line = set.lines[l];
        double thick = 1;
        for (double t : set.thickness[l]) thick = std::max(thick, t);
        const double sine = std::sin(line.degrees * kPi / 180);
        const double merge = MergeWidth(thick, sine);
        if (Farthest2(rest, line) <= merge * merge) {
          loose.insert(loose.end(), rest.begin(), rest.end());
          continue;
        }
        // Otherwise its parts beyond the junction's core (where the two sheets' voxels are
        // one), each a sheet.
        const double core = std::min(merge, 0.5 * thick / std::max(0.1, sine) + 1.5);
        std::vector<std::vector<Index3>> parts =
            PartsBeyond(std::move(rest), line, core, merge, dims);
        for (size_t q = 0; q < parts.size(); ++q) {
          std::vector<Index3>& part = parts[q];
          // A part within the merge of the line is the merge's (as a rest would be).
          if (q == 0 || part.size() < kMinPart || Farthest2(part, line) <= merge * merge) {
            loose.insert(loose.end(), part.begin(), part.end());
            continue;
          }
          // What lies beyond along the plane of a chart it touches there is that sheet's (the
          // separation drew their border off the junction): it joins it.
          // Not across another line from that chart, though: a part the separation gave the
          // wrong side of a crossing is a sheet of its own (joined, the two would pass back and
          // forth between the lines' splits).
          auto may_join = [&](int32_t k) {
            for (size_t m = 0; m < set.lines.size(); ++m) {
              if (m == l) continue;
              for (const auto& [other, unused] : set.planes[m]) {
                if (other == k && AcrossLine(part, *(*charts)[k], set.lines[m])) return false;
              }
            }
            return true;
          };
          if (const int32_t k =
                  CoplanarNeighbour(part, c, *charts, dims, options.min_degrees, may_join);
              k >= 0) {
            (*charts)[k]->ForEachVoxel([&](const Index3& p, bool) { part.push_back(p); });
            const int32_t piece = (*charts)[k]->info().piece;
            (*charts)[k] = std::make_unique<Chart>(std::move(part), piece, dims);
            continue;
          }
          charts->push_back(std::make_unique<Chart>(std::move(part), (*next_piece)++, dims));
        }
      }
    }
    if (!split) break;
  }
  std::vector<JunctionLine>& lines = set.lines;
  // Samples evenly spaced from end to end, so that a line's end on the box is a sample.
  for (JunctionLine& line : lines) {
    const double length = line.t1 - line.t0;
    line.step = length / std::max(1.0, std::round(length / options.sample_step));
  }
  // Each line cuts its charts and fills them up to it.
  constexpr double kBand = 12, kMaxBand = 64;
  for (size_t l = 0; l < lines.size(); ++l) {
    JunctionLine& line = lines[l];
    std::vector<std::pair<int32_t, std::pair<Vec3, Vec3>>> cuts = set.planes[l];
    std::vector<double> thick = set.thickness[l];
    // Each plane turned the least to hold the line (merged lines lie a little off the
    // planes of the pairs they came from): the sheets meet on it at their planes' angle.
    for (auto& [chart, plane] : cuts) {
      const Vec3 n = plane.second - line.direction * Dot(plane.second, line.direction);
      if (Norm2(n) > 1e-12) plane = {line.point, Normalized(n)};
    }
    // A chart along the plane of one that ends here and that ends here too is cut and
    // zipped to the line as well: the separation drew the border between two parts of one
    // sheet off the junction, and the part that reached it went to the other.
    const size_t meeting = cuts.size();
    for (int32_t k = 0; k < static_cast<int32_t>(charts->size()); ++k) {
      if (std::any_of(cuts.begin(), cuts.end(), [&](const auto& c) { return c.first == k; })) {
        continue;
      }
      const Chart& chart = *(*charts)[k];
      for (size_t m = 0; m < meeting; ++m) {
        const Chart& along = *(*charts)[cuts[m].first];
        if (std::abs(Dot(chart.info().normal, along.info().normal)) <
            std::cos(options.min_degrees * kPi / 180)) {
          continue;
        }
        if (!EndsAt(chart, line, static_cast<int>(l))) continue;
        cuts.push_back({k, cuts[m].second});
        thick.push_back(thick[m]);
        break;
      }
    }
    double thickest = 1;
    for (double t : thick) thickest = std::max(thickest, t);
    const double merge = MergeWidth(thickest, std::sin(line.degrees * kPi / 180));
    for (size_t k = 0; k < cuts.size(); ++k) {
      Chart& chart = *(*charts)[cuts[k].first];
      // Towards the chart's own columns: the side where most of them lie.
      ChartCut trace = chart.Trace(line, static_cast<int>(l), chart.info().centroid);
      uint64_t kept = 0, beyond = 0;
      chart.Sides(trace, &kept, &beyond);
      if (beyond > kept) {
        trace.ni = -trace.ni;
        trace.nj = -trace.nj;
      }
      // A chart that runs on across the line along its extent (a quarter of its columns
      // there), farther than the sheets' merge, does not end there: it touched the line's sheets
      // only where another junction takes it (the end of a T's line at the sheet it stops on), and
      // is not cut.
      const Chart::StripSides strip = chart.SidesAlong(trace, line);
      if (strip.beyond >= kPassing && 4 * strip.beyond >= strip.kept + strip.beyond &&
          strip.farthest_beyond > merge + kZipSpan) {
        continue;
      }
      // The band reaches the chart's columns: past a shallow crossing's merged runs.
      const double band = std::min(kMaxBand, std::max(kBand, chart.Gap(trace, line) + 4));
      chart.Cut(trace, line, band, cuts[k].second.first, cuts[k].second.second, thick[k]);
      line.charts.push_back(cuts[k].first);
      line.thickness.push_back(thick[k]);
      line.pieces.push_back(chart.info().piece);
      line.plane_points.push_back(cuts[k].second.first);
      line.plane_normals.push_back(cuts[k].second.second);
    }
  }
  return lines;
}

}  // namespace sheetmesh
