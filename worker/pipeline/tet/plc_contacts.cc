// Mends contacts between sheets: a sheet vertex within a voxel or so of another sheet's
// face, edge or vertex without being joined to it. TetGen must fill the gap, a fraction of
// a voxel wide, with tetrahedra as flat as the gap is narrow; nothing after can mend them,
// since every point it could add lands as close. In the image the two sheets touch.
#include <algorithm>
#include <array>
#include <cmath>
#include <queue>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

// Where a vertex touches a triangle: onto its corner k, onto its edge k (corners k and
// k + 1) at `at`, or into its interior at `at`.
struct Contact {
  enum Kind { kCorner, kEdge, kInterior } kind = kInterior;
  uint32_t vertex = 0;               // the sheet vertex that moves
  uint32_t face = 0;                 // the triangle it touches
  int k = 0;                         // the corner or edge
  Vec3 at;                           // where the vertex goes
  double distance = 0;               // how far that is
  std::vector<uint32_t> edge_faces;  // kEdge: the faces on that edge, which split too
};

// The contact of p with triangle t, if p lies within gap of it: a corner within gap of p's
// nearest point goes first, then an edge, else the interior.
bool FindContact(const Vec3& p, const Triangle& t, double gap, Contact* c) {
  double u, w, x;
  Vec3 q;
  if (ProjectBarycentric(p, t, &u, &w, &x) && u > 0 && w > 0 && x > 0) {
    q = t[0] * u + t[1] * w + t[2] * x;
  } else {
    double best = 1e300;
    for (int k = 0; k < 3; ++k) {
      const Vec3 e = ClosestOnSegment(p, t[k], t[(k + 1) % 3]);
      if (Norm2(e - p) < best) best = Norm2(e - p), q = e;
    }
  }
  if (!(Norm2(q - p) < gap * gap)) return false;
  for (int k = 0; k < 3; ++k) {
    if (Norm2(t[k] - q) < gap * gap) {
      c->kind = Contact::kCorner, c->k = k, c->at = t[k];
      c->distance = Norm(t[k] - p);
      return true;
    }
  }
  for (int k = 0; k < 3; ++k) {
    const Vec3 e = ClosestOnSegment(q, t[k], t[(k + 1) % 3]);
    if (Norm2(e - q) < gap * gap) {
      c->kind = Contact::kEdge, c->k = k, c->at = e;
      c->distance = Norm(e - p);
      return true;
    }
  }
  c->kind = Contact::kInterior, c->at = q;
  c->distance = Norm(q - p);
  return true;
}

// FindContact for vertex u on the box (on_face[u] != 0) against triangle t: only t's edges
// lying in every box face u is on, and their corners, count, so that u moved there stays
// on the box.
bool FindContactOnBox(uint32_t u, const Face& t, const std::vector<Vec3>& v,
                      const std::vector<uint8_t>& on_face, double gap, Contact* c) {
  const uint8_t faces = on_face[u];
  auto in_faces = [&](uint32_t x) { return (on_face[x] & faces) == faces; };
  const Vec3& p = v[u];
  double best = gap * gap;
  int edge = -1;
  Vec3 q;
  for (int k = 0; k < 3; ++k) {
    const uint32_t a = t[k], b = t[(k + 1) % 3];
    if (!in_faces(a) || !in_faces(b)) continue;
    const Vec3 e = ClosestOnSegment(p, v[a], v[b]);
    if (Norm2(e - p) < best) best = Norm2(e - p), q = e, edge = k;
  }
  if (edge < 0) return false;
  for (const int k : {edge, (edge + 1) % 3}) {
    if (Norm2(v[t[k]] - q) < gap * gap) {
      c->kind = Contact::kCorner, c->k = k, c->at = v[t[k]];
      c->distance = Norm(v[t[k]] - p);
      return true;
    }
  }
  c->kind = Contact::kEdge, c->k = edge, c->at = q;
  c->distance = Norm(q - p);
  return true;
}

// Appends a copy of face f's attributes for a new face.
void AddFace(SheetTriangles& s, uint32_t f, const Face& face) {
  s.faces.push_back(face);
  s.source.push_back(s.source[f]);
  s.piece.push_back(s.piece[f]);
  s.thickness.push_back(s.thickness[f]);
}

