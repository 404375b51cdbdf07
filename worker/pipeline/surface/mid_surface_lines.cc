#include "worker/pipeline/surface/mid_surface_lines.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "absl/container/flat_hash_map.h"

namespace sheetmesh {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A junction found between charts, before lines along one another are merged.
struct Found {
  JunctionLine line;
  uint64_t contact = 0;
  Vec3 plane_point[2], plane_normal[2];
  double thickness[2] = {0, 0};
};

// Where a line's end lies near another line (within kNodeReach along it of where they
// cross, the two within kNodeGap of one another there, the crossing along the other's
// extent), it ends where they cross: a T's line ends on the crossing its sheet stops at, not
// a few voxels past it (a cut and fill along the overshoot crossed the other line's sheets).
constexpr double kNodeReach = 6, kNodeGap = 2;

void EndAtNodes(std::vector<JunctionLine>* lines) {
  for (size_t a = 0; a < lines->size(); ++a) {
    JunctionLine& la = (*lines)[a];
    for (size_t b = 0; b < lines->size(); ++b) {
      if (a == b) continue;
      const JunctionLine& lb = (*lines)[b];
      // The closest points of the two lines: la.point + s u and lb.point + t v.
      const Vec3& u = la.direction;
      const Vec3& v = lb.direction;
      const double k = Dot(u, v);
      if (1 - k * k < 0.05) continue;  // along one another (within 13 degrees)
      const Vec3 w = la.point - lb.point;
      const double du = Dot(u, w), dv = Dot(v, w);
      const double s = (k * dv - du) / (1 - k * k);
      const double t = (dv - k * du) / (1 - k * k);
      if (Norm2(la.point + u * s - (lb.point + v * t)) > kNodeGap * kNodeGap) continue;
      if (t < lb.t0 - 1 || t > lb.t1 + 1) continue;
      if (std::abs(s - la.t0) <= kNodeReach && std::abs(s - la.t0) < std::abs(s - la.t1)) {
        la.t0 = s;
        la.node0 = true;
      } else if (std::abs(s - la.t1) <= kNodeReach) {
        la.t1 = s;
        la.node1 = true;
      }
    }
  }
}

}  // namespace

// How far from their junction two sheets of `thickness` meeting at an angle of this sine
// run together (their runs merge): the planes near a contact are fitted beyond it, and
// what a cut leaves beyond a line within it is the junction's.
double MergeWidth(double thickness, double sine) {
  return std::min(40.0, 1.5 * thickness / std::max(0.1, sine) + 2);
}

void Contact::Add(const Vec3& p) {
  // Every k-th past the cap: an even subsample of a long contact.
  if (points.size() < kMaxContactPoints || (count % (count / kMaxContactPoints + 1)) == 0) {
    if (points.size() < 2 * kMaxContactPoints) points.push_back(p);
  }
  ++count;
}

// Which charts meet, and by which voxels: those that touch, and those that touch one
// component of the `loose` voxels (in no chart).
std::map<std::pair<int32_t, int32_t>, Contact> FindContacts(
    const std::vector<std::unique_ptr<Chart>>& charts_in, const std::vector<Index3>& loose,
    const Dims& dims) {
  const std::vector<std::unique_ptr<Chart>>* charts = &charts_in;
  auto key = [&](const Index3& p) { return VoxelKey(p, dims); };
  auto inside = [&](const Index3& p) { return dims.Contains(p.x, p.y, p.z); };
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

// The lines of `contacts` (mid_surface_lines.h).
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
    constexpr double kEndMargin = 0.5;
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
  EndAtNodes(&set.lines);
  return set;
}

}  // namespace sheetmesh
