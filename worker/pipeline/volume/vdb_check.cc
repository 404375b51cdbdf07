#include "worker/pipeline/volume/vdb_check.h"

#include <openvdb/io/Compression.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <map>
#include <mutex>
#include <optional>
#include <span>
#include <tuple>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "common/file_util.h"
#include "common/status_macros.h"

namespace sheetmesh {
namespace {

// The format versions whose grid layout this walk knows: OpenVDB 3.0 (node-mask compression,
// 222) to OpenVDB 10 (224). Older files are refused, saying so.
constexpr uint32_t kOldestVersion = openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION;

// Leaf, lower and upper internal nodes of the standard 5-4-3 tree.
constexpr int kLeafLog2 = 3, kLowerLog2 = 4, kUpperLog2 = 5;
constexpr int64_t kLeafSize = 1 << (3 * kLeafLog2);    // 512 values
constexpr int64_t kLowerSize = 1 << (3 * kLowerLog2);  // 4096
constexpr int64_t kUpperSize = 1 << (3 * kUpperLog2);  // 32768
constexpr int32_t kLeafDim = 1 << kLeafLog2;                            // 8 voxels
constexpr int32_t kLowerDim = kLeafDim << kLowerLog2;                   // 128
constexpr int32_t kUpperDim = kLowerDim << kUpperLog2;                  // 4096
constexpr int64_t kMaxName = 1 << 16;  // names, type names, map types: generous, not gigabytes

void InitializeOnce() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// A file read forward through a buffer; every read is checked against the file's end.
class Cursor {
 public:
  Cursor(int fd, int64_t size, const std::string& path) : fd_(fd), size_(size), path_(path) {}

  int64_t at() const { return at_; }
  int64_t left() const { return size_ - at_; }
  const std::string& path() const { return path_; }
  void set_context(std::string context) { context_ = std::move(context); }

  // REQUIRES: 0 <= pos <= size.
  void Seek(int64_t pos) { at_ = pos; }

  // kInvalidArgument naming the file, the byte the cursor is at and `what`.
  absl::Status Bad(absl::string_view what) const { return BadAt(at_, what); }
  absl::Status BadAt(int64_t byte, absl::string_view what) const {
    return absl::InvalidArgumentError(absl::StrCat(path_, ": not a readable .vdb: at byte ",
                                                   byte, context_, ": ", what,
                                                   " (damaged, or not written by OpenVDB)"));
  }

  absl::Status Skip(int64_t n, absl::string_view what) {
    if (n < 0 || n > left()) {
      return Bad(absl::StrCat(what, " takes ", n, " bytes but the file ends ", left(),
                              " bytes further (cut short?)"));
    }
    at_ += n;
    return absl::OkStatus();
  }

  absl::Status Bytes(void* out, int64_t n, absl::string_view what) {
    if (n < 0 || n > left()) return Skip(n, what);
    auto* dst = static_cast<std::byte*>(out);
    while (n > 0) {
      if (at_ < buffer_start_ || at_ >= buffer_start_ + buffer_length_) {
        SM_RETURN_IF_ERROR(Fill());
      }
      const int64_t from = at_ - buffer_start_;
      const int64_t take = std::min(n, buffer_length_ - from);
      std::memcpy(dst, buffer_.data() + from, static_cast<size_t>(take));
      dst += take;
      at_ += take;
      n -= take;
    }
    return absl::OkStatus();
  }

  template <class T>
  absl::Status Read(T* value, absl::string_view what) {
    return Bytes(value, sizeof(T), what);
  }

  // A string stored as a 32-bit length and its bytes, at most `max_length` of them.
  absl::Status String(std::string* out, absl::string_view what, int64_t max_length = kMaxName) {
    uint32_t length = 0;
    SM_RETURN_IF_ERROR(Read(&length, what));
    if (length > max_length) {
      return BadAt(at_ - 4, absl::StrCat(what, " declares ", length, " bytes, more than the ",
                                         max_length, " such a field holds"));
    }
    if (out == nullptr) return Skip(length, what);
    out->resize(length);
    return Bytes(out->data(), length, what);
  }