// Applies the contacts to copies of s and v: the vertex moves onto the corner (merging into
// it), the edge (splitting the faces on it in two) or the interior (splitting the face in
// three). Faces that collapse in a merge go. `owner` gets, per output face, the contact
// that made or moved it (-1: none).
void Apply(const std::vector<Contact>& contacts, SheetTriangles& s, std::vector<Vec3>& v,
           std::vector<int>& owner) {
  owner.assign(s.faces.size(), -1);
  std::vector<uint32_t> into(v.size());
  for (uint32_t i = 0; i < v.size(); ++i) into[i] = i;
  std::vector<int> contact_of(v.size(), -1);  // the contact a vertex moves in
  for (size_t i = 0; i < contacts.size(); ++i) {
    const Contact& c = contacts[i];
    contact_of[c.vertex] = static_cast<int>(i);
    if (c.kind == Contact::kCorner) into[c.vertex] = s.faces[c.face][c.k];
  }
  auto add = [&](uint32_t f, const Face& face, int by) {
    AddFace(s, f, face);
    owner.push_back(by);
  };
  for (size_t i = 0; i < contacts.size(); ++i) {
    const Contact& c = contacts[i];
    const int by = static_cast<int>(i);
    // (No other contact of the round touches c's faces, so they are as found.)
    const Face t = s.faces[c.face];
    if (c.kind == Contact::kCorner) continue;
    v[c.vertex] = c.at;
    if (c.kind == Contact::kInterior) {
      // (a, b, c) -> (a, b, u), (b, c, u), (c, a, u): the same orientation.
      s.faces[c.face] = {t[0], t[1], c.vertex};
      owner[c.face] = by;
      add(c.face, {t[1], t[2], c.vertex}, by);
      add(c.face, {t[2], t[0], c.vertex}, by);
      continue;
    }
    SplitEdgeFaces(t[c.k], t[(c.k + 1) % 3], c.vertex, c.edge_faces, by, s, owner);
  }
  std::vector<uint8_t> drop(s.faces.size(), 0);
  // Merges re-point the faces; those left with a repeated corner, or repeating another
  // face, go. The faces of a moved vertex belong to its contact.
  absl::flat_hash_set<std::array<uint32_t, 3>> seen;
  for (size_t f = 0; f < s.faces.size(); ++f) {
    Face& g = s.faces[f];
    for (uint32_t& x : g) {
      if (contact_of[x] >= 0 && owner[f] < 0) owner[f] = contact_of[x];
      x = into[x];
    }
    std::array<uint32_t, 3> key = {g[0], g[1], g[2]};
    std::sort(key.begin(), key.end());
    if (g[0] == g[1] || g[1] == g[2] || g[0] == g[2] || !seen.insert(key).second) drop[f] = 1;
  }
  std::vector<int> kept;
  for (size_t f = 0; f < s.faces.size(); ++f) {
    if (!drop[f]) kept.push_back(owner[f]);
  }
  s = Without(s, drop);
  owner = std::move(kept);
}

// Applies the contacts of a round to s and v, leaving out those whose faces then clash
// (their vertices marked `failed`) until none do; none at all where a clash is no
// contact's. Returns the number applied.
uint32_t ApplyWithoutClashes(const std::vector<Contact>& contacts, SheetTriangles& s,
                             std::vector<Vec3>& v, std::vector<uint8_t>& failed) {
  std::vector<size_t> left_out;
  const uint32_t made = ApplyLeavingClashesOut(
      contacts.size(),
      [&](const std::vector<size_t>& kept, SheetTriangles& out, std::vector<Vec3>& moved,
          std::vector<int>& owner) {
        std::vector<Contact> these;
        for (size_t i : kept) these.push_back(contacts[i]);
        Apply(these, out, moved, owner);
      },
      s, v, &left_out);
  for (size_t i : left_out) failed[contacts[i].vertex] = 1;
  return made;
}

}  // namespace

