// Replays the fuzz entry points on the checked-in corpus and on seeded random mutations of
// it, so that the normal build keeps what the fuzzers proved.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "tests/fuzz/fuzz_targets.h"

namespace sheetmesh::fuzz {
namespace {

std::vector<std::string> Corpus(const std::string& name) {
  std::vector<std::string> out;
  const std::filesystem::path dir = std::filesystem::path(SHEETMESH_FUZZ_CORPUS) / name;
  if (!std::filesystem::exists(dir)) return out;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    std::ifstream in(e.path(), std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    out.push_back(ss.str());
  }
  return out;
}

void Replay(const std::string& name, void (*target)(const uint8_t*, size_t), int mutations) {
  const std::vector<std::string> corpus = Corpus(name);
  ASSERT_FALSE(corpus.empty()) << "no corpus for " << name;
  std::mt19937 rng(42);
  for (const std::string& input : corpus) {
    target(reinterpret_cast<const uint8_t*>(input.data()), input.size());
    for (int m = 0; m < mutations; ++m) {
      std::string mutated = input;
      const int edits = 1 + rng() % 4;
      for (int e = 0; e < edits && !mutated.empty(); ++e) {
        const size_t at = rng() % mutated.size();
        switch (rng() % 3) {
          case 0:
            mutated[at] = static_cast<char>(rng());
            break;
          case 1:
            mutated.erase(at, 1 + rng() % 16);
            break;
          default:
            mutated.insert(at, std::string(1 + rng() % 4, static_cast<char>(rng())));
        }
      }
      target(reinterpret_cast<const uint8_t*>(mutated.data()), mutated.size());
    }
  }
}

TEST(FuzzReplayTest, NrrdHeaderCorpusAndMutations) { Replay("nrrd_header", FuzzNrrdHeader, 300); }
TEST(FuzzReplayTest, TiffFileCorpusAndMutations) { Replay("tiff_file", FuzzTiffFile, 60); }
TEST(FuzzReplayTest, NrrdFileCorpusAndMutations) { Replay("nrrd_file", FuzzNrrdFile, 60); }
// OpenVDB allocates what a damaged header declares (the corpus holds files that ask for tens
// of GiB); jobs and the CLI run it under an address-space limit, and so does this test (its
// own process: ctest runs each test apart), where the allocation fails as std::bad_alloc.
TEST(FuzzReplayTest, VdbFileCorpusAndMutations) {
  struct rlimit rl;
  ASSERT_EQ(::getrlimit(RLIMIT_AS, &rl), 0);
  const rlim_t limit = rlim_t{3} << 29;  // 1.5 GiB
  if (rl.rlim_cur == RLIM_INFINITY || rl.rlim_cur > limit) {
    rl.rlim_cur = limit;
    ASSERT_EQ(::setrlimit(RLIMIT_AS, &rl), 0);
  }
  Replay("vdb_file", FuzzVdbFile, 6);
}
TEST(FuzzReplayTest, RawFileCorpusAndMutations) { Replay("raw_file", FuzzRawFile, 60); }
TEST(FuzzReplayTest, Hdf5FileCorpusAndMutations) { Replay("hdf5_file", FuzzHdf5File, 40); }
TEST(FuzzReplayTest, NpyFileCorpusAndMutations) { Replay("npy_file", FuzzNpyFile, 60); }
// GDCM asserts (aborting) on elements its image reader takes with another VR, and on a
// recognition code that is not ACR-NEMA's: the corpus holds the mutation fuzzer's findings
// (bench/mutation_fuzz.py), which the walk before GDCM refuses.
TEST(FuzzReplayTest, DicomFileCorpusAndMutations) { Replay("dicom_file", FuzzDicomFile, 60); }
TEST(FuzzReplayTest, NiftiFileCorpusAndMutations) { Replay("nifti_file", FuzzNiftiFile, 60); }
TEST(FuzzReplayTest, JpegFileCorpusAndMutations) { Replay("jpeg_file", FuzzJpegFile, 60); }
TEST(FuzzReplayTest, PngFileCorpusAndMutations) { Replay("png_file", FuzzPngFile, 60); }
TEST(FuzzReplayTest, TextParsersCorpusAndMutations) {
  Replay("text_parsers", FuzzTextParsers, 300);
}

}  // namespace
}  // namespace sheetmesh::fuzz