 private:
  absl::Status Fill() {
    buffer_start_ = at_;
    buffer_length_ = std::min<int64_t>(static_cast<int64_t>(buffer_.size()), left());
    return ReadFullyAt(fd_, at_,
                       std::span<std::byte>(buffer_.data(), static_cast<size_t>(buffer_length_)),
                       path_);
  }

  int fd_;
  int64_t size_;
  const std::string& path_;
  std::string context_;
  int64_t at_ = 0;
  std::array<std::byte, 1 << 20> buffer_{};
  int64_t buffer_start_ = 0, buffer_length_ = 0;
};

// What a grid's values take: in memory, and in its chunks.
struct ValueKind {
  int value_bytes = 4;  // a value in memory, a background, a tile, an inactive value
  int data_bytes = 4;   // a value in a chunk (2 for a float grid saved as halves)
  bool bool_leaves = false;
  bool mask_leaves = false;
};

std::optional<ValueKind> KindOf(const std::string& type, bool half) {
  static const std::map<std::string, std::pair<int, bool>> kTypes = {
      {"Tree_float_5_4_3", {4, true}}, {"Tree_double_5_4_3", {8, true}},
      {"Tree_int32_5_4_3", {4, false}}, {"Tree_int64_5_4_3", {8, false}},
      {"Tree_bool_5_4_3", {1, false}},  {"Tree_mask_5_4_3", {1, false}}};
  const auto it = kTypes.find(type);
  if (it == kTypes.end()) return std::nullopt;
  ValueKind k;
  k.value_bytes = it->second.first;
  k.data_bytes = half && it->second.second ? 2 : k.value_bytes;
  k.bool_leaves = type == "Tree_bool_5_4_3";
  k.mask_leaves = type == "Tree_mask_5_4_3";
  return k;
}

int64_t CountOn(std::span<const uint64_t> words) {
  int64_t n = 0;
  for (uint64_t w : words) n += std::popcount(w);
  return n;
}

uint64_t HashWords(std::span<const uint64_t> words) {
  uint64_t h = 1469598103934665603ull;
  for (uint64_t w : words) h = (h ^ w) * 1099511628211ull;
  return h;
}

// Offset n of a node of side 2^log2 as local (x, y, z), x slowest (OpenVDB's order).
std::array<int32_t, 3> LocalCoord(int64_t n, int log2) {
  const int64_t mask = (int64_t{1} << log2) - 1;
  return {static_cast<int32_t>(n >> (2 * log2)), static_cast<int32_t>((n >> log2) & mask),
          static_cast<int32_t>(n & mask)};
}

using Coord = std::array<int32_t, 3>;

// One leaf as the topology gave it: where it is, and its mask.
struct LeafRecord {
  Coord origin;
  uint16_t on = 0;
  uint64_t mask_hash = 0;
};

// Walks one grid's data (see CheckVdbGrid).
class GridWalker {
 public:
  GridWalker(Cursor& c, const VdbGridEntry& e, ValueKind kind, int64_t budget)
      : c_(c), entry_(e), kind_(kind), budget_(budget) {}

  // Compression flags, metadata and transform: what every grid, an instance too, holds.
  absl::Status Header() {
    SM_RETURN_IF_ERROR(c_.Read(&compression_, "the grid's compression flags"));
    SM_RETURN_IF_ERROR(Metadata());
    return Transform();
  }

