#include "worker/pipeline/tet/plc.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <set>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/status_macros.h"
#include "worker/pipeline/mesh/mesh_io.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

constexpr size_t kContactPlaces = 10;  // unmended contacts the report names
constexpr double kTouchVoxels = 1e-6;  // a vertex this near a sheet edge or face lies on it
// The caps the mends left are closed where flatter than this (or plc.cap_degrees): at 160
// degrees the moves changed the 192^3 phantom's minimum at r = 5 from 4.45 to 2.83 degrees.
constexpr double kCloseCapDegrees = 170.0;

// The offset of coordinate k of seed i, in [-0.5, 0.5) (kSeedJitterVoxels).
double Jitter(uint64_t i, int k) {
  uint64_t x = (i + 1) * 0x9E3779B97F4A7C15ull + static_cast<uint64_t>(k) * 0xBF58476D1CE4E5B9ull;
  x ^= x >> 31;
  x *= 0x94D049BB133111EBull;
  x ^= x >> 29;
  return static_cast<double>(x >> 11) / 9007199254740992.0 - 0.5;
}

// The sheets' median edge sets the spacing of the seeded points, so that the tetrahedra
// off the sheets are about as large as those on them. 0 without sheets.
double MedianEdge(const SheetTriangles& st, const std::vector<Vec3>& v) {
  if (st.faces.empty()) return 0;
  std::vector<double> edges;
  for (const Face& f : st.faces) {
    for (int k = 0; k < 3; ++k) edges.push_back(Norm(v[f[(k + 1) % 3]] - v[f[k]]));
  }
  std::nth_element(edges.begin(), edges.begin() + edges.size() / 2, edges.end());
  return edges[edges.size() / 2];
}

// The facet of box face `face`. Corner c has bit 0 = x high, bit 1 = y high, bit 2 = z
// high. The face is a polygon through its 4 corners and the sheet vertices on its edges,
// in order, plus the sheet edges and vertices that lie in it and the box points seeded on
// it. `index` maps a sheet vertex of `v` to its PLC vertex (UINT32_MAX: unused).
PlcFacet BoxFacet(int face, const Plc& plc, const std::vector<Vec3>& v,
                  const std::vector<uint8_t>& on_face, const std::vector<uint32_t>& index,
                  const std::vector<Face>& faces, const std::vector<BoxPoint>& box_points,
                  uint32_t first_box_point, const Placement& placement) {
  const int k = Axis(face);
  const int bit = Low(face) ? 0 : 1;
  const int a = (k + 1) % 3, b = (k + 2) % 3;
  // Corners of the face in cyclic order over axes a, b.
  auto corner = [&](int ca, int cb) {
    int c = 0;
    if (bit) c |= 1 << k;
    if (ca) c |= 1 << a;
    if (cb) c |= 1 << b;
    return static_cast<uint32_t>(c);
  };
  const uint32_t cyc[4] = {corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)};
  std::vector<uint32_t> polygon;
  for (int e = 0; e < 4; ++e) {
    const uint32_t p = cyc[e], q = cyc[(e + 1) % 4];
    polygon.push_back(p);
    // Sheet vertices on edge p-q: on this face and on the face of the other varying axis.
    std::vector<std::pair<double, uint32_t>> along;
    const Vec3 pp = plc.vertices[p], qq = plc.vertices[q];
    const Vec3 dir = qq - pp;
    for (uint32_t i = 0; i < v.size(); ++i) {
      if (index[i] == UINT32_MAX || !(on_face[i] & (1 << face))) continue;
      const Vec3 x = placement.ToPhysical(v[i]);
      const double t = Dot(x - pp, dir) / Norm2(dir);
      if (t <= 1e-12 || t >= 1 - 1e-12) continue;
      if (Norm(x - (pp + dir * t)) > 1e-9 * (1 + Norm(dir))) continue;
      along.emplace_back(t, index[i]);
    }
    for (uint32_t i = 0; i < box_points.size(); ++i) {
      const BoxPoint& bp = box_points[i];
      if (!(bp.on_face & (1 << face)) || std::popcount(bp.on_face) != 2) continue;
      const double t = Dot(bp.p - pp, dir) / Norm2(dir);
      if (t <= 1e-12 || t >= 1 - 1e-12) continue;
      if (Norm(bp.p - (pp + dir * t)) > 1e-9 * (1 + Norm(dir))) continue;
      along.emplace_back(t, first_box_point + i);
    }
    std::sort(along.begin(), along.end());
    for (const auto& [t, id] : along) polygon.push_back(id);
  }
  PlcFacet facet;
  facet.marker = kBoundaryMarker;
  facet.polygons.push_back(polygon);
  std::set<uint32_t> on_polygon(polygon.begin(), polygon.end());
  std::set<std::pair<uint32_t, uint32_t>> segments;
  std::set<uint32_t> points;
  for (size_t f = 0; f < faces.size(); ++f) {
    const Face& t = faces[f];
    for (int e = 0; e < 3; ++e) {
      const uint32_t s = t[e], u = t[(e + 1) % 3];
      // An edge in this face is a segment of its facet, unless it runs along the outline:
      // both ends on one box edge, on another face too. (Ends on two box edges make a chord
      // across a corner of the face, which TetGen must be given.)
      const uint8_t both = on_face[s] & on_face[u];
      if ((both & (1 << face)) != 0 && (both & ~(1 << face)) == 0) {
        segments.insert({std::min(index[s], index[u]), std::max(index[s], index[u])});
      }
    }
    for (uint32_t s : t) {
      if ((on_face[s] & (1 << face)) && !on_polygon.count(index[s])) points.insert(index[s]);
    }
  }
  for (const auto& [s, u] : segments) {
    facet.polygons.push_back({s, u});
    points.erase(s);
    points.erase(u);
  }
  for (uint32_t p : points) facet.polygons.push_back({p});
  for (uint32_t i = 0; i < box_points.size(); ++i) {
    if (box_points[i].on_face == (1 << face)) facet.polygons.push_back({first_box_point + i});
  }
  return facet;
}

