#include "worker/pipeline/tet/tet_mesh_editor.h"

#include <algorithm>
#include <atomic>

#include "worker/pipeline/tet/tet_quality.h"

namespace sheetmesh {

TetMeshEditor::TetMeshEditor(TetMesh* mesh) : m_(*mesh) {
  const size_t n = m_.nodes.size();
  star_.resize(n);
  changed_.assign(n, 0);
  q_.resize(m_.tets.size());
  dead_.assign(m_.tets.size(), 0);
  failed_.assign(m_.tets.size(), 0);
  neighbor_.assign(m_.tets.size(), {kUnknown, kUnknown, kUnknown, kUnknown});
  for (uint32_t t = 0; t < m_.tets.size(); ++t) {
    for (uint32_t v : m_.tets[t]) star_[v].push_back(t);
    q_[t] = Quality(m_.tets[t]);
  }
  sheet_faces_of_.resize(n);
  for (uint32_t f = 0; f < m_.faces.size(); ++f) {
    const auto& face = m_.faces[f];
    constrained_[SortedFace(face[0], face[1], face[2])] = f;
    if (m_.face_piece[f] >= 0) {
      for (uint32_t v : face) sheet_faces_of_[v].push_back(f);
    }
  }
}

uint32_t TetMeshEditor::AddNode(const Vec3& p) {
  const uint32_t v = num_nodes();
  m_.nodes.push_back(p);
  star_.emplace_back();
  changed_.push_back(clock_);
  sheet_faces_of_.emplace_back();
  return v;
}

void TetMeshEditor::Remeasure(uint32_t t) {
  q_[t] = Quality(m_.tets[t]);
  failed_[t] = 0;
  Stamp(m_.tets[t]);
}

double TetMeshEditor::Quality(const Tet& t) const {
  return MinDihedralDegrees(P(t[0]), P(t[1]), P(t[2]), P(t[3]));
}

void TetMeshEditor::Kill(uint32_t t) {
  dead_[t] = 1;
  Stamp(m_.tets[t]);
  for (uint32_t v : m_.tets[t]) {
    auto& s = star_[v];
    auto it = std::find(s.begin(), s.end(), t);
    *it = s.back();
    s.pop_back();
  }
  free_.push_back(t);
}

void TetMeshEditor::Add(const Tet& tet) {
  uint32_t t;
  if (!free_.empty()) {
    t = free_.back();
    free_.pop_back();
    m_.tets[t] = tet;
    dead_[t] = 0;
    failed_[t] = 0;
    neighbor_[t] = {kUnknown, kUnknown, kUnknown, kUnknown};
    q_[t] = Quality(tet);
  } else {
    t = static_cast<uint32_t>(m_.tets.size());
    m_.tets.push_back(tet);
    dead_.push_back(0);
    failed_.push_back(0);
    neighbor_.push_back({kUnknown, kUnknown, kUnknown, kUnknown});
    q_.push_back(Quality(tet));
  }
  for (uint32_t v : tet) star_[v].push_back(t);
  Stamp(tet);
}

const uint32_t* TetMeshEditor::FacetFaceIndex(const FaceKey& face) const {
  const auto it = constrained_.find(face);
  return it == constrained_.end() ? nullptr : &it->second;
}

uint32_t TetMeshEditor::Neighbor(uint32_t t, int f) const {
  const Tet& tet = m_.tets[t];
  const uint32_t a = tet[(f + 1) % 4], b = tet[(f + 2) % 4], c = tet[(f + 3) % 4];
  // The memo is read and written through relaxed atomics: look-ups from several threads
  // (the insertion's candidates) may fill it at once, and all of them write the one
  // neighbour the mesh has there.
  const uint32_t known = std::atomic_ref<uint32_t>(neighbor_[t][f]).load(std::memory_order_relaxed);
  if (known != kUnknown && !dead_[known]) {
    const Tet& k = m_.tets[known];
    if (Has(k, a) && Has(k, b) && Has(k, c)) return known;
  }
  for (uint32_t s : star_[a]) {
    if (s != t && Has(m_.tets[s], b) && Has(m_.tets[s], c)) {
      std::atomic_ref<uint32_t>(neighbor_[t][f]).store(s, std::memory_order_relaxed);
      // And t is s's neighbour across the same face (the corner of s not on it).
      const Tet& st = m_.tets[s];
      for (int g = 0; g < 4; ++g) {
        if (st[g] != a && st[g] != b && st[g] != c) {
          std::atomic_ref<uint32_t>(neighbor_[s][g]).store(t, std::memory_order_relaxed);
        }
      }
      return s;
    }
  }
  return UINT32_MAX;
}

std::array<uint32_t, 3> TetMeshEditor::InwardFace(uint32_t t, int f) const {
  const Tet& tet = m_.tets[t];
  std::array<uint32_t, 3> face = {tet[(f + 1) % 4], tet[(f + 2) % 4], tet[(f + 3) % 4]};
  if (TetVolume(P(face[0]), P(face[1]), P(face[2]), P(tet[f])) < 0) std::swap(face[0], face[1]);
  return face;
}

std::pair<double, double> TetMeshEditor::MinMean() const {
  double mn = 1e300, sum = 0;
  size_t count = 0;
  for (size_t t = 0; t < q_.size(); ++t) {
    if (dead_[t]) continue;
    mn = std::min(mn, q_[t]);
    sum += q_[t];
    ++count;
  }
  return {count ? mn : 0.0, count ? sum / count : 0.0};
}

std::vector<uint32_t> TetMeshEditor::Bad(double target) const {
  std::vector<uint32_t> bad;
  for (uint32_t t = 0; t < q_.size(); ++t) {
    if (!dead_[t] && q_[t] < target) bad.push_back(t);
  }
  std::sort(bad.begin(), bad.end(), [&](uint32_t a, uint32_t b) { return q_[a] < q_[b]; });
  return bad;
}

double TetMeshEditor::StarMin(uint32_t v) const {
  double mn = 1e300;
  for (uint32_t t : star_[v]) mn = std::min(mn, q_[t]);
  return mn;
}

void TetMeshEditor::ContractSheetFaces(uint32_t v, uint32_t w) {
  const std::vector<uint32_t> at_v = sheet_faces_of_[v];
  face_gone_.resize(m_.faces.size(), 0);
  for (const uint32_t f : at_v) {
    std::array<uint32_t, 3> face = m_.faces[f];
    constrained_.erase(SortedFace(face[0], face[1], face[2]));
    for (const uint32_t x : face) {
      auto& of = sheet_faces_of_[x];
      of.erase(std::remove(of.begin(), of.end(), f), of.end());
    }
    if (face[0] == w || face[1] == w || face[2] == w) {
      face_gone_[f] = 1;
      continue;
    }
    for (uint32_t& x : face) x = x == v ? w : x;
    m_.faces[f] = face;
    constrained_[SortedFace(face[0], face[1], face[2])] = f;
    for (const uint32_t x : face) sheet_faces_of_[x].push_back(f);
  }
}

void TetMeshEditor::Finish() {
  size_t out = 0;
  for (size_t t = 0; t < m_.tets.size(); ++t) {
    if (!dead_[t]) m_.tets[out++] = m_.tets[t];
  }
  m_.tets.resize(out);
  face_gone_.resize(m_.faces.size(), 0);
  if (std::find(face_gone_.begin(), face_gone_.end(), 1) == face_gone_.end()) return;
  // Every per-face array the mesh has (a test's may lack the thickness).
  const size_t n = m_.faces.size();
  auto compact = [&](auto& a) {
    if (a.size() != n) return;
    size_t kept = 0;
    for (size_t f = 0; f < n; ++f) {
      if (!face_gone_[f]) a[kept++] = a[f];
    }
    a.resize(kept);
  };
  compact(m_.face_marker);
  compact(m_.face_piece);
  compact(m_.face_thickness_voxels);
  compact(m_.faces);
}

}  // namespace sheetmesh