  // The tree's topology, then its leaves' buffers.
  absl::Status Tree() {
    int32_t buffers = 0;
    SM_RETURN_IF_ERROR(c_.Read(&buffers, "the tree's buffer count"));
    if (buffers != 1) return c_.BadAt(c_.at() - 4, absl::StrCat("a tree of ", buffers, " buffers"));
    SM_RETURN_IF_ERROR(c_.Skip(kind_.value_bytes, "the background value"));
    uint32_t tiles = 0, children = 0;
    SM_RETURN_IF_ERROR(c_.Read(&tiles, "the root's tile count"));
    SM_RETURN_IF_ERROR(c_.Read(&children, "the root's child count"));
    const int64_t tile_bytes = 12 + kind_.value_bytes + 1;
    if (tiles > c_.left() / tile_bytes) {
      return c_.BadAt(c_.at() - 8, absl::StrCat("the root declares ", tiles,
                                                " tiles, more than the rest of the file holds"));
    }
    const int64_t child_min = 12 + 2 * kUpperSize / 8 + 1;
    if (children > c_.left() / child_min) {
      return c_.BadAt(c_.at() - 4, absl::StrCat("the root declares ", children,
                                                " children, more than the rest of the file holds"));
    }
    std::map<Coord, std::pair<size_t, size_t>> table;  // origin -> leaves [first, last)
    for (uint32_t i = 0; i < tiles; ++i) {
      Coord origin;
      SM_RETURN_IF_ERROR(c_.Read(&origin, "a root tile's origin"));
      SM_RETURN_IF_ERROR(RootKey(origin, table, "tile"));
      SM_RETURN_IF_ERROR(c_.Skip(kind_.value_bytes + 1, "a root tile's value"));
      SM_RETURN_IF_ERROR(Charge(64));
      table[origin] = {0, 0};
    }
    for (uint32_t i = 0; i < children; ++i) {
      Coord origin;
      SM_RETURN_IF_ERROR(c_.Read(&origin, "a root child's origin"));
      SM_RETURN_IF_ERROR(RootKey(origin, table, "child"));
      const size_t first = leaves_.size();
      SM_RETURN_IF_ERROR(Upper(origin));
      table[origin] = {first, leaves_.size()};
    }
    // The buffers follow in the root table's order (its children sorted by origin).
    for (const auto& [origin, range] : table) {
      for (size_t i = range.first; i < range.second; ++i) SM_RETURN_IF_ERROR(LeafBuffer(leaves_[i]));
    }
    return absl::OkStatus();
  }

 private:
  absl::Status RootKey(const Coord& o, const std::map<Coord, std::pair<size_t, size_t>>& table,
                       absl::string_view what) {
    for (int32_t v : o) {
      if (v % kUpperDim != 0) {
        return c_.BadAt(c_.at() - 12, absl::StrCat("a root ", what, " at (", o[0], ", ", o[1],
                                                   ", ", o[2], ") is not on the ", kUpperDim,
                                                   "-voxel grid of the root's children"));
      }
    }
    if (table.count(o) != 0) {
      return c_.BadAt(c_.at() - 12, absl::StrCat("a second root ", what, " at (", o[0], ", ",
                                                 o[1], ", ", o[2], ")"));
    }
    return absl::OkStatus();
  }

  absl::Status Charge(int64_t bytes) {
    memory_ += bytes;
    if (memory_ > budget_) {
      return absl::ResourceExhaustedError(absl::StrCat(
          c_.path(), ": grid '", entry_.name, "' would take more than ", memory_,
          " bytes in memory as OpenVDB builds it (by byte ", c_.at(),
          " of the file), over the reading budget of ", budget_, " bytes"));
    }
    return absl::OkStatus();
  }