// Bit k set where vertex i lies on box face k: on it before (`was`), or at its plane now
// (within rounding); a coordinate past the box is clamped onto it.
std::vector<uint8_t> OnBox(std::vector<Vec3>& v, const Vec3& lo, const Vec3& hi,
                           const std::vector<uint8_t>& was) {
  std::vector<uint8_t> on(v.size(), 0);
  for (size_t i = 0; i < v.size(); ++i) {
    on[i] = i < was.size() ? was[i] : 0;
    for (int k = 0; k < 3; ++k) {
      const double tol = 1e-9 * (1 + std::abs(hi[k] - lo[k]));
      if (v[i][k] <= lo[k] + tol) v[i][k] = lo[k], on[i] |= 1 << (2 * k);
      if (v[i][k] >= hi[k] - tol) v[i][k] = hi[k], on[i] |= 1 << (2 * k + 1);
    }
  }
  return on;
}

}  // namespace

SheetTriangles Without(const SheetTriangles& s, const std::vector<uint8_t>& drop) {
  SheetTriangles keep;
  for (size_t f = 0; f < s.faces.size(); ++f) {
    if (drop[f]) continue;
    keep.faces.push_back(s.faces[f]);
    keep.source.push_back(s.source[f]);
    keep.piece.push_back(s.piece[f]);
    keep.thickness.push_back(s.thickness[f]);
  }
  return keep;
}

std::string Plc::ToPoly() const {
  std::string out = absl::StrCat("# sheetmesh PLC: box + ", sheet_triangles.size(),
                                 " sheet triangles\n", vertices.size(), " 3 0 0\n");
  for (size_t i = 0; i < vertices.size(); ++i) {
    absl::StrAppendFormat(&out, "%d %.17g %.17g %.17g\n", i, vertices[i].x, vertices[i].y,
                          vertices[i].z);
  }
  absl::StrAppend(&out, facets.size(), " 1\n");
  for (const PlcFacet& f : facets) {
    absl::StrAppend(&out, f.polygons.size(), " 0 ", f.marker, "\n");
    for (const auto& poly : f.polygons) {
      out += std::to_string(poly.size());
      for (uint32_t v : poly) absl::StrAppend(&out, " ", v);
      out += "\n";
    }
  }
  out += "0\n0\n";
  return out;
}

void MoveSeeds(uint32_t salt, double voxels, Plc* plc) {
  const size_t first = plc->vertices.size() - plc->seed_points;
  const uint64_t offset = (uint64_t{salt} << 40) + plc->vertices.size();
  for (size_t i = first; i < plc->vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      plc->vertices[i][k] += voxels * plc->voxel_length * Jitter(offset + i, k);
    }
  }
}

void JitterSheetVertices(uint32_t salt, double voxels, Plc* plc) {
  std::vector<uint8_t> on_sheet(plc->vertices.size(), 0);
  for (const Face& t : plc->sheet_triangles) {
    for (uint32_t v : t) on_sheet[v] = 1;
  }
  const uint64_t offset = (uint64_t{salt} << 40) + 2 * plc->vertices.size();
  for (size_t i = 0; i < plc->vertices.size(); ++i) {
    if (!on_sheet[i]) continue;
    Vec3& p = plc->vertices[i];
    for (int k = 0; k < 3; ++k) {
      // A coordinate on a box face stays on it exactly.
      if (p[k] == plc->box_lo[k] || p[k] == plc->box_hi[k]) continue;
      p[k] += voxels * plc->voxel_length * Jitter(offset + i, k);
    }
  }
}