uint32_t MendContacts(SheetTriangles& s, std::vector<Vec3>& v, std::vector<uint8_t>& on_face,
                      const std::vector<uint8_t>& held, double gap, bool zip_rims,
                      std::vector<Vec3>* unmended, uint32_t* edge_contacts) {
  if (!(gap > 0) || s.faces.empty()) return 0;
  uint32_t mended = 0;
  std::vector<uint8_t> failed(v.size(), 0);
  // A vertex near another sheet with a neighbour that is too (a rim along it) waits: the
  // edge contacts of a later round may join its neighbours there, making it a point's. It
  // moves then only beside a joint: its neighbours moved one by one would lay its edges
  // across the other sheet's triangles all the same (the DPM junction at r = 3, 10.8 to
  // 6.4 degrees). Without zip_rims it is given up at once.
  std::vector<uint8_t> along_line(v.size(), 0), was_line(v.size(), 0);
  const size_t first_joint = v.size();  // the edge contacts' joints come after
  constexpr int kRounds = 6;
  for (int round = 0; round < kRounds; ++round) {
    const uint32_t joined_edges = zip_rims ? MendEdgeContacts(s, v, on_face, gap) : 0;
    if (edge_contacts != nullptr) *edge_contacts += joined_edges;
    failed.resize(v.size(), 0);
    was_line.resize(v.size(), 0);
    along_line.assign(v.size(), 0);
    // The triangles in a grid; each vertex's faces and neighbours.
    const SheetIndex index = IndexSheets(s, v, gap);
    const std::vector<std::vector<uint32_t>>& faces_of = index.faces_of;
    const auto& edge = index.edge_faces;
    const SpatialGrid& grid = index.grid;
    auto joined = [&](uint32_t a, uint32_t b) { return edge.contains(EdgeKey(a, b)); };
    auto normal = [&](const Face& t) {
      const Vec3 n = Cross(v[t[1]] - v[t[0]], v[t[2]] - v[t[0]]);
      const double len = Norm(n);
      return len > 0 ? n * (1 / len) : n;
    };
    const double steep_cos = std::cos(kSteepRimDegrees * 3.14159265358979323846 / 180);
    // Each free vertex's nearest contact with a triangle not its own, nor one it reaches
    // along the sheets as a wedge of kWedgeKeptDegrees or more.
    const double wedge_sine = std::sin(kWedgeKeptDegrees * 3.14159265358979323846 / 180);
    std::vector<Contact> found;
    for (uint32_t u = 0; u < v.size(); ++u) {
      if (faces_of[u].empty() || failed[u]) continue;
      if (u < held.size() && held[u]) continue;
      Contact best;
      best.distance = 1e300;
      absl::flat_hash_map<uint32_t, double> reach;  // ReachAlongSheets as a map
      bool reached = false;
      // u on a rim next to a joint the edge contacts made (index first_joint or more).
      bool by_joint = false;
      for (uint32_t f : faces_of[u]) {
        for (int k = 0; k < 3; ++k) {
          const uint32_t a = s.faces[f][k], b = s.faces[f][(k + 1) % 3];
          const uint32_t x = a == u ? b : b == u ? a : UINT32_MAX;
          by_joint = by_joint ||
                     (x != UINT32_MAX && x >= first_joint && edge.at(EdgeKey(a, b)).size() == 1);
        }
      }
      if (was_line[u] && !by_joint) {
        along_line[u] = 1;
        continue;
      }
      grid.Query(v[u] - Vec3(gap, gap, gap), v[u] + Vec3(gap, gap, gap), [&](uint32_t f) {
        const Face& t = s.faces[f];
        if (t[0] == u || t[1] == u || t[2] == u) return;
        Contact c;
        if (on_face[u] != 0) {
          // A vertex on the box stays on it: it meets only t's corners and edges that lie in
          // every box face it is on (two sheets' rims on a face passing close).
          if (!FindContactOnBox(u, t, v, on_face, gap, &c) || !(c.distance < best.distance)) return;
        } else if (!FindContact(v[u], {v[t[0]], v[t[1]], v[t[2]]}, gap, &c) ||
                   !(c.distance < best.distance)) {
          return;
        }
        // A rim vertex next to a joint, its faces all standing steeply on t, is no wedge
        // with t, however soon the sheets reach it through the joint: moving it lays the
        // rim on t at the faces' own angle. (Without the joint, rims near a junction moved
        // and made slivers: the planar junction at r = 3, 15.3 to 6.7 degrees.)
        bool steep = zip_rims && by_joint;
        const Vec3 nt = normal(t);
        for (uint32_t g : faces_of[u])
          steep = steep && std::abs(Dot(normal(s.faces[g]), nt)) <= steep_cos;
        if (!reached && !steep) {
          for (const auto& [x, d] :
               ReachAlongSheets(u, kReachFactor * gap / wedge_sine, v, s.faces, faces_of)) {
            reach[x] = d;
          }
          reached = true;
        }
        // On the box, a slit: u and t's edge there both reach a neighbour w of u, the two
        // meeting at w under kWedgeKeptDegrees (a sheet's rim and its own triangle folded
        // down to the box beside it, NETL at r = 2: 6 degrees). That is no wedge to keep.
        bool slit = false;
        if (on_face[u] != 0) {
          for (uint32_t w : t) {
            const Vec3 a = v[u] - v[w], b = c.at - v[w];
            slit = slit || (joined(u, w) && Norm(Cross(a, b)) < wedge_sine * Norm(a) * Norm(b) &&
                            Dot(a, b) > 0);
          }
        }
        for (uint32_t x : t) {
          const auto it = reach.find(x);
          if (!steep && !slit && it != reach.end() &&
              it->second + Norm(v[x] - c.at) <= kReachFactor * c.distance / wedge_sine) {
            return;
          }
        }
        // Not onto a neighbour's corner (that collapses an edge of u's own sheet).
        if (c.kind == Contact::kCorner && joined(u, t[c.k])) return;
        // Not onto an edge of u's own triangle (a flat one: the flips' business).
        if (c.kind == Contact::kEdge && joined(u, t[c.k]) && joined(u, t[(c.k + 1) % 3])) return;
        c.vertex = u, c.face = f;
        best = c;
      });
      if (best.distance < 1e300) found.push_back(best);
    }
    if (found.empty() && joined_edges == 0) break;
    // A contact along a line, u and a neighbour both near the other sheet (a rim running
    // over it), is not a point's: moving u would lay its edges on that sheet, or leave
    // them in a wedge over it. It stays, and is reported. Neighbours that both land on
    // corners lay their edge onto the other sheet's edge, or across it (the clash check
    // tells).
    {
      std::vector<int8_t> kind(v.size(), -1);
      for (const Contact& c : found) kind[c.vertex] = static_cast<int8_t>(c.kind);
      std::vector<Contact> points;
      for (const Contact& c : found) {
        bool line = false;
        for (uint32_t f : faces_of[c.vertex]) {
          for (uint32_t x : s.faces[f]) {
            if (x == c.vertex || kind[x] < 0) continue;
            line = line || c.kind != Contact::kCorner || kind[x] != Contact::kCorner;
          }
        }
        if (line) {
          (zip_rims ? along_line : failed)[c.vertex] = 1;
          was_line[c.vertex] = 1;
        } else {
          points.push_back(c);
        }
      }
      found = std::move(points);
    }
    if (found.empty() && joined_edges == 0) break;
    // Nearest first; each vertex and face takes part in one contact a round.
    std::sort(found.begin(), found.end(),
              [](const Contact& a, const Contact& b) { return a.distance < b.distance; });
    std::vector<uint8_t> busy_vertex(v.size(), 0), busy_face(s.faces.size(), 0);
    std::vector<Contact> round_contacts;
    for (Contact& c : found) {
      const Face& t = s.faces[c.face];
      bool busy = busy_vertex[c.vertex] || busy_face[c.face] || busy_vertex[t[0]] ||
                  busy_vertex[t[1]] || busy_vertex[t[2]];
      for (uint32_t f : faces_of[c.vertex]) busy = busy || busy_face[f];
      if (c.kind == Contact::kEdge) {
        // The faces on the edge split too.
        for (uint32_t f : faces_of[t[c.k]]) busy = busy || busy_face[f];
      }
      if (busy) continue;
      busy_vertex[c.vertex] = 1;
      for (uint32_t x : t) busy_vertex[x] = 1;
      busy_face[c.face] = 1;
      for (uint32_t f : faces_of[c.vertex]) busy_face[f] = 1;
      if (c.kind == Contact::kEdge) {
        const uint32_t b = t[(c.k + 1) % 3];
        for (uint32_t f : faces_of[t[c.k]]) {
          busy_face[f] = 1;
          const Face& g = s.faces[f];
          if (g[0] == b || g[1] == b || g[2] == b) c.edge_faces.push_back(f);
        }
      }
      round_contacts.push_back(c);
    }
    mended += ApplyWithoutClashes(round_contacts, s, v, failed);
  }
  // What is left: vertices still within gap of a triangle not their own.
  if (unmended != nullptr) {
    for (uint32_t u = 0; u < v.size(); ++u) {
      if (failed[u] || along_line[u]) unmended->push_back(v[u]);
    }
  }
  return mended;
}