  absl::Status Metadata() {
    int32_t count = 0;
    SM_RETURN_IF_ERROR(c_.Read(&count, "the grid's metadata count"));
    if (count < 0 || count > c_.left() / 12) {
      return c_.BadAt(c_.at() - 4, absl::StrCat("the grid declares ", count, " metadata entries"));
    }
    for (int32_t i = 0; i < count; ++i) {
      std::string name, type;
      SM_RETURN_IF_ERROR(c_.String(&name, "a metadata name"));
      SM_RETURN_IF_ERROR(c_.String(&type, absl::StrCat("metadata '", name, "''s type")));
      uint32_t bytes = 0;
      SM_RETURN_IF_ERROR(c_.Read(&bytes, absl::StrCat("metadata '", name, "''s size")));
      if (bytes > c_.left()) {
        return c_.BadAt(c_.at() - 4, absl::StrCat("metadata '", name, "' declares ", bytes,
                                                  " bytes, past the end of the file"));
      }
      SM_RETURN_IF_ERROR(Charge(bytes + 128));
      const int64_t start = c_.at();
      if (type == openvdb::io::DelayedLoadMetadata::staticTypeName()) {
        SM_RETURN_IF_ERROR(DelayedLoad(name, bytes));
        SM_RETURN_IF_ERROR(c_.Skip(bytes - (c_.at() - start), "the rest of a delayed-load table"));
        continue;
      }
      if (type != "string" && openvdb::Metadata::isRegisteredType(type)) {
        // A registered type other than a string reads its own size, whatever the file says.
        const int64_t size = openvdb::Metadata::createMetadata(type)->size();
        if (bytes != size) {
          return c_.BadAt(start - 4, absl::StrCat("metadata '", name, "' of type ", type,
                                                  " declares ", bytes, " bytes, not its ", size));
        }
      }
      SM_RETURN_IF_ERROR(c_.Skip(bytes, absl::StrCat("metadata '", name, "'")));
    }
    return absl::OkStatus();
  }

  // A delayed-load table: a leaf count, a mask byte per leaf and a 64-bit size per leaf, each
  // array stored raw or as one blosc chunk; it must end within its declared `bytes`.
  absl::Status DelayedLoad(const std::string& name, uint32_t bytes) {
    if (bytes == 0) return absl::OkStatus();
    const int64_t end = c_.at() + bytes;
    uint32_t count = 0;
    SM_RETURN_IF_ERROR(c_.Read(&count, "a delayed-load table's leaf count"));
    for (const int element : {1, 8}) {
      uint32_t stored = 0;
      SM_RETURN_IF_ERROR(c_.Read(&stored, "a delayed-load table's chunk size"));
      if (element == 8 && stored == UINT32_MAX) break;  // no sizes stored
      const int64_t raw = int64_t{count} * element;
      SM_RETURN_IF_ERROR(Charge(2 * raw + 320));
      if (stored == 0) {
        SM_RETURN_IF_ERROR(c_.Skip(raw, "a delayed-load table"));
      } else {
        SM_RETURN_IF_ERROR(Blosc(raw, stored, "a delayed-load table's chunk", /*padded=*/true));
      }
      if (c_.at() > end) {
        return c_.Bad(absl::StrCat("metadata '", name, "' runs past its declared ", bytes,
                                   " bytes"));
      }
    }
    return absl::OkStatus();
  }

  absl::Status Transform() {
    std::string type;
    SM_RETURN_IF_ERROR(c_.String(&type, "the transform's map type"));
    static const std::map<std::string, int> kMaps = {
        {"AffineMap", 128},         {"UnitaryMap", 128},        {"ScaleMap", 120},
        {"UniformScaleMap", 120},   {"TranslationMap", 24},     {"ScaleTranslateMap", 144},
        {"UniformScaleTranslateMap", 144}};
    const auto it = kMaps.find(type);
    if (it == kMaps.end()) {
      return c_.Bad(absl::StrCat("the transform '", type.substr(0, 64),
                                 "' is not a linear map of voxels (affine, scale, translation)"));
    }
    return c_.Skip(it->second, absl::StrCat("the ", type, " transform"));
  }

