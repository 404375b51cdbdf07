#include "common/sha256.h"

#include <openssl/evp.h>
#include <unistd.h>

#include <vector>

#include "absl/strings/str_cat.h"
#include "common/file_util.h"
#include "common/status_macros.h"

namespace sheetmesh {

Sha256::Sha256() : ctx_(EVP_MD_CTX_new()) {
  EVP_DigestInit_ex(static_cast<EVP_MD_CTX*>(ctx_), EVP_sha256(), nullptr);
}

Sha256::~Sha256() { EVP_MD_CTX_free(static_cast<EVP_MD_CTX*>(ctx_)); }

void Sha256::Update(const void* data, size_t size) {
  EVP_DigestUpdate(static_cast<EVP_MD_CTX*>(ctx_), data, size);
}

std::string Sha256::Hex() {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  EVP_DigestFinal_ex(static_cast<EVP_MD_CTX*>(ctx_), md, &len);
  static const char kHex[] = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < len; ++i) {
    out += kHex[md[i] >> 4];
    out += kHex[md[i] & 15];
  }
  return out;
}

std::string Sha256Hex(absl::string_view data) {
  Sha256 sha;
  sha.Update(data.data(), data.size());
  return sha.Hex();
}

absl::Status HashFilePrefix(int fd, int64_t length, Sha256* sha, const std::string& path) {
  std::vector<char> buf(1 << 20);
  int64_t done = 0;
  while (done < length) {
    const ssize_t n = ::pread(fd, buf.data(), std::min<int64_t>(buf.size(), length - done), done);
    if (n < 0) return ErrnoStatus(errno, path);
    if (n == 0) return absl::DataLossError(absl::StrCat(path, ": shorter than ", length, " bytes"));
    sha->Update(buf.data(), n);
    done += n;
  }
  return absl::OkStatus();
}

absl::StatusOr<FileHash> HashFile(const std::string& path) {
  SM_ASSIGN_OR_RETURN(ScopedFd fd, OpenForRead(path));
  FileHash h;
  SM_ASSIGN_OR_RETURN(h.size, FileSizeOf(fd.get(), path));
  Sha256 sha;
  SM_RETURN_IF_ERROR(HashFilePrefix(fd.get(), h.size, &sha, path));
  h.hex = sha.Hex();
  return h;
}

}  // namespace sheetmesh