absl::StatusOr<Plc> BuildPlc(const TriangleMesh& sheets, const Dims& dims,
                             const Placement& placement, const PlcOptions& options,
                             std::vector<Clash>* clashes) {
  if (dims.nx <= 0 || dims.ny <= 0 || dims.nz <= 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("volume mesh box ", dims.ToString(), " is empty"));
  }
  Plc plc;
  // The box spans the voxels' extent, in index coordinates [-0.5, n - 0.5].
  const Vec3 lo(-0.5, -0.5, -0.5), hi(dims.nx - 0.5, dims.ny - 0.5, dims.nz - 0.5);
  plc.box_lo = placement.ToPhysical(lo);
  plc.box_hi = placement.ToPhysical(hi);
  plc.voxel_length = PhysicalLength(1.0, placement);

  SnappedSheets snapped = SnapToBox(sheets, lo, hi, options, &plc);
  std::vector<Vec3>& v = snapped.v;
  // Per vertex; the untangling's splits add vertices, off the box (kept as long as v).
  std::vector<uint8_t>& on_face = snapped.on_face;
  SheetTriangles& st = snapped.st;
  // Facets must not cut through each other: untangle them, check before TetGen, and name
  // the clashes left.
  bool clean = snapped.checked_clean;
  if (!clean && options.untangle_voxels > 0) {
    const UntangleStats u = Untangle(st, v, on_face, options.untangle_voxels);
    plc.clashing_pairs = u.found_pairs;
    plc.untangle_moves = u.moved_vertices;
    plc.untangle_flips = u.flipped_edges;
    plc.untangle_patches = u.retriangulated_patches;
    plc.untangle_splits = u.split_crossings;
    plc.untangle_thin_splits = u.thin_splits;
    plc.untangle_max_move = u.max_move;
    clean = u.remaining_pairs == 0;
    on_face.resize(v.size(), 0);
  }
  SM_RETURN_IF_ERROR(
      ResolveClashes(v, clean, sheets.body_pieces, placement, options, &st, &plc, clashes));
  // The junctions as the untangling left them (its splits along crossings are junctions too).
  std::vector<uint8_t> held = HeldAtJunctions(st, v.size());
  if (options.short_edge_voxels > 0) {
    plc.collapsed_edges = CollapseShortEdges(st, v, on_face, options.short_edge_voxels);
  }
  if (options.cap_degrees < 180) plc.closed_slits = CloseSlits(st, v, options.cap_degrees);
  if (options.overlap_voxels > 0) {
    plc.dropped_overlaps = DropOverlaps(st, v, on_face, HeldAtJunctions(st, v.size()),
                                        options.overlap_voxels, options.overlap_degrees);
  }
  if (options.contact_voxels > 0) {
    std::vector<Vec3> unmended;
    plc.mended_contacts = MendContacts(st, v, on_face, held, options.contact_voxels,
                                       options.zip_rims, &unmended, &plc.mended_edge_contacts);
    plc.unmended_contacts = static_cast<uint32_t>(unmended.size());
    for (size_t i = 0; i < unmended.size() && i < kContactPlaces; ++i) {
      plc.contact_places.push_back(placement.ToPhysical(unmended[i]));
    }
  }
  if (options.wedge_degrees > 0 && options.junction_voxels > 0) {
    plc.straightened_junctions =
        StraightenJunctions(st, v, on_face, options.wedge_degrees, options.junction_voxels);
    on_face.resize(v.size(), 0);
    plc.opened_dihedral_wedges =
        OpenDihedralWedges(st, v, on_face, options.wedge_degrees, options.junction_voxels);
  }
  if (options.wedge_degrees > 0 && options.wedge_voxels > 0) {
    plc.opened_wedges = OpenWedges(st, on_face, options.wedge_degrees, options.wedge_voxels, v);
  }
  // A cap the mends left (or the flips could not touch, at a junction) is where TetGen 1.5
  // crashes (the rough network's surface at r = 3, read back from its PLY: every try) and
  // leaves slivers: its wide corner goes onto its long edge, by at most plc.wedge_voxels.
  if (options.cap_degrees < 180 && options.wedge_voxels > 0) {
    plc.closed_caps = CloseCaps(st, v, on_face, std::max(options.cap_degrees, kCloseCapDegrees),
                                options.wedge_voxels);
  }
  // A triangle the mends left with no area covers nothing and holds a corner on its own
  // long edge, which TetGen aborts on: it goes, and a vertex then left exactly on another
  // sheet's edge or face is joined to it.
  plc.dropped_triangles += DropFlatTriangles(st, v, kTouchVoxels);
  plc.joined_touches = JoinTouches(st, v, kTouchVoxels);
  // The lattice's spacing follows the sheets' median edge as the mends left it; edges far
  // over it are then halved (the split shortens no edge the lattice was sized from).
  const double median_edge_voxels = MedianEdge(st, v);
  plc.split_long_edges =
      SplitLongSheetEdges(options.long_edge_factor * median_edge_voxels, &v, &on_face, &st);
  // Which box faces each vertex lies on, as the mends left it: a vertex moved onto another
  // sheet where that sheet meets the box lies on the box too, and its edges there must be
  // segments of the box's facet (else TetGen sees a sheet triangle cut the box face and
  // gives up); none may lie outside.
  const std::vector<uint8_t> on_box = OnBox(v, lo, hi, on_face);
  // A triangle the mends laid into a box face (its corners all on it) is that face's: as a
  // sheet facet too it would overlap the box's, and TetGen aborts.
  {
    std::vector<uint8_t> drop(st.faces.size(), 0);
    bool any = false;
    for (size_t f = 0; f < st.faces.size(); ++f) {
      const Face& t = st.faces[f];
      if ((on_box[t[0]] & on_box[t[1]] & on_box[t[2]]) != 0) drop[f] = 1, any = true;
    }
    if (any) {
      plc.dropped_triangles += static_cast<uint32_t>(std::count(drop.begin(), drop.end(), 1));
      st = Without(st, drop);
    }
  }

  // Compact the used vertices; the 8 box corners go first.
  std::vector<uint32_t> index(v.size(), UINT32_MAX);
  for (int c = 0; c < 8; ++c) {
    plc.vertices.push_back(
        placement.ToPhysical(Vec3(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z)));
  }
  for (const Face& t : st.faces) {
    Face out;
    for (int k = 0; k < 3; ++k) {
      if (index[t[k]] == UINT32_MAX) {
        index[t[k]] = static_cast<uint32_t>(plc.vertices.size());
        plc.vertices.push_back(placement.ToPhysical(v[t[k]]));
      }
      out[k] = index[t[k]];
    }
    const size_t f = plc.sheet_triangles.size();
    plc.sheet_triangles.push_back(out);
    plc.sheet_piece.push_back(st.piece[f]);
    plc.sheet_thickness.push_back(st.thickness[f]);
  }
  const double median_edge = PhysicalLength(median_edge_voxels, placement);
  // Points of the box's surface, when TetGen may add none there.
  std::vector<BoxPoint> box_points;
  const uint32_t first_box_point = static_cast<uint32_t>(plc.vertices.size());
  const LatticeLevels levels =
      GradeLattice(plc.box_lo, plc.box_hi,
                   (options.lattice > 0 ? options.lattice : 1.0) * median_edge, options.grading);
  const double jitter = kSeedJitterVoxels * plc.voxel_length;
  if (options.seed_box && !levels.spacing.empty()) {
    box_points = SeedBox(plc, levels);
    for (size_t i = 0; i < box_points.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        if (!(box_points[i].on_face & (3 << (2 * k)))) box_points[i].p[k] += jitter * Jitter(i, k);
      }
    }
    for (const BoxPoint& b : box_points) plc.vertices.push_back(b.p);
    plc.box_points = static_cast<uint32_t>(box_points.size());
  }
  for (int face = 0; face < 6; ++face) {
    plc.facets.push_back(
        BoxFacet(face, plc, v, on_box, index, st.faces, box_points, first_box_point, placement));
  }
  for (size_t t = 0; t < plc.sheet_triangles.size(); ++t) {
    const Face& f = plc.sheet_triangles[t];
    plc.facets.push_back({{{f[0], f[1], f[2]}}, kFirstSheetMarker + static_cast<int32_t>(t)});
  }
  if (options.lattice > 0 && !levels.spacing.empty()) {
    plc.lattice_spacing = levels.spacing.front();
    plc.lattice_levels = static_cast<uint32_t>(levels.spacing.size());
    plc.lattice_coarsest = levels.spacing.back();
    std::vector<Vec3> seeds = SeedLattice(plc, levels);
    for (size_t i = 0; i < seeds.size(); ++i) {
      for (int k = 0; k < 3; ++k) seeds[i][k] += jitter * Jitter(box_points.size() + i, k);
    }
    plc.seed_points = static_cast<uint32_t>(seeds.size());
    plc.vertices.insert(plc.vertices.end(), seeds.begin(), seeds.end());
  }
  return plc;
}

}  // namespace sheetmesh