  // A blosc chunk of `stored` bytes that must decode to `raw` bytes: its header declares
  // both (blosc 1 reads as far as its header says, whatever it was given), and its blocks
  // start within it.
  // A delayed-load table's chunks may decode to more than their array (OpenVDB pads them, and
  // reads them into a buffer of the declared size): `padded` allows that, up to twice.
  absl::Status Blosc(int64_t raw, int64_t stored, absl::string_view what, bool padded = false) {
    const int64_t start = c_.at();
    if (stored < 16 || stored > c_.left()) {
      return c_.Bad(absl::StrCat(what, " declares ", stored, " bytes, ",
                                 stored < 16 ? "less than its header" : "past the end of the file"));
    }
    uint8_t head[16];
    SM_RETURN_IF_ERROR(c_.Bytes(head, 16, what));
    uint32_t nbytes, blocksize, cbytes;
    std::memcpy(&nbytes, head + 4, 4);
    std::memcpy(&blocksize, head + 8, 4);
    std::memcpy(&cbytes, head + 12, 4);
    const bool fits = padded ? nbytes >= raw && nbytes <= 2 * raw + 256 : nbytes == raw;
    if (!fits || cbytes != stored) {
      return c_.BadAt(start, absl::StrCat(what, " is ", stored, " bytes for ", raw,
                                          " bytes of values, but its blosc header says ", cbytes,
                                          " bytes for ", nbytes));
    }
    raw = nbytes;
    const bool copied = (head[2] & 0x2) != 0;  // BLOSC_MEMCPYED: the data follows as it is
    if (copied) {
      if (stored != raw + 16) {
        return c_.BadAt(start, absl::StrCat(what, " is stored uncompressed in ", stored,
                                            " bytes for ", raw, " bytes of values"));
      }
    } else if (raw > 0) {
      if (blocksize == 0) return c_.BadAt(start, absl::StrCat(what, " has blocks of 0 bytes"));
      const int64_t blocks = (raw + blocksize - 1) / blocksize;
      if (16 + 4 * blocks > stored) {
        return c_.BadAt(start, absl::StrCat(what, " has ", blocks, " blocks in ", stored,
                                            " bytes"));
      }
      for (int64_t b = 0; b < blocks; ++b) {
        int32_t block_start = 0;
        SM_RETURN_IF_ERROR(c_.Read(&block_start, what));
        if (block_start < 16 + 4 * blocks || block_start >= stored) {
          return c_.BadAt(c_.at() - 4, absl::StrCat(what, "'s block ", b, " starts at ",
                                                    block_start, ", outside its ", stored,
                                                    " bytes"));
        }
      }
    }
    c_.Seek(start);
    return c_.Skip(stored, what);
  }

  // One chunk of `raw` bytes of values, as the grid's compression stores it.
  absl::Status Chunk(int64_t raw, absl::string_view what) {
    using openvdb::io::COMPRESS_BLOSC;
    using openvdb::io::COMPRESS_ZIP;
    if ((compression_ & (COMPRESS_BLOSC | COMPRESS_ZIP)) == 0) return c_.Skip(raw, what);
    int64_t stored = 0;
    SM_RETURN_IF_ERROR(c_.Read(&stored, absl::StrCat(what, "'s size")));
    if (stored <= 0) {  // stored as it is
      if (stored != -raw) {
        return c_.BadAt(c_.at() - 8, absl::StrCat(what, "'s size field is ", stored,
                                                  " (an uncompressed chunk of minus that many "
                                                  "bytes) where its values take ",
                                                  raw));
      }
      return c_.Skip(raw, what);
    }
    if (compression_ & COMPRESS_BLOSC) return Blosc(raw, stored, what);
    if (stored > c_.left()) {
      return c_.BadAt(c_.at() - 8, absl::StrCat(what, " declares ", stored,
                                                " zipped bytes, past the end of the file"));
    }
    return c_.Skip(stored, what);
  }

  // A node's values (readCompressedValues): a flag, up to two inactive values, a selection
  // mask, then a chunk of all `size` values or of the `on` active ones.
  absl::Status Values(int64_t size, int64_t on, absl::string_view what) {
    int8_t flag = 0;
    SM_RETURN_IF_ERROR(c_.Read(&flag, absl::StrCat(what, "'s compression flag")));
    if (flag < 0 || flag > 6) {
      return c_.BadAt(c_.at() - 1, absl::StrCat(what, " has compression flag ", int{flag}));
    }
    if (flag == 2 || flag == 4 || flag == 5) {
      SM_RETURN_IF_ERROR(c_.Skip(kind_.value_bytes * (flag == 5 ? 2 : 1), "inactive values"));
    }
    if (flag >= 3 && flag <= 5) SM_RETURN_IF_ERROR(c_.Skip(size / 8, "a selection mask"));
    const bool only_active = (compression_ & openvdb::io::COMPRESS_ACTIVE_MASK) && flag != 6;
    const int64_t count = only_active ? on : size;
    SM_RETURN_IF_ERROR(Charge(count * kind_.value_bytes));
    // Halves are read through a reader that reads nothing, not even a chunk's size, for none.
    if (count == 0 && kind_.data_bytes != kind_.value_bytes) return absl::OkStatus();
    return Chunk(count * kind_.data_bytes, what);
  }

