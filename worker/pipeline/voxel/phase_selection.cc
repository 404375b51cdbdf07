#include "worker/pipeline/voxel/phase_selection.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "common/status_macros.h"

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
    if (parts.size() != 2 || !absl::SimpleAtod(parts[0], &lo) || !absl::SimpleAtod(parts[1], &hi)) {
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
      return absl::InvalidArgumentError(
          absl::StrCat("selection label '", p, "' in '", text, "' is not a number"));
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
  if (std::isnan(v)) return false;  // no value: never the sheet phase
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

// What one scanning task learns besides the runs: which values it saw (integers) or their
// range (floats).
struct ValueSeen {
  std::vector<uint8_t> seen;  // integer voxels: seen[v] = 1
  float lo = std::numeric_limits<float>::max();
  float hi = std::numeric_limits<float>::lowest();
};

// Appends the runs of selected voxels of one row of 8- or 16-bit voxels. The table holds
// the selection for every value. Stretches of one unselected value (the background of a
// segmented image) are skipped eight bytes at a time.
template <class T>
void ScanIntegerRow(const T* row, int64_t nx, const uint8_t* table, uint8_t* seen,
                    std::vector<Run>* out) {
  constexpr int64_t kPerWord = 8 / sizeof(T);
  int64_t x = 0;
  while (x < nx) {
    const T v = row[x];
    seen[v] = 1;
    if (table[v] == 0) {
      uint64_t pattern = 0;
      for (int64_t k = 0; k < kPerWord; ++k) pattern = (pattern << (8 * sizeof(T))) | v;
      ++x;
      // Four words per step: the compare of their xors is one branch per 32 bytes.
      while (x + 4 * kPerWord <= nx) {
        uint64_t w[4];
        std::memcpy(w, row + x, 32);
        if (((w[0] ^ pattern) | (w[1] ^ pattern) | (w[2] ^ pattern) | (w[3] ^ pattern)) != 0) {
          break;
        }
        x += 4 * kPerWord;
      }
      while (x + kPerWord <= nx) {
        uint64_t w;
        std::memcpy(&w, row + x, 8);
        if (w != pattern) break;
        x += kPerWord;
      }
      continue;
    }
    const int64_t start = x;
    ++x;
    while (x < nx && table[row[x]] != 0) {
      seen[row[x]] = 1;
      ++x;
    }
    out->push_back({static_cast<int32_t>(start), static_cast<int32_t>(x)});
  }
}

void ScanFloatRow(const float* row, int64_t nx, const PhaseSelection& selection, ValueSeen* seen,
                  std::vector<Run>* out) {
  int64_t x = 0;
  while (x < nx) {
    seen->lo = std::min(seen->lo, row[x]);
    seen->hi = std::max(seen->hi, row[x]);
    if (!Matches(selection, row[x])) {
      ++x;
      continue;
    }
    const int64_t start = x;
    while (x < nx && Matches(selection, row[x])) {
      seen->lo = std::min(seen->lo, row[x]);
      seen->hi = std::max(seen->hi, row[x]);
      ++x;
    }
    out->push_back({static_cast<int32_t>(start), static_cast<int32_t>(x)});
  }
}

// Runs of one slice: (y, run) pairs in increasing y.
struct SliceRuns {
  std::vector<std::pair<int32_t, Run>> runs;
  uint64_t outside_mask = 0;
};

template <class T>
absl::StatusOr<VoxelSet> SelectTyped(VolumeSource& source, const PhaseSelection& selection,
                                     const VoxelSet* mask, SelectionStats* stats,
                                     const Progress& progress) {
  const Dims& d = source.info().dims;
  const int64_t slice_bytes = d.nx * d.ny * static_cast<int64_t>(sizeof(T));
  // Slabs of about 32 MiB keep memory flat whatever the box.
  const int64_t slab =
      std::clamp<int64_t>((int64_t{32} << 20) / std::max<int64_t>(1, slice_bytes), 1, d.nz);
  const bool map = source.CanMap();
  std::vector<T> buffer(map ? 0 : static_cast<size_t>(slab * d.nx * d.ny));
  VoxelSet::Builder builder(d);

  std::vector<uint8_t> table;
  if constexpr (std::is_integral_v<T>) {
    static_assert(sizeof(T) <= 2, "integer voxels are 8 or 16 bit");
    table.resize(size_t{1} << (8 * sizeof(T)));
    for (size_t v = 0; v < table.size(); ++v) table[v] = Matches(selection, double(v)) ? 1 : 0;
  }
  ValueSeen all;
  if constexpr (std::is_integral_v<T>) all.seen.assign(table.size(), 0);
  std::vector<SliceRuns> slices(static_cast<size_t>(slab));
  std::vector<ValueSeen> seen_per_slice(static_cast<size_t>(slab));

  for (int64_t z0 = 0; z0 < d.nz; z0 += slab) {
    const int64_t count = std::min(slab, d.nz - z0);
    const T* data = nullptr;
    MappedSlices mapped;
    if (map) {
      SM_ASSIGN_OR_RETURN(mapped, source.MapSlices(z0, count));
      data = reinterpret_cast<const T*>(mapped.data().data());
    } else {
      std::span<std::byte> bytes(reinterpret_cast<std::byte*>(buffer.data()),
                                 static_cast<size_t>(count * slice_bytes));
      SM_RETURN_IF_ERROR(source.ReadSlices(z0, count, bytes));
      data = buffer.data();
    }
    // Slices scan in parallel; their runs are appended in order afterwards.
    tbb::parallel_for(int64_t{0}, count, [&](int64_t k) {
      const int64_t z = z0 + k;
      SliceRuns& out = slices[k];
      out.runs.clear();
      out.outside_mask = 0;
      ValueSeen& seen = seen_per_slice[k];
      if constexpr (std::is_integral_v<T>) {
        if (seen.seen.size() != table.size()) seen.seen.assign(table.size(), 0);
      }
      std::vector<Run> row_runs, masked;
      for (int64_t y = 0; y < d.ny; ++y) {
        const T* row = data + (k * d.ny + y) * d.nx;
        row_runs.clear();
        if constexpr (std::is_integral_v<T>) {
          ScanIntegerRow(row, d.nx, table.data(), seen.seen.data(), &row_runs);
        } else {
          ScanFloatRow(row, d.nx, selection, &seen, &row_runs);
        }
        if (row_runs.empty()) continue;
        const std::vector<Run>* keep = &row_runs;
        if (mask != nullptr) {
          masked.clear();
          IntersectRuns(row_runs, mask->RowRuns(y, z), &masked);
          uint64_t before = 0, after = 0;
          for (const Run& r : row_runs) before += r.length();
          for (const Run& r : masked) after += r.length();
          out.outside_mask += before - after;
          keep = &masked;
        }
        for (const Run& r : *keep) out.runs.push_back({static_cast<int32_t>(y), r});
      }
    });
    for (int64_t k = 0; k < count; ++k) {
      for (const auto& [y, r] : slices[k].runs) builder.AddRun(y, z0 + k, r.x0, r.x1);
      if (stats != nullptr) stats->outside_mask += slices[k].outside_mask;
    }
    SM_RETURN_IF_ERROR(progress.Update(double(z0 + count) / d.nz));
  }
  VoxelSet set = std::move(builder).Build();
  if (stats != nullptr) {
    for (const ValueSeen& s : seen_per_slice) {
      all.lo = std::min(all.lo, s.lo);
      all.hi = std::max(all.hi, s.hi);
      for (size_t v = 0; v < s.seen.size(); ++v) all.seen[v] |= s.seen[v];
    }
    if constexpr (std::is_integral_v<T>) {
      const auto first = std::find(all.seen.begin(), all.seen.end(), 1);
      const auto last = std::find(all.seen.rbegin(), all.seen.rend(), 1);
      stats->min_value = static_cast<double>(first - all.seen.begin());
      stats->max_value = static_cast<double>(all.seen.rend() - last - 1);
    } else {
      stats->min_value = all.lo;
      stats->max_value = all.hi;
    }
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
    return absl::InvalidArgumentError(
        absl::StrCat(info.path, ": rock mask dims ", mask->dims().ToString(),
                     " differ from the volume's ", info.dims.ToString()));
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

std::string SelectionStats::RangeText() const {
  if (!(min_value <= max_value)) return "the volume holds no number: every voxel is NaN";
  return absl::StrCat("values range from ", min_value, " to ", max_value);
}

absl::Status CheckNotEmpty(const VoxelSet& set, const VolumeInfo& info,
                           const PhaseSelection& selection, const SelectionStats& stats) {
  if (!set.empty()) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(
      info.path, ": selection ", selection.ToString(), " matched no voxel (", stats.RangeText(),
      stats.outside_mask > 0 ? absl::StrCat("; ", stats.outside_mask, " matched outside the mask")
                             : std::string(),
      ")"));
}

}  // namespace sheetmesh