uint32_t CloseCaps(SheetTriangles& s, std::vector<Vec3>& v, const std::vector<uint8_t>& on_face,
                   double cap_degrees, double max_move) {
  if (!(cap_degrees < 180) || !(max_move > 0)) return 0;
  const double max_cos = std::cos(cap_degrees * 3.14159265358979323846 / 180);
  uint32_t closed = 0;
  std::vector<uint8_t> failed(v.size(), 0);
  for (int round = 0; round < 4 && !s.faces.empty(); ++round) {
    std::vector<std::vector<uint32_t>> faces_of(v.size());
    for (uint32_t f = 0; f < s.faces.size(); ++f) {
      for (uint32_t x : s.faces[f]) faces_of[x].push_back(f);
    }
    // Each cap: its wide corner c (off the box), the long edge a-b, c's foot on it.
    std::vector<Contact> found;
    for (uint32_t f = 0; f < s.faces.size(); ++f) {
      const Face& t = s.faces[f];
      for (int k = 0; k < 3; ++k) {
        const uint32_t c = t[k], a = t[(k + 1) % 3], b = t[(k + 2) % 3];
        if (on_face[c] != 0 || failed[c]) continue;
        const Vec3 ca = v[a] - v[c], cb = v[b] - v[c];
        if (!(Dot(ca, cb) < max_cos * Norm(ca) * Norm(cb))) continue;
        Contact cap;
        cap.kind = Contact::kEdge;
        cap.vertex = c;
        cap.face = f;
        cap.k = (k + 1) % 3;  // the edge from t[k + 1] = a to t[k + 2] = b
        cap.at = ClosestOnSegment(v[c], v[a], v[b]);
        cap.distance = Norm(cap.at - v[c]);
        if (!(cap.distance <= max_move)) continue;
        for (uint32_t g : faces_of[a]) {
          const Face& h = s.faces[g];
          if (h[0] == b || h[1] == b || h[2] == b) cap.edge_faces.push_back(g);
        }
        found.push_back(cap);
      }
    }
    if (found.empty()) break;
    // Lowest first; a vertex and a face take part in one a round.
    std::sort(found.begin(), found.end(),
              [](const Contact& x, const Contact& y) { return x.distance < y.distance; });
    std::vector<uint8_t> busy_vertex(v.size(), 0), busy_face(s.faces.size(), 0);
    std::vector<Contact> round_caps;
    for (const Contact& c : found) {
      bool busy = busy_vertex[c.vertex];
      for (uint32_t g : c.edge_faces) {
        for (uint32_t x : s.faces[g]) busy = busy || busy_vertex[x];
      }
      for (uint32_t g : faces_of[c.vertex]) busy = busy || busy_face[g];
      for (uint32_t g : c.edge_faces) busy = busy || busy_face[g];
      if (busy) continue;
      for (uint32_t g : c.edge_faces) {
        busy_face[g] = 1;
        for (uint32_t x : s.faces[g]) busy_vertex[x] = 1;
      }
      for (uint32_t g : faces_of[c.vertex]) busy_face[g] = 1;
      busy_vertex[c.vertex] = 1;
      round_caps.push_back(c);
    }
    const uint32_t n = ApplyWithoutClashes(round_caps, s, v, failed);
    if (n == 0 && round_caps.size() == found.size()) break;
    closed += n;
  }
  return closed;
}