  absl::Status Mask(std::span<uint64_t> words, absl::string_view what) {
    return c_.Bytes(words.data(), static_cast<int64_t>(words.size() * 8), what);
  }

  absl::Status Upper(const Coord& origin) {
    std::span<uint64_t> child(upper_child_), value(upper_value_);
    c_.set_context(absl::StrCat(", grid '", entry_.name, "', the upper node at (", origin[0],
                                ", ", origin[1], ", ", origin[2], ")"));
    SM_RETURN_IF_ERROR(Mask(child, "its child mask"));
    SM_RETURN_IF_ERROR(Mask(value, "its value mask"));
    SM_RETURN_IF_ERROR(Charge(kUpperSize * std::max(8, kind_.value_bytes) + kUpperSize / 4 + 64));
    SM_RETURN_IF_ERROR(Values(kUpperSize, CountOn(value), "its values"));
    memory_ -= kUpperSize * kind_.value_bytes;  // the values' array is freed once copied
    for (int64_t n = 0; n < kUpperSize; ++n) {
      if ((child[n / 64] >> (n % 64) & 1) == 0) continue;
      const Coord l = LocalCoord(n, kUpperLog2);
      SM_RETURN_IF_ERROR(Lower({origin[0] + l[0] * kLowerDim, origin[1] + l[1] * kLowerDim,
                                origin[2] + l[2] * kLowerDim}));
    }
    return absl::OkStatus();
  }

  absl::Status Lower(const Coord& origin) {
    std::array<uint64_t, kLowerSize / 64> child, value;
    c_.set_context(absl::StrCat(", grid '", entry_.name, "', the lower node at (", origin[0],
                                ", ", origin[1], ", ", origin[2], ")"));
    SM_RETURN_IF_ERROR(Mask(child, "its child mask"));
    SM_RETURN_IF_ERROR(Mask(value, "its value mask"));
    SM_RETURN_IF_ERROR(Charge(kLowerSize * std::max(8, kind_.value_bytes) + kLowerSize / 4 + 64));
    SM_RETURN_IF_ERROR(Values(kLowerSize, CountOn(value), "its values"));
    memory_ -= kLowerSize * kind_.value_bytes;
    for (int64_t n = 0; n < kLowerSize; ++n) {
      if ((child[n / 64] >> (n % 64) & 1) == 0) continue;
      const Coord l = LocalCoord(n, kLowerLog2);
      std::array<uint64_t, kLeafSize / 64> mask;
      SM_RETURN_IF_ERROR(Mask(mask, "a leaf's mask"));
      const int64_t leaf_bytes = kind_.mask_leaves   ? 64
                                 : kind_.bool_leaves ? 128
                                                     : kLeafSize * kind_.value_bytes + 64;
      SM_RETURN_IF_ERROR(Charge(leaf_bytes + 48 + sizeof(LeafRecord)));
      leaves_.push_back({{origin[0] + l[0] * kLeafDim, origin[1] + l[1] * kLeafDim,
                          origin[2] + l[2] * kLeafDim},
                         static_cast<uint16_t>(CountOn(mask)),
                         HashWords(mask)});
    }
    return absl::OkStatus();
  }

