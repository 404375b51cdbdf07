#include "worker/pipeline/voxel/phase_selection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "worker/pipeline/core/status_macros.h"

namespace sheetmesh {

PhaseSelection PhaseSelection::Labels(std::vector<double> labels) {
  PhaseSelection s;
  s.mode = Mode::kLabels;
  s.labels = std::move(labels);
  return s;
}

PhaseSelection PhaseSelection::Window(double lo, double hi) {
  PhaseSelection s;
  s.mode = Mode::kWindow;
  s.lo = lo;
  s.hi = hi;
  return s;
}

std::string PhaseSelection::ToString() const {
  switch (mode) {
    case Mode::kNonZero:
      return "nonzero";
    case Mode::kLabels:
      return absl::StrCat("labels=", absl::StrJoin(labels, ","));
    case Mode::kWindow:
      return absl::StrCat("window=", lo, ":", hi);
  }
  return "?";
}

absl::StatusOr<PhaseSelection> ParsePhaseSelection(absl::string_view text) {
  absl::string_view t = absl::StripAsciiWhitespace(text);
  if (t == "nonzero" || t.empty()) return PhaseSelection::NonZero();
  const bool window = absl::ConsumePrefix(&t, "window=") || (t.find(':') != t.npos);
  absl::ConsumePrefix(&t, "labels=");
  if (window) {
    std::vector<absl::string_view> parts = absl::StrSplit(t, ':');
    double lo = 0, hi = 0;
    if (parts.size() != 2 || !absl::SimpleAtod(parts[0], &lo) ||
        !absl::SimpleAtod(parts[1], &hi)) {
      return absl::InvalidArgumentError(
          absl::StrCat("selection window '", text, "' must look like LO:HI, e.g. 100:200"));
    }
    if (lo > hi) {
      return absl::InvalidArgumentError(
          absl::StrCat("selection window '", text, "' has lo ", lo, " above hi ", hi));
    }
    return PhaseSelection::Window(lo, hi);
  }
  std::vector<double> labels;
  for (absl::string_view p : absl::StrSplit(t, ',', absl::SkipEmpty())) {
    double v = 0;
    if (!absl::SimpleAtod(absl::StripAsciiWhitespace(p), &v)) {
      return absl::InvalidArgumentError(absl::StrCat("selection label '", p, "' in '", text,
                                                     "' is not a number"));
    }
    labels.push_back(v);
  }
  if (labels.empty()) {
    return absl::InvalidArgumentError(absl::StrCat("selection '", text, "' names no label"));
  }
  return PhaseSelection::Labels(std::move(labels));
}

namespace {

bool Matches(const PhaseSelection& s, double v) {
  switch (s.mode) {
    case PhaseSelection::Mode::kNonZero:
      return v != 0;
    case PhaseSelection::Mode::kLabels:
      return std::find(s.labels.begin(), s.labels.end(), v) != s.labels.end();
    case PhaseSelection::Mode::kWindow:
      return s.lo <= v && v <= s.hi;
  }
  return false;
}

// Appends the runs of selected voxels of one row. For integer types a lookup table makes
// the test one load per voxel.
template <class T, class Pred>
void RowRuns(const T* row, int64_t nx, Pred pred, std::vector<Run>* out) {
  int64_t x = 0;
  while (x < nx) {
    while (x < nx && !pred(row[x])) ++x;
    if (x >= nx) break;
    const int64_t start = x;
    while (x < nx && pred(row[x])) ++x;
    out->push_back({static_cast<int32_t>(start), static_cast<int32_t>(x)});
  }
}

template <class T>
absl::StatusOr<VoxelSet> SelectTyped(VolumeSource& source, const PhaseSelection& selection,
                                     const VoxelSet* mask, SelectionStats* stats,
                                     const Progress& progress) {
  const Dims& d = source.info().dims;
  // Slabs of at most ~32 MiB keep the buffer small whatever the box.
  const int64_t slice_bytes = d.nx * d.ny * static_cast<int64_t>(sizeof(T));
  const int64_t slab = std::clamp<int64_t>((int64_t{32} << 20) / std::max<int64_t>(1, slice_bytes),
                                           1, d.nz);
  std::vector<T> buffer(static_cast<size_t>(slab * d.nx * d.ny));
  VoxelSet::Builder builder(d);
  std::vector<Run> runs, masked;
  T lo = std::numeric_limits<T>::max();
  T hi = std::numeric_limits<T>::lowest();

  // For 8- and 16-bit voxels the selection is a table over all values.
  std::vector<uint8_t> table;
  if constexpr (std::is_integral_v<T>) {
    static_assert(sizeof(T) <= 2, "integer voxels are 8 or 16 bit");
    table.resize(size_t{1} << (8 * sizeof(T)));
    for (size_t v = 0; v < table.size(); ++v) table[v] = Matches(selection, double(v)) ? 1 : 0;
  }
  for (int64_t z0 = 0; z0 < d.nz; z0 += slab) {
    const int64_t count = std::min(slab, d.nz - z0);
    std::span<std::byte> bytes(reinterpret_cast<std::byte*>(buffer.data()),
                               static_cast<size_t>(count * slice_bytes));
    SM_RETURN_IF_ERROR(source.ReadSlices(z0, count, bytes));
    for (int64_t k = 0; k < count; ++k) {
      const int64_t z = z0 + k;
      for (int64_t y = 0; y < d.ny; ++y) {
        const T* row = buffer.data() + (k * d.ny + y) * d.nx;
        for (int64_t x = 0; x < d.nx; ++x) {
          lo = std::min(lo, row[x]);
          hi = std::max(hi, row[x]);
        }
        runs.clear();
        if constexpr (std::is_integral_v<T>) {
          const uint8_t* tab = table.data();
          RowRuns(row, d.nx, [tab](T v) { return tab[v] != 0; }, &runs);
        } else {
          RowRuns(row, d.nx, [&selection](T v) { return Matches(selection, v); }, &runs);
        }
        if (runs.empty()) continue;
        const std::vector<Run>* keep = &runs;
        if (mask != nullptr) {
          masked.clear();
          IntersectRuns(runs, mask->RowRuns(y, z), &masked);
          if (stats != nullptr) {
            uint64_t before = 0, after = 0;
            for (const Run& r : runs) before += r.length();
            for (const Run& r : masked) after += r.length();
            stats->outside_mask += before - after;
          }
          keep = &masked;
        }
        for (const Run& r : *keep) builder.AddRun(y, z, r.x0, r.x1);
      }
    }
    SM_RETURN_IF_ERROR(progress.Update(double(z0 + count) / d.nz));
  }
  VoxelSet set = std::move(builder).Build();
  if (stats != nullptr) {
    stats->min_value = static_cast<double>(lo);
    stats->max_value = static_cast<double>(hi);
    stats->selected = set.size();
  }
  return set;
}

}  // namespace

absl::StatusOr<VoxelSet> SelectPhase(VolumeSource& source, const PhaseSelection& selection,
                                     const VoxelSet* mask, SelectionStats* stats,
                                     const Progress& progress) {
  const VolumeInfo& info = source.info();
  if (mask != nullptr && !(mask->dims() == info.dims)) {
    return absl::InvalidArgumentError(absl::StrCat(info.path, ": rock mask dims ",
                                                   mask->dims().ToString(),
                                                   " differ from the volume's ",
                                                   info.dims.ToString()));
  }
  if (stats != nullptr) *stats = SelectionStats();
  switch (info.dtype) {
    case DType::kUInt8:
      return SelectTyped<uint8_t>(source, selection, mask, stats, progress);
    case DType::kUInt16:
      return SelectTyped<uint16_t>(source, selection, mask, stats, progress);
    case DType::kFloat32:
      return SelectTyped<float>(source, selection, mask, stats, progress);
  }
  return absl::InternalError("unknown dtype");
}

absl::Status CheckNotEmpty(const VoxelSet& set, const VolumeInfo& info,
                           const PhaseSelection& selection, const SelectionStats& stats) {
  if (!set.empty()) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(
      info.path, ": selection ", selection.ToString(), " matched no voxel (values range from ",
      stats.min_value, " to ", stats.max_value,
      stats.outside_mask > 0 ? absl::StrCat("; ", stats.outside_mask, " matched outside the mask")
                             : std::string(),
      ")"));
}

}  // namespace sheetmesh