uint32_t JoinTouches(SheetTriangles& s, std::vector<Vec3>& v, double eps) {
  uint32_t joined = 0;
  for (int round = 0; round < 8 && !s.faces.empty(); ++round) {
    std::vector<std::vector<uint32_t>> faces_of(v.size());
    double longest = eps;
    for (uint32_t f = 0; f < s.faces.size(); ++f) {
      for (int k = 0; k < 3; ++k) {
        faces_of[s.faces[f][k]].push_back(f);
        longest = std::max(longest, Norm(v[s.faces[f][k]] - v[s.faces[f][(k + 1) % 3]]));
      }
    }
    SpatialGrid grid(longest);
    for (uint32_t f = 0; f < s.faces.size(); ++f) {
      Vec3 lo, hi;
      TriangleBox({v[s.faces[f][0]], v[s.faces[f][1]], v[s.faces[f][2]]}, eps, &lo, &hi);
      grid.Insert(f, lo, hi);
    }
    // Each vertex lying on a triangle not its own: on its edge or inside it (a corner that
    // close is a duplicate, the merge's business).
    std::vector<Contact> found;
    for (uint32_t u = 0; u < v.size(); ++u) {
      if (faces_of[u].empty()) continue;
      bool taken = false;
      grid.Query(v[u] - Vec3(eps, eps, eps), v[u] + Vec3(eps, eps, eps), [&](uint32_t f) {
        const Face& t = s.faces[f];
        if (taken || t[0] == u || t[1] == u || t[2] == u) return;
        Contact c;
        if (!FindContact(v[u], {v[t[0]], v[t[1]], v[t[2]]}, eps, &c) ||
            c.kind == Contact::kCorner) {
          return;
        }
        c.vertex = u, c.face = f;
        found.push_back(c);
        taken = true;
      });
    }
    if (found.empty()) break;
    // Each face split once a round (its edge's faces too).
    std::vector<uint8_t> busy(s.faces.size(), 0);
    std::vector<Contact> apply;
    for (Contact& c : found) {
      const Face& t = s.faces[c.face];
      std::vector<uint32_t> touched = {c.face};
      if (c.kind == Contact::kEdge) {
        const uint32_t a = t[c.k], b = t[(c.k + 1) % 3];
        for (uint32_t f : faces_of[a]) {
          const Face& g = s.faces[f];
          if (g[0] == b || g[1] == b || g[2] == b) c.edge_faces.push_back(f);
        }
        touched = c.edge_faces;
      }
      // The faces of the vertex itself re-point nothing (it stays), but a face both on
      // the edge and at the vertex would fold: such a touch is a clash, not a T.
      bool skip = false;
      for (uint32_t f : touched) {
        skip = skip || busy[f];
        for (uint32_t x : s.faces[f]) skip = skip || x == c.vertex;
      }
      if (skip) continue;
      for (uint32_t f : touched) busy[f] = 1;
      apply.push_back(c);
    }
    if (apply.empty()) break;
    std::vector<int> owner;
    Apply(apply, s, v, owner);
    joined += static_cast<uint32_t>(apply.size());
  }
  return joined;
}

