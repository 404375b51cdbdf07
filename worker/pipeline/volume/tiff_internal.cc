#include "worker/pipeline/volume/tiff_internal.h"

#include <cstdarg>
#include <cstdio>

#include "absl/strings/str_cat.h"

namespace sheetmesh::tiff_internal {
namespace {

// libtiff reports through global handlers; keep the last message per thread so that it
// can go into the Status of the call that failed.
thread_local std::string tls_tiff_error;

void TiffErrorHandler(const char* module, const char* fmt, va_list ap) {
  char buf[512];
  vsnprintf(buf, sizeof(buf), fmt, ap);
  tls_tiff_error = module != nullptr ? absl::StrCat(module, ": ", buf) : std::string(buf);
}

void TiffWarningHandler(const char*, const char*, va_list) {}

}  // namespace

void InstallTiffHandlersOnce() {
  static const bool installed = [] {
    TIFFSetErrorHandler(TiffErrorHandler);
    TIFFSetWarningHandler(TiffWarningHandler);
    return true;
  }();
  (void)installed;
}

std::string LastTiffError() {
  std::string e = tls_tiff_error.empty() ? std::string("libtiff failed") : tls_tiff_error;
  tls_tiff_error.clear();
  return e;
}

}  // namespace sheetmesh::tiff_internal
