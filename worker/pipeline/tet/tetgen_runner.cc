#include "worker/pipeline/tet/tetgen_runner.h"

#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>
#include <thread>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "common/subprocess.h"

namespace sheetmesh {
namespace {

std::string Tail(const std::string& path, size_t bytes = 600) {
  auto text = ReadFileToString(path);
  if (!text.ok()) return "";
  std::string s = *text;
  if (s.size() > bytes) s = "..." + s.substr(s.size() - bytes);
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

// Removes the scratch folder unless asked to keep it.
class Scratch {
 public:
  static absl::StatusOr<Scratch> Create(const std::string& parent, bool keep) {
    std::string base = parent;
    if (base.empty()) base = getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
    std::string templ = base + "/sheetmesh-tetgen-XXXXXX";
    if (::mkdtemp(templ.data()) == nullptr) return ErrnoStatus(errno, templ);
    return Scratch(templ, keep);
  }
  Scratch(Scratch&& o) noexcept : dir_(std::move(o.dir_)), keep_(o.keep_) { o.dir_.clear(); }
  ~Scratch() {
    if (!dir_.empty() && !keep_) {
      std::error_code ec;
      std::filesystem::remove_all(dir_, ec);
    }
  }
  const std::string& dir() const { return dir_; }

 private:
  Scratch(std::string dir, bool keep) : dir_(std::move(dir)), keep_(keep) {}
  std::string dir_;
  bool keep_;
};

// Lines of a TetGen output file without comments and blank lines.
absl::StatusOr<std::vector<std::vector<double>>> ReadTable(const std::string& path) {
  SM_ASSIGN_OR_RETURN(std::string text, ReadFileToString(path, int64_t{16} << 30));
  std::vector<std::vector<double>> rows;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    const size_t hash = line.find('#');
    if (hash != absl::string_view::npos) line = line.substr(0, hash);
    std::vector<double> row;
    for (absl::string_view tok :
         absl::StrSplit(line, absl::ByAnyChar(" \t\r"), absl::SkipEmpty())) {
      double v = 0;
      if (!absl::SimpleAtod(tok, &v)) {
        return absl::InternalError(absl::StrCat(path, ": unreadable number '", tok, "'"));
      }
      row.push_back(v);
    }
    if (!row.empty()) rows.push_back(std::move(row));
  }
  if (rows.empty()) return absl::InternalError(absl::StrCat(path, ": empty TetGen output"));
  return rows;
}

absl::StatusOr<TetMesh> ReadOutput(const std::string& stem, const Plc& plc) {
  TetMesh m;
  SM_ASSIGN_OR_RETURN(auto nodes, ReadTable(stem + ".node"));
  SM_ASSIGN_OR_RETURN(auto eles, ReadTable(stem + ".ele"));
  SM_ASSIGN_OR_RETURN(auto faces, ReadTable(stem + ".face"));
  const size_t n = static_cast<size_t>(nodes[0][0]);
  if (nodes.size() != n + 1)
    return absl::InternalError(
        absl::StrCat(stem, ".node: ", nodes.size() - 1, " rows for ", n, " nodes"));
  for (size_t i = 1; i <= n; ++i) {
    if (nodes[i].size() < 4) return absl::InternalError(absl::StrCat(stem, ".node: short row ", i));
    m.nodes.push_back({nodes[i][1], nodes[i][2], nodes[i][3]});
  }
  const size_t e = static_cast<size_t>(eles[0][0]);
  if (eles.size() != e + 1)
    return absl::InternalError(
        absl::StrCat(stem, ".ele: ", eles.size() - 1, " rows for ", e, " tetrahedra"));
  for (size_t i = 1; i <= e; ++i) {
    if (eles[i].size() < 5) return absl::InternalError(absl::StrCat(stem, ".ele: short row ", i));
    Tet t;
    for (int k = 0; k < 4; ++k) {
      const double id = eles[i][k + 1];
      if (id < 0 || id >= n)
        return absl::InternalError(absl::StrCat(stem, ".ele: node ", id, " out of range"));
      t[k] = static_cast<uint32_t>(id);
    }
    m.tets.push_back(t);
  }
  const size_t f = static_cast<size_t>(faces[0][0]);
  if (faces.size() != f + 1)
    return absl::InternalError(
        absl::StrCat(stem, ".face: ", faces.size() - 1, " rows for ", f, " faces"));
  for (size_t i = 1; i <= f; ++i) {
    if (faces[i].size() < 5)
      return absl::InternalError(absl::StrCat(stem, ".face: row ", i, " has no marker"));
    std::array<uint32_t, 3> t;
    for (int k = 0; k < 3; ++k) t[k] = static_cast<uint32_t>(faces[i][k + 1]);
    const int32_t marker = static_cast<int32_t>(faces[i][4]);
    if (marker == 0) continue;  // a face on no facet
    m.faces.push_back(t);
    m.face_marker.push_back(marker);
    const int64_t s = marker - kFirstSheetMarker;
    if (s >= 0 && s < static_cast<int64_t>(plc.sheet_triangles.size())) {
      m.face_piece.push_back(plc.sheet_piece[s]);
      m.face_thickness_voxels.push_back(plc.sheet_thickness[s]);
    } else {
      m.face_piece.push_back(-1);
      m.face_thickness_voxels.push_back(0.0f);
    }
  }
  return m;
}

}  // namespace

std::string TetgenSwitches(const TetgenOptions& o) {
  std::string s = "-pzQ";
  if (o.max_radius_edge_ratio > 0) {
    absl::StrAppend(&s, "q", o.max_radius_edge_ratio, "/", o.min_dihedral_degrees);
  }
  if (o.max_volume > 0) absl::StrAppend(&s, "a", o.max_volume);
  // TetGen's own optimization with flips and smoothing only (-O level 2, operations 1 + 2).
  // Its vertex insertion and deletion (operation 4, on by default) can leave facet faces in
  // the .face file that no tetrahedron has any more (seen on the NETL fracture at r = 7);
  // sheetmesh's improvement pass inserts vertices itself, keeping the facets.
  s += "O2/3";
  if (!o.steiner_on_sheets) s += "Y";
  return s;
}

namespace {

// A TetGen run on `plc` in `scratch` with `switches`: its exit, within the time limit (else
// kDeadlineExceeded) unless `progress` cancels; its output goes to scratch/tetgen.log.
absl::StatusOr<ChildExit> RunInScratch(const Plc& plc, const TetgenOptions& options,
                                       const std::string& switches, const Scratch& scratch,
                                       const Progress& progress) {
  absl::StatusOr<std::string> program = FindProgram(options.program);
  if (!program.ok()) {
    return absl::NotFoundError(
        absl::StrCat("TetGen ", program.status().message(), " (Debian package tetgen)"));
  }
  const std::string poly = scratch.dir() + "/plc.poly";
  SM_RETURN_IF_ERROR(WriteFileAtomically(poly, plc.ToPoly()));
  SubprocessOptions spawn;
  spawn.argv = {*program, switches, poly};
  spawn.output_path = scratch.dir() + "/tetgen.log";
  spawn.memory_limit_bytes = options.memory_limit_bytes;
  SM_ASSIGN_OR_RETURN(Subprocess child, Subprocess::Start(spawn));
  const auto start = std::chrono::steady_clock::now();
  std::optional<ChildExit> exit;
  while (!(exit = child.Poll())) {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    absl::Status cancel =
        progress.Update(std::min(0.99, elapsed / options.time_limit_seconds), "TetGen running");
    if (elapsed > options.time_limit_seconds || !cancel.ok()) {
      child.Kill();
      child.Wait();
      if (!cancel.ok()) return cancel;
      return absl::DeadlineExceededError(absl::StrCat(
          "TetGen exceeded the time limit of ", options.time_limit_seconds, " s and was killed"));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (exit->code == 127 && !exit->signaled && Tail(spawn.output_path).empty()) {
    return absl::NotFoundError(
        absl::StrCat("TetGen program '", *program, "' could not be started"));
  }
  return *exit;
}

}  // namespace

absl::StatusOr<TetMesh> RunTetgen(const Plc& plc, const TetgenOptions& options,
                                  const Progress& progress) {
  SM_ASSIGN_OR_RETURN(Scratch scratch, Scratch::Create(options.scratch_dir, options.keep_scratch));
  const std::string log = scratch.dir() + "/tetgen.log";
  const std::string switches = TetgenSwitches(options);
  SM_ASSIGN_OR_RETURN(const ChildExit exit,
                      RunInScratch(plc, options, switches, scratch, progress));
  const bool failed = exit.signaled || exit.code != 0;
  if (failed && !options.failed_plc_path.empty()) {
    WriteFileAtomically(options.failed_plc_path, plc.ToPoly()).IgnoreError();
  }
  if (exit.signaled) {
    const int sig = exit.code;
    const std::string tail = Tail(log);
    if (tail.find("bad_alloc") != std::string::npos || tail.find("memory") != std::string::npos) {
      return absl::ResourceExhaustedError(absl::StrCat(
          "TetGen ran out of memory (limit ", options.memory_limit_bytes, " bytes): ", tail));
    }
    return absl::InternalError(absl::StrCat("TetGen crashed with signal ", sig, " (",
                                            strsignal(sig), "); its last output: ", tail));
  }
  if (exit.code != 0) {
    return absl::InternalError(absl::StrCat("TetGen exited with code ", exit.code, " running '",
                                            switches, "': ", Tail(log)));
  }
  auto mesh = ReadOutput(scratch.dir() + "/plc.1", plc);
  if (!mesh.ok()) {
    return absl::InternalError(absl::StrCat("TetGen output unreadable: ", mesh.status().message(),
                                            "; its log: ", Tail(log)));
  }
  return mesh;
}

absl::StatusOr<std::vector<std::pair<uint32_t, uint32_t>>> FindFacetIntersections(
    const Plc& plc, const TetgenOptions& options, const Progress& progress) {
  SM_ASSIGN_OR_RETURN(Scratch scratch, Scratch::Create(options.scratch_dir, options.keep_scratch));
  SM_ASSIGN_OR_RETURN(const ChildExit exit, RunInScratch(plc, options, "-pd", scratch, progress));
  const std::string log = scratch.dir() + "/tetgen.log";
  if (exit.signaled || exit.code != 0) {
    return absl::InternalError(
        absl::StrCat("TetGen's intersection check ", exit.ToString(), ": ", Tail(log)));
  }
  SM_ASSIGN_OR_RETURN(const std::string text, ReadFileToString(log, int64_t{1} << 30));
  // "  Facet #A intersects facet #B at triangles:", A and B counted from 1; each pair is
  // listed once per pair of its triangles.
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    const std::vector<absl::string_view> words =
        absl::StrSplit(line, absl::ByAnyChar(" #"), absl::SkipEmpty());
    if (words.size() < 5 || words[0] != "Facet" || words[2] != "intersects") continue;
    uint32_t a = 0, b = 0;
    if (!absl::SimpleAtoi(words[1], &a) || !absl::SimpleAtoi(words[4], &b) || a == 0 || b == 0) {
      continue;
    }
    pairs.push_back({std::min(a, b) - 1, std::max(a, b) - 1});
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

}  // namespace sheetmesh
