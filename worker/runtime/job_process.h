// A job's pipeline in a child process: the server (or sheetmesh-worker) starts itself again
// as a job child, which runs the pipeline on one input into one scratch folder, with a
// memory limit, a CPU limit and a wall-clock limit, and with the filesystem closed to it but
// for its input, its scratch folder and the system's libraries (Landlock, where the kernel
// has it). A crash, an abort, a signal or a limit ends that child alone; the parent names
// the cause and carries on. Progress comes back as JSON lines on a pipe.
#ifndef SHEETMESH_WORKER_RUNTIME_JOB_PROCESS_H_
#define SHEETMESH_WORKER_RUNTIME_JOB_PROCESS_H_

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "worker/runtime/brick_tasks.h"

namespace sheetmesh {
struct VolumeInfo;  // volume_source.h
}  // namespace sheetmesh

namespace sheetmesh::runtime {

// What the child runs.
struct JobSpec {
  std::string volume_path;   // readable on this machine
  std::string display_name;  // the volume's name for messages (the client's)
  std::string output_dir;    // the child's scratch folder (made by the parent)
  std::string parameters;    // the job's canonical parameter JSON
  // Where a file the volume names (a detached NRRD's data file) may lie; empty with
  // `data_files` false: the volume may name none (an upload).
  std::vector<std::string> allowed_roots;
  bool data_files = false;
  // Only open the volume and say what it holds (InspectVolumeInChild); no stage runs.
  bool inspect = false;
  // One task of a job run as bricks instead of the whole pipeline (brick_tasks.h); a merge
  // reads no volume (volume_path only names it).
  BrickTaskSpec brick;
};

// The limits of one child.
struct JobLimits {
  uint64_t memory_bytes = uint64_t{8} << 30;  // its address space (RLIMIT_AS)
  uint64_t cpu_seconds = 0;                   // its CPU time (0: none)
  absl::Duration wall = absl::Hours(24);      // it is killed after this
  // Opening the volume (its header, its slices' list) may take this long: a damaged file
  // can make a library loop for ever (HDF5 1.10 on a symbol table that points back on
  // itself), and the job then fails as a bad input instead of holding its worker.
  absl::Duration open = absl::Minutes(2);
};

// One progress report of the child; return false to stop it (it is killed).
using JobProgressFn =
    std::function<bool(const std::string& stage, double fraction, const std::string& message)>;

// Runs `spec` in a child of this program (`self`, usually /proc/self/exe), which must call
// RunJobChildIfAsked first thing in main(). Returns the files the child wrote (names within
// output_dir). The pipeline's own errors come back with their codes; kCancelled when
// `progress` asked to stop; kResourceExhausted when the child ran out of its memory limit;
// kDeadlineExceeded past the CPU or wall limit; kInternal when it was killed by a signal or
// died without a word (naming the signal and the stage it was in).
absl::StatusOr<std::vector<std::string>> RunJobInChild(const std::string& self, const JobSpec& spec,
                                                       const JobLimits& limits,
                                                       const JobProgressFn& progress);

// What a volume holds, as the child that opened it saw it.
struct InspectedVolume {
  std::array<int64_t, 3> dims{};
  std::string dtype;  // "uint8", "uint16", "float32"
  std::array<double, 3> spacing{};
};

// What `info` says, as InspectedVolume.
InspectedVolume InspectedOf(const VolumeInfo& info);

// Opens spec.volume_path in a child with `limits` (only the format parameters of
// spec.parameters matter) and returns what it holds. A reader that crashes or that a hostile
// header drives past the memory limit ends the child, not the caller; errors as RunJobInChild.
absl::StatusOr<InspectedVolume> InspectVolumeInChild(const std::string& self, const JobSpec& spec,
                                                     const JobLimits& limits);

// When argv says this process is a job child (argv[1] == "--sheetmesh-job-child"), runs the
// job and returns its exit code; otherwise -1, and main() carries on.
int RunJobChildIfAsked(int argc, char** argv);

// Three quarters of the machine's memory: the default memory limit of a job.
uint64_t DefaultJobMemory();

// This program's own path (for `self`). kInternal when /proc/self/exe cannot be read.
absl::StatusOr<std::string> SelfPath();

}  // namespace sheetmesh::runtime

#endif  // SHEETMESH_WORKER_RUNTIME_JOB_PROCESS_H_