uint32_t DropFlatTriangles(SheetTriangles& s, const std::vector<Vec3>& v, double eps) {
  std::vector<uint8_t> drop(s.faces.size(), 0);
  uint32_t n = 0;
  for (size_t f = 0; f < s.faces.size(); ++f) {
    const Vec3 &a = v[s.faces[f][0]], &b = v[s.faces[f][1]], &c = v[s.faces[f][2]];
    const double longest = std::max({Norm(b - a), Norm(c - b), Norm(a - c)});
    // Twice the area is the longest edge times the height over it.
    if (Norm(Cross(b - a, c - a)) <= eps * longest) drop[f] = 1, ++n;
  }
  if (n > 0) s = Without(s, drop);
  return n;
}

std::array<Face, 2> HalvesAt(const Face& t, uint32_t a, uint32_t b, uint32_t w) {
  // (.. a .. b ..) -> (.. a .. w ..) and (.. w .. b ..): the same orientation.
  Face first = t, second = t;
  for (int k = 0; k < 3; ++k) {
    if (t[k] == b) first[k] = w;
    if (t[k] == a) second[k] = w;
  }
  return {first, second};
}

void SplitEdgeFaces(uint32_t a, uint32_t b, uint32_t w, const std::vector<uint32_t>& on_edge,
                    int by, SheetTriangles& s, std::vector<int>& owner) {
  for (uint32_t f : on_edge) {
    const std::array<Face, 2> halves = HalvesAt(s.faces[f], a, b, w);
    s.faces[f] = halves[0];
    owner[f] = by;
    AddFace(s, f, halves[1]);
    owner.push_back(by);
  }
}

}  // namespace sheetmesh
