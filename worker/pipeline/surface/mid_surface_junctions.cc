#include "worker/pipeline/surface/mid_surface_junctions.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"

namespace sheetmesh {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr size_t kMaxContactPoints = 4000;  // a line's fit needs no more

// A voxel's index in a box of `dims`, and its six neighbours' steps.
uint64_t VoxelKey(const Index3& p, const Dims& dims) {
  return static_cast<uint64_t>(p.x) +
         static_cast<uint64_t>(dims.nx) *
             (static_cast<uint64_t>(p.y) + static_cast<uint64_t>(dims.ny) * p.z);
}
constexpr int kStep[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};

// How far from their junction two sheets of `thickness` meeting at an angle of this sine
// run together (their runs merge): the planes near a contact are fitted beyond it, and
// what a cut leaves beyond a line within it is the junction's.
double MergeWidth(double thickness, double sine) {
  return std::min(40.0, 1.5 * thickness / std::max(0.1, sine) + 2);
}

// Where two charts meet: the voxels by which they do.
struct Contact {
  std::vector<Vec3> points;
  uint64_t count = 0;
  void Add(const Vec3& p) {
    // Every k-th past the cap: an even subsample of a long contact.
    if (points.size() < kMaxContactPoints || (count % (count / kMaxContactPoints + 1)) == 0) {
      if (points.size() < 2 * kMaxContactPoints) points.push_back(p);
    }
    ++count;
  }
};

// A junction found between charts, before lines along one another are merged.
struct Found {
  JunctionLine line;
  uint64_t contact = 0;
  Vec3 plane_point[2], plane_normal[2];
  double thickness[2] = {0, 0};
};

// Which charts meet, and by which voxels: those that touch, and those that touch one
// component of the `loose` voxels (in no chart).
std::map<std::pair<int32_t, int32_t>, Contact> FindContacts(
    const std::vector<std::unique_ptr<Chart>>& charts_in, const std::vector<Index3>& loose,
    const Dims& dims) {
  const std::vector<std::unique_ptr<Chart>>* charts = &charts_in;
  auto key = [&](const Index3& p) { return VoxelKey(p, dims); };
  auto inside = [&](const Index3& p) {
    return p.x >= 0 && p.y >= 0 && p.z >= 0 && p.x < dims.nx && p.y < dims.ny && p.z < dims.nz;
  };
  // Who holds each voxel: a chart, or none of them (-1).
  absl::flat_hash_map<uint64_t, int32_t> owner;
  for (size_t c = 0; c < charts->size(); ++c) {
    (*charts)[c]->ForEachVoxel(
        [&](const Index3& p, bool) { owner[key(p)] = static_cast<int32_t>(c); });
  }
  for (const Index3& p : loose) owner.try_emplace(key(p), -1);
  std::map<std::pair<int32_t, int32_t>, Contact> contacts;
  // Charts that touch.
  for (size_t c = 0; c < charts->size(); ++c) {
    (*charts)[c]->ForEachVoxel([&](const Index3& p, bool) {
      for (const auto& s : kStep) {
        const Index3 q{p.x + s[0], p.y + s[1], p.z + s[2]};
        if (!inside(q)) continue;
        const auto it = owner.find(key(q));
        if (it == owner.end() || it->second < 0 || it->second <= static_cast<int32_t>(c)) continue;
        contacts[{static_cast<int32_t>(c), it->second}].Add(Vec3(p.x, p.y, p.z));
      }
    });
  }
  // Charts that touch one component of the voxels between them.
  {
    absl::flat_hash_map<uint64_t, uint32_t> index;
    for (uint32_t k = 0; k < loose.size(); ++k) index[key(loose[k])] = k;
    std::vector<uint32_t> parent(loose.size());
    for (uint32_t k = 0; k < loose.size(); ++k) parent[k] = k;
    auto find = [&](uint32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    std::vector<std::vector<int32_t>> touching(loose.size());
    for (uint32_t k = 0; k < loose.size(); ++k) {
      const Index3& p = loose[k];
      for (const auto& s : kStep) {
        const Index3 q{p.x + s[0], p.y + s[1], p.z + s[2]};
        if (!inside(q)) continue;
        const auto o = owner.find(key(q));
        if (o == owner.end()) continue;
        if (o->second >= 0) {
          touching[k].push_back(o->second);
        } else if (const auto j = index.find(key(q)); j != index.end()) {
          parent[find(k)] = find(j->second);
        }
      }
    }
    // By root in order: a contact's points, and so its line, come out the same every run.
    std::map<uint32_t, std::vector<int32_t>> charts_of;
    absl::flat_hash_map<uint32_t, std::vector<uint32_t>> members;
    for (uint32_t k = 0; k < loose.size(); ++k) {
      const uint32_t root = find(k);
      members[root].push_back(k);
      for (int32_t c : touching[k]) charts_of[root].push_back(c);
    }
    for (auto& [root, cs] : charts_of) {
      std::sort(cs.begin(), cs.end());
      cs.erase(std::unique(cs.begin(), cs.end()), cs.end());
      for (size_t a = 0; a < cs.size(); ++a) {
        for (size_t b = a + 1; b < cs.size(); ++b) {
          Contact& contact = contacts[{cs[a], cs[b]}];
          for (uint32_t k : members[root]) {
            contact.Add(Vec3(loose[k].x, loose[k].y, loose[k].z));
          }
        }
      }
    }
  }
  return contacts;
}

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
// `degrees` of theirs, the one they touch most; -1 when none.
int32_t CoplanarNeighbour(const std::vector<Index3>& voxels, int32_t self,
                          const std::vector<std::unique_ptr<Chart>>& charts, const Dims& dims,
                          double degrees) {
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

// The junction lines of `contacts`: per contact the line where the two charts' planes near it
// cross, lines along one another merged; with each line the planes and thickness of its
// charts.
struct LineSet {
  std::vector<JunctionLine> lines;
  std::vector<std::vector<std::pair<int32_t, std::pair<Vec3, Vec3>>>> planes;  // per line
  std::vector<std::vector<double>> thickness;
};

LineSet MakeLines(const std::vector<std::unique_ptr<Chart>>& charts_in,
                  const std::map<std::pair<int32_t, int32_t>, Contact>& contacts, const Dims& dims,
                  const JunctionOptions& options) {
  const std::vector<std::unique_ptr<Chart>>* charts = &charts_in;
  // Each contact's line: where the two charts' planes near it cross.
  std::vector<Found> found;
  for (const auto& [pair, contact] : contacts) {
    if (contact.count < options.min_contact || contact.points.size() < 3) continue;
    Vec3 c, d;
    PrincipalLine(contact.points, &c, &d);
    double ta = 0, tb = 0;
    for (const Vec3& p : contact.points) {
      ta = std::min(ta, Dot(p - c, d));
      tb = std::max(tb, Dot(p - c, d));
    }
    constexpr double kRadius = 24;
    constexpr double kEndMargin = 2;
    constexpr double kBoxGap = 3;  // a chart reaching this near the box reaches it
    Found f;
    const int32_t ids[2] = {pair.first, pair.second};
    // First the planes near the contact; then again away from the line they give, by a
    // band as wide as two sheets at that angle run together, until the line stands.
    Vec3 line_point = c, line_dir = d;
    double la = ta, lb = tb, inner = 0;
    bool ok = false;
    for (int round = 0; round < 3; ++round) {
      Found trial = f;
      bool fitted = true;
      for (int s = 0; s < 2; ++s) {
        fitted = fitted && (*charts)[ids[s]]->LocalPlane(
                               line_point, line_dir, la, lb, inner, inner + kRadius,
                               &trial.plane_point[s], &trial.plane_normal[s], &trial.thickness[s]);
      }
      if (!fitted) break;  // the last fit stands
      f = trial;
      ok = true;
      const Vec3& na = f.plane_normal[0];
      const Vec3& nb = f.plane_normal[1];
      const double sine = Norm(Cross(na, nb));
      if (sine < std::sin(options.min_degrees * kPi / 180)) break;
      const Vec3 u = Normalized(Cross(na, nb));
      const double k = Dot(na, nb);
      const double ra = Dot(na, f.plane_point[0] - c), rb = Dot(nb, f.plane_point[1] - c);
      const double det = 1 - k * k;
      const double alpha = (ra - k * rb) / det, beta = (rb - k * ra) / det;
      line_point = c + na * alpha + nb * beta;
      line_dir = u;
      la = 1e300;
      lb = -1e300;
      for (const Vec3& p : contact.points) {
        const double t = Dot(p - line_point, u);
        la = std::min(la, t);
        lb = std::max(lb, t);
      }
      const double thick = std::max({f.thickness[0], f.thickness[1], 1.0});
      inner = MergeWidth(thick, sine);
    }
    if (!ok) continue;
    const Vec3& na = f.plane_normal[0];
    const Vec3& nb = f.plane_normal[1];
    const double cosine = std::min(1.0, std::abs(Dot(na, nb)));
    const double degrees = std::acos(cosine) * 180 / kPi;
    if (degrees < options.min_degrees) continue;
    const Vec3 u = Normalized(Cross(na, nb));
    // The point of both planes nearest the contact's centroid.
    const double k = Dot(na, nb);
    const double ra = Dot(na, f.plane_point[0] - c), rb = Dot(nb, f.plane_point[1] - c);
    const double det = 1 - k * k;
    const double alpha = (ra - k * rb) / det, beta = (rb - k * ra) / det;
    f.line.point = c + na * alpha + nb * beta;
    f.line.direction = u;
    f.line.degrees = degrees;
    double t0 = 1e300, t1 = -1e300;
    for (const Vec3& p : contact.points) {
      const double t = Dot(p - f.line.point, u);
      t0 = std::min(t0, t);
      t1 = std::max(t1, t);
    }
    // The line runs on to the box where the contact stops short of it by less than the
    // planes' reach (the voxels at a face of the box are often cut or merged away) and both
    // charts reach the box there; otherwise it ends a little past the contact: where sheets
    // end inside the box (10 voxels short of it: a line run on made flaps with no aperture),
    // or curve away from the planes fitted near it, a line run on past the contact would lie
    // off the charts it cuts, and their fills up to it would fold over their own columns.
    double box0 = t0 - kRadius, box1 = t1 + kRadius;
    if (!ClipToBox(f.line.point, u, dims, &box0, &box1)) continue;
    auto reaches = [&](double from, double box, int sign) {
      for (const int32_t id : ids) {
        const double reach =
            (*charts)[id]->ReachAlong(f.line.point, u, from, inner + kRadius, sign);
        if (sign * (box - reach) > kBoxGap) return false;
      }
      return true;
    };
    f.line.t0 = box0 > t0 - kRadius && reaches(t0, box0, -1) ? box0 : t0 - kEndMargin;
    f.line.t1 = box1 < t1 + kRadius && reaches(t1, box1, 1) ? box1 : t1 + kEndMargin;
    if (!ClipToBox(f.line.point, u, dims, &f.line.t0, &f.line.t1)) continue;
    f.line.step = options.sample_step;
    f.line.charts = {ids[0], ids[1]};
    f.contact = contact.count;
    found.push_back(f);
  }
  // Lines along one another (an X's four halves meet pairwise) are one.
  LineSet set;
  std::vector<JunctionLine>& lines = set.lines;
  auto& planes = set.planes;
  auto& thickness = set.thickness;
  std::vector<uint64_t> weight;
  for (const Found& f : found) {
    int merged = -1;
    for (size_t l = 0; l < lines.size(); ++l) {
      const JunctionLine& g = lines[l];
      if (std::abs(Dot(g.direction, f.line.direction)) < std::cos(3 * kPi / 180)) continue;
      const Vec3 mid = f.line.point + f.line.direction * (0.5 * (f.line.t0 + f.line.t1));
      const Vec3 off = mid - g.point;
      if (Norm2(off - g.direction * Dot(off, g.direction)) > 1.5 * 1.5) continue;
      merged = static_cast<int>(l);
      break;
    }
    if (merged < 0) {
      lines.push_back(f.line);
      lines.back().charts.clear();
      planes.emplace_back();
      thickness.emplace_back();
      weight.push_back(0);
      merged = static_cast<int>(lines.size() - 1);
    } else {
      // Weighted by contact; the direction kept pointing one way.
      JunctionLine& g = lines[merged];
      const double w0 = double(weight[merged]), w1 = double(f.contact);
      const Vec3 u = Dot(g.direction, f.line.direction) < 0 ? -f.line.direction : f.line.direction;
      const Vec3 direction = Normalized(g.direction * w0 + u * w1);
      const Vec3 p1 = f.line.point;
      const Vec3 off = p1 - g.point;
      const Vec3 point = g.point + (off - g.direction * Dot(off, g.direction)) * (w1 / (w0 + w1));
      const double s = Dot(g.point - point, direction);
      const double a0 = g.t0 + s, a1 = g.t1 + s;
      // f's points p1 + t f.direction lie at sf + t along `direction`, or sf - t reversed.
      const double sf = Dot(p1 - point, direction);
      const bool flipped = Dot(u, f.line.direction) < 0;
      double b0 = sf + (flipped ? -f.line.t1 : f.line.t0);
      double b1 = sf + (flipped ? -f.line.t0 : f.line.t1);
      g.point = point;
      g.direction = direction;
      g.t0 = std::min(a0, b0);
      g.t1 = std::max(a1, b1);
      ClipToBox(g.point, g.direction, dims, &g.t0, &g.t1);
      g.degrees = (g.degrees * w0 + f.line.degrees * w1) / (w0 + w1);
    }
    weight[merged] += f.contact;
    for (int s = 0; s < 2; ++s) {
      const int32_t c = f.line.charts[s];
      bool have = false;
      for (const auto& [chart, plane] : planes[merged]) have |= chart == c;
      if (!have) {
        planes[merged].push_back({c, {f.plane_point[s], f.plane_normal[s]}});
        thickness[merged].push_back(f.thickness[s]);
      }
    }
  }
  return set;
}

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
        uint64_t kept = 0, beyond = 0;
        chart.Sides(trace, &kept, &beyond);
        if (beyond * 10 <= kept + beyond || beyond < 32) continue;
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
        const double merge = MergeWidth(thick, std::sin(line.degrees * kPi / 180));
        double farthest2 = 0;
        for (const Index3& p : rest) {
          farthest2 = std::max(farthest2, line.Distance2(Vec3(p.x, p.y, p.z)));
        }
        if (farthest2 <= merge * merge) {
          loose.insert(loose.end(), rest.begin(), rest.end());
          continue;
        }
        // What lies beyond along the plane of a chart it touches there is that sheet's (the
        // separation drew their border off the junction): it joins it.
        if (const int32_t k = CoplanarNeighbour(rest, c, *charts, dims, options.min_degrees);
            k >= 0) {
          (*charts)[k]->ForEachVoxel([&](const Index3& p, bool) { rest.push_back(p); });
          const int32_t piece = (*charts)[k]->info().piece;
          (*charts)[k] = std::make_unique<Chart>(std::move(rest), piece, dims);
          continue;
        }
        charts->push_back(std::make_unique<Chart>(std::move(rest), (*next_piece)++, dims));
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
