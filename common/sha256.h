// SHA-256, the hash of content addresses (OpenSSL underneath).
#ifndef SHEETMESH_COMMON_SHA256_H_
#define SHEETMESH_COMMON_SHA256_H_

#include <cstddef>
#include <cstdint>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace sheetmesh {

// Incremental hashing. Not thread-safe.
class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;

  void Update(const void* data, size_t size);
  // Lower-case hex of the digest; the object is spent afterwards.
  std::string Hex();

 private:
  void* ctx_;  // EVP_MD_CTX
};

// Lower-case hex SHA-256 of `data`.
std::string Sha256Hex(absl::string_view data);

// SHA-256 (hex) and size of the first `length` bytes of an open file, read with pread.
absl::Status HashFilePrefix(int fd, int64_t length, Sha256* sha, const std::string& path);

// SHA-256 (hex) and size of a whole file.
struct FileHash {
  std::string hex;
  int64_t size = 0;
};
absl::StatusOr<FileHash> HashFile(const std::string& path);

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_SHA256_H_