  absl::Status LeafBuffer(const LeafRecord& leaf) {
    const Coord& o = leaf.origin;
    c_.set_context(absl::StrCat(", grid '", entry_.name, "', the buffer of the leaf at (", o[0],
                                ", ", o[1], ", ", o[2], ")"));
    std::array<uint64_t, kLeafSize / 64> mask;
    SM_RETURN_IF_ERROR(Mask(mask, "its mask"));
    if (HashWords(mask) != leaf.mask_hash || CountOn(mask) != leaf.on) {
      return c_.BadAt(c_.at() - 64, "its mask differs from the one the tree's topology gave");
    }
    if (kind_.bool_leaves || kind_.mask_leaves) {
      Coord stored;
      SM_RETURN_IF_ERROR(c_.Read(&stored, "its origin"));
      if (stored != o) {
        return c_.BadAt(c_.at() - 12, absl::StrCat("it says it lies at (", stored[0], ", ",
                                                   stored[1], ", ", stored[2], ")"));
      }
      if (kind_.bool_leaves) SM_RETURN_IF_ERROR(Mask(mask, "its values"));
      return absl::OkStatus();
    }
    return Values(kLeafSize, leaf.on, "its values");
  }

  Cursor& c_;
  const VdbGridEntry& entry_;
  ValueKind kind_;
  int64_t budget_;
  uint32_t compression_ = 0;
  int64_t memory_ = 0;
  std::vector<LeafRecord> leaves_;
  std::vector<uint64_t> upper_child_ = std::vector<uint64_t>(kUpperSize / 64);
  std::vector<uint64_t> upper_value_ = std::vector<uint64_t>(kUpperSize / 64);
};

}  // namespace

bool IsScalarVdbGridType(const std::string& type) { return KindOf(type, false).has_value(); }

absl::StatusOr<VdbFileLayout> ReadVdbLayout(const std::string& path) {
  InitializeOnce();
  SM_ASSIGN_OR_RETURN(ScopedFd fd, OpenForRead(path));
  SM_ASSIGN_OR_RETURN(const int64_t size, FileSizeOf(fd.get(), path));
  auto cursor = std::make_unique<Cursor>(fd.get(), size, path);
  Cursor& c = *cursor;
  VdbFileLayout layout;
  int64_t magic = 0;
  SM_RETURN_IF_ERROR(c.Read(&magic, "the magic number"));
  if (magic != openvdb::OPENVDB_MAGIC) return c.BadAt(0, "no OpenVDB magic number at its start");
  SM_RETURN_IF_ERROR(c.Read(&layout.version, "the file format version"));
  if (layout.version < kOldestVersion || layout.version > openvdb::OPENVDB_FILE_VERSION) {
    return c.BadAt(8, absl::StrCat("file format version ", layout.version,
                                   " is not one this reader takes (", kOldestVersion, "-",
                                   openvdb::OPENVDB_FILE_VERSION,
                                   ", OpenVDB 3 to 10; save older files again with a newer "
                                   "OpenVDB)"));
  }
  SM_RETURN_IF_ERROR(c.Skip(8, "the library version"));
  char offsets = 0;
  SM_RETURN_IF_ERROR(c.Read(&offsets, "the grid-offsets flag"));
  if (offsets == 0) {
    return c.BadAt(c.at() - 1, "written as a stream without grid offsets; save it with "
                               "openvdb.write");
  }
  SM_RETURN_IF_ERROR(c.Skip(36, "the file's UUID"));
  int32_t entries = 0;
  SM_RETURN_IF_ERROR(c.Read(&entries, "the file's metadata count"));
  if (entries < 0 || entries > c.left() / 12) {
    return c.BadAt(c.at() - 4, absl::StrCat("the file declares ", entries, " metadata entries"));
  }
  for (int32_t i = 0; i < entries; ++i) {
    std::string name;
    SM_RETURN_IF_ERROR(c.String(&name, "a file metadata name"));
    SM_RETURN_IF_ERROR(c.String(nullptr, absl::StrCat("file metadata '", name, "''s type")));
    uint32_t bytes = 0;
    SM_RETURN_IF_ERROR(c.Read(&bytes, absl::StrCat("file metadata '", name, "''s size")));
    SM_RETURN_IF_ERROR(c.Skip(bytes, absl::StrCat("file metadata '", name, "'")));
  }
  int32_t grids = 0;
  SM_RETURN_IF_ERROR(c.Read(&grids, "the grid count"));
  if (grids < 0 || grids > c.left() / 36) {
    return c.BadAt(c.at() - 4, absl::StrCat("the file declares ", grids, " grids"));
  }
  for (int32_t i = 0; i < grids; ++i) {
    const std::string what = absl::StrCat("grid descriptor ", i);
    VdbGridEntry e;
    SM_RETURN_IF_ERROR(c.String(&e.name, what + "'s name"));
    SM_RETURN_IF_ERROR(c.String(&e.type, what + "'s type"));
    if (absl::EndsWith(e.type, "_HalfFloat")) {
      e.half = true;
      e.type.resize(e.type.size() - std::strlen("_HalfFloat"));
    }
    SM_RETURN_IF_ERROR(c.String(&e.instance_parent, what + "'s instance parent"));
    SM_RETURN_IF_ERROR(c.Read(&e.grid_pos, what));
    SM_RETURN_IF_ERROR(c.Read(&e.block_pos, what));
    SM_RETURN_IF_ERROR(c.Read(&e.end_pos, what));
    // An instance holds no tree, and OpenVDB writes no block position for it.
    const bool blocks_placed = e.instance_parent.empty()
                                   ? e.grid_pos <= e.block_pos && e.block_pos <= e.end_pos
                                   : e.block_pos == 0;
    if (!(c.at() <= e.grid_pos && blocks_placed && e.grid_pos <= e.end_pos && e.end_pos <= size)) {
      return c.Bad(absl::StrCat(what, " places its grid at bytes ", e.grid_pos, "-", e.end_pos,
                                ", not within the file's ", size, " (cut short?)"));
    }
    c.Seek(e.end_pos);  // the next descriptor follows this grid's data
    layout.grids.push_back(std::move(e));
  }
  return layout;
}

absl::Status CheckVdbGrid(const std::string& path, const VdbFileLayout& layout, size_t index,
                          int64_t memory_budget) {
  InitializeOnce();
  if (index >= layout.grids.size()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": no grid ", index));
  }
  const VdbGridEntry& grid = layout.grids[index];
  const std::optional<ValueKind> kind = KindOf(grid.type, grid.half);
  if (!kind) {
    return absl::InvalidArgumentError(absl::StrCat(
        path, ": grid '", grid.name, "' of type ", grid.type.substr(0, 64),
        " is not a scalar grid of the standard 5-4-3 tree (float, double, int32, int64, bool, "
        "mask)"));
  }
  const VdbGridEntry* tree = &grid;
  if (!grid.instance_parent.empty()) {
    tree = nullptr;
    for (const VdbGridEntry& g : layout.grids) {
      if (g.name == grid.instance_parent && g.instance_parent.empty()) tree = &g;
    }
    if (tree == nullptr || tree->type != grid.type || tree->half != grid.half) {
      return absl::InvalidArgumentError(
          absl::StrCat(path, ": not a readable .vdb: grid '", grid.name,
                       "' shares the tree of '", grid.instance_parent.substr(0, 64),
                       "', which is not a grid of its type in the file"));
    }
  }
  SM_ASSIGN_OR_RETURN(ScopedFd fd, OpenForRead(path));
  SM_ASSIGN_OR_RETURN(const int64_t size, FileSizeOf(fd.get(), path));
  auto cursor = std::make_unique<Cursor>(fd.get(), size, path);
  cursor->Seek(grid.grid_pos);
  cursor->set_context(absl::StrCat(", grid '", grid.name, "'"));
  GridWalker walker(*cursor, grid, *kind, memory_budget);
  SM_RETURN_IF_ERROR(walker.Header());
  if (tree == &grid) return walker.Tree();
  cursor->Seek(tree->grid_pos);
  cursor->set_context(absl::StrCat(", grid '", tree->name, "'"));
  GridWalker parent(*cursor, *tree, *kind, memory_budget);
  SM_RETURN_IF_ERROR(parent.Header());
  return parent.Tree();
}

}  // namespace sheetmesh
