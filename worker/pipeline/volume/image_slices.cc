// PNG (libpng) and JPEG (libjpeg) slices. Both libraries report errors by longjmp: the
// functions that set the jump hold no C++ object with a destructor, and every buffer they
// fill is allocated before they are called.
// jpeglib.h needs size_t and FILE declared before it.
// clang-format off
#include <cstddef>
#include <cstdio>
#include <jpeglib.h>
// clang-format on
#include <png.h>
#include <sys/stat.h>

#include <csetjmp>
#include <cstring>
#include <filesystem>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "worker/pipeline/volume/slice_stack.h"

namespace sheetmesh {
namespace {

bool HasExtension(const std::string& file, std::initializer_list<const char*> exts) {
  const std::string ext = absl::AsciiStrToLower(std::filesystem::path(file).extension().string());
  for (const char* e : exts) {
    if (ext == e) return true;
  }
  return false;
}

struct FileCloser {
  void operator()(FILE* f) const {
    if (f != nullptr) std::fclose(f);
  }
};
using FilePtr = std::unique_ptr<FILE, FileCloser>;

absl::StatusOr<FilePtr> OpenForRead(const std::string& file) {
  FilePtr f(std::fopen(file.c_str(), "rb"));
  if (f == nullptr) return ErrnoStatus(errno, file);
  return f;
}

int64_t SizeOf(FILE* f) {
  struct stat st;
  return ::fstat(::fileno(f), &st) == 0 ? static_cast<int64_t>(st.st_size) : 0;
}

// The most a compressed slice may decode to per byte of its file: PNG is deflate (1032:1 at
// best); a JPEG takes about 2 bits per 8x8 block of constant grey when progressive (255
// pixels per byte), a few times less with arithmetic coding: 4096 leaves room for that.
constexpr double kMaxPngRatio = 1100;
constexpr double kMaxJpegPixelsPerByte = 4096;

// ---------------------------------------------------------------- PNG

struct PngFailure {
  std::jmp_buf jump;
  char message[256] = {0};
};

void OnPngError(png_structp png, png_const_charp message) {
  auto* f = static_cast<PngFailure*>(png_get_error_ptr(png));
  std::snprintf(f->message, sizeof(f->message), "%s", message);
  std::longjmp(f->jump, 1);
}

void OnPngWarning(png_structp, png_const_charp) {}

// One PNG file being read: its header at Begin, its rows at Read.
class PngFile {
 public:
  explicit PngFile(FILE* fp) : fp_(fp) {
    png_ = png_create_read_struct(PNG_LIBPNG_VER_STRING, &failure_, OnPngError, OnPngWarning);
    if (png_ != nullptr) info_ = png_create_info_struct(png_);
  }
  ~PngFile() { png_destroy_read_struct(&png_, &info_, nullptr); }

  // Reads the header; false with message() on failure.
  bool Begin() {
    if (png_ == nullptr || info_ == nullptr) {
      std::snprintf(failure_.message, sizeof(failure_.message), "out of memory");
      return false;
    }
    unsigned char signature[8];
    if (std::fread(signature, 1, 8, fp_) != 8 || png_sig_cmp(signature, 0, 8) != 0) {
      std::snprintf(failure_.message, sizeof(failure_.message), "not a PNG (no PNG signature)");
      return false;
    }
    if (setjmp(failure_.jump)) return false;
    png_init_io(png_, fp_);
    png_set_sig_bytes(png_, 8);
    png_read_info(png_, info_);
    width = png_get_image_width(png_, info_);
    height = png_get_image_height(png_, info_);
    bit_depth = png_get_bit_depth(png_, info_);
    color_type = png_get_color_type(png_, info_);
    return true;
  }

  // Decodes every row into rows[y] (prepared by the caller for the transformed layout:
  // grey or palette indices, 8 or 16 bits, alpha dropped, colour kept as RGB).
  bool Read(png_bytep* rows) {
    if (setjmp(failure_.jump)) return false;
    if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png_);
    if (bit_depth == 16) png_set_swap(png_);  // to the machine's (little-endian) order
    if (color_type & PNG_COLOR_MASK_ALPHA) png_set_strip_alpha(png_);
    if (color_type == PNG_COLOR_TYPE_PALETTE && bit_depth < 8) png_set_packing(png_);
    png_set_interlace_handling(png_);
    png_read_update_info(png_, info_);
    png_read_image(png_, rows);
    png_read_end(png_, nullptr);
    return true;
  }

  const char* message() const { return failure_.message; }

  uint32_t width = 0;
  uint32_t height = 0;
  int bit_depth = 0;
  int color_type = 0;

 private:
  FILE* fp_;
  PngFailure failure_;
  png_structp png_ = nullptr;
  png_infop info_ = nullptr;
};

std::string PngKind(int bit_depth, int color_type) {
  const int bits = bit_depth == 16 ? 16 : 8;
  const char* what = color_type == PNG_COLOR_TYPE_PALETTE       ? "palette indices"
                     : (color_type & PNG_COLOR_MASK_COLOR) != 0 ? "colour"
                                                                : "grey";
  return absl::StrCat(bits, "-bit ", what);
}

class PngSliceCodec : public SliceCodec {
 public:
  std::string name() const override { return "png"; }
  bool Claims(const std::string& file) const override { return HasExtension(file, {".png"}); }

  absl::StatusOr<SliceHeader> ReadHeader(const std::string& file,
                                         const VolumeLimits& limits) const override {
    SM_ASSIGN_OR_RETURN(FilePtr fp, OpenForRead(file));
    PngFile png(fp.get());
    if (!png.Begin()) {
      return absl::InvalidArgumentError(
          absl::StrCat(file, ": not a readable PNG: ", png.message()));
    }
    SliceHeader h;
    h.width = png.width;
    h.height = png.height;
    h.dtype = png.bit_depth == 16 ? DType::kUInt16 : DType::kUInt8;
    h.kind = PngKind(png.bit_depth, png.color_type);
    const int64_t channels =
        (png.color_type & PNG_COLOR_MASK_COLOR) && png.color_type != PNG_COLOR_TYPE_PALETTE ? 3 : 1;
    const std::string what = absl::StrCat(file, " (", h.width, "x", h.height, " ", h.kind, ")");
    const int64_t decoded = int64_t{h.width} * h.height * channels * BytesPerVoxel(h.dtype);
    // Palette and sub-byte slices decode to more bytes than their compressed rows hold.
    const int64_t packed = png.bit_depth < 8 ? decoded * png.bit_depth / 8 : decoded;
    SM_RETURN_IF_ERROR(CheckCompressionRatio(packed, SizeOf(fp.get()), kMaxPngRatio, what));
    SM_RETURN_IF_ERROR(CheckAllocation(decoded, limits, what));
    return h;
  }

  absl::Status ReadSlice(const std::string& file, const SliceHeader& expected, DType dtype,
                         std::span<std::byte> out) const override {
    SM_ASSIGN_OR_RETURN(FilePtr fp, OpenForRead(file));
    PngFile png(fp.get());
    if (!png.Begin()) {
      return absl::InvalidArgumentError(
          absl::StrCat(file, ": not a readable PNG: ", png.message()));
    }
    const DType got = png.bit_depth == 16 ? DType::kUInt16 : DType::kUInt8;
    if (png.width != expected.width || png.height != expected.height || got != dtype) {
      return absl::InvalidArgumentError(
          absl::StrCat(file, ": slice is ", png.width, "x", png.height, " ",
                       PngKind(png.bit_depth, png.color_type), " but the first slice is ",
                       expected.width, "x", expected.height, " ", expected.kind));
    }
    const bool colour =
        (png.color_type & PNG_COLOR_MASK_COLOR) != 0 && png.color_type != PNG_COLOR_TYPE_PALETTE;
    const size_t bpv = BytesPerVoxel(dtype);
    const size_t row = png.width * bpv;
    std::vector<std::byte> rgb(colour ? out.size() * 3 : 0);
    std::vector<png_bytep> rows(png.height);
    for (uint32_t y = 0; y < png.height; ++y) {
      rows[y] =
          reinterpret_cast<png_bytep>(colour ? rgb.data() + y * row * 3 : out.data() + y * row);
    }
    if (!png.Read(rows.data())) {
      return absl::InvalidArgumentError(absl::StrCat(
          file, ": PNG data cannot be decoded (cut short or corrupt?): ", png.message()));
    }
    if (!colour) return absl::OkStatus();
    // A colour slice is taken when it is grey (R = G = B everywhere), as exported scans
    // often are; anything else has no one value per voxel.
    for (size_t i = 0; i < static_cast<size_t>(png.width) * png.height; ++i) {
      const std::byte* p = rgb.data() + i * 3 * bpv;
      if (std::memcmp(p, p + bpv, bpv) != 0 || std::memcmp(p, p + 2 * bpv, bpv) != 0) {
        return absl::InvalidArgumentError(
            absl::StrCat(file, ": colour PNG whose pixel (", i % png.width, ",", i / png.width,
                         ") is not grey; convert the slices to greyscale (one value per voxel)"));
      }
      std::memcpy(out.data() + i * bpv, p, bpv);
    }
    return absl::OkStatus();
  }
};

// ---------------------------------------------------------------- JPEG

struct JpegFailure {
  jpeg_error_mgr manager;  // first: libjpeg's callbacks get it as the error manager
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX] = {0};
  char warning[JMSG_LENGTH_MAX] = {0};
  int warnings = 0;
  bool decoding = false;  // warnings end the decoding (not the header's reading)
};

void OnJpegError(j_common_ptr cinfo) {
  auto* f = reinterpret_cast<JpegFailure*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, f->message);
  std::longjmp(f->jump, 1);
}

// Warnings (level -1) include "Premature end of JPEG file", after which libjpeg fills the
// rest of the image with grey: the reader treats any as an error.
// The first ends the decoding at once: a cut file of huge declared size would otherwise be
// filled with grey to its end.
void OnJpegMessage(j_common_ptr cinfo, int level) {
  auto* f = reinterpret_cast<JpegFailure*>(cinfo->err);
  if (level >= 0) return;
  if (f->warnings++ == 0) (*cinfo->err->format_message)(cinfo, f->warning);
  if (f->decoding) {
    std::snprintf(f->message, sizeof(f->message), "corrupt or cut short (%s)", f->warning);
    std::longjmp(f->jump, 1);
  }
}

class JpegFile {
 public:
  explicit JpegFile(FILE* fp) : fp_(fp) {
    cinfo_.err = jpeg_std_error(&failure_.manager);
    failure_.manager.error_exit = OnJpegError;
    failure_.manager.emit_message = OnJpegMessage;
  }
  ~JpegFile() {
    if (created_) jpeg_destroy_decompress(&cinfo_);
  }

  bool Begin() {
    if (setjmp(failure_.jump)) return false;
    jpeg_create_decompress(&cinfo_);
    created_ = true;
    jpeg_stdio_src(&cinfo_, fp_);
    jpeg_read_header(&cinfo_, TRUE);
    width = cinfo_.image_width;
    height = cinfo_.image_height;
    components = cinfo_.num_components;
    precision = cinfo_.data_precision;
    return true;
  }

  // Decodes into rows[y] as 8-bit grey (colour as its luminance).
  bool Read(JSAMPROW* rows) {
    if (setjmp(failure_.jump)) return false;
    failure_.decoding = true;
    cinfo_.out_color_space = JCS_GRAYSCALE;
    jpeg_start_decompress(&cinfo_);
    while (cinfo_.output_scanline < cinfo_.output_height) {
      jpeg_read_scanlines(&cinfo_, rows + cinfo_.output_scanline,
                          cinfo_.output_height - cinfo_.output_scanline);
    }
    jpeg_finish_decompress(&cinfo_);
    return true;
  }

  const char* message() const { return failure_.message; }
  int warnings() const { return failure_.warnings; }
  const char* warning() const { return failure_.warning; }

  uint32_t width = 0;
  uint32_t height = 0;
  int components = 0;
  int precision = 0;

 private:
  FILE* fp_;
  JpegFailure failure_;
  jpeg_decompress_struct cinfo_{};
  bool created_ = false;
};

std::string JpegKind(int components) {
  return components == 1 ? "8-bit grey" : "8-bit colour (read as luminance)";
}

class JpegSliceCodec : public SliceCodec {
 public:
  std::string name() const override { return "jpeg"; }
  bool Claims(const std::string& file) const override {
    return HasExtension(file, {".jpg", ".jpeg"});
  }

  absl::StatusOr<SliceHeader> ReadHeader(const std::string& file,
                                         const VolumeLimits& limits) const override {
    SM_ASSIGN_OR_RETURN(FilePtr fp, OpenForRead(file));
    JpegFile jpeg(fp.get());
    if (!jpeg.Begin()) {
      return absl::InvalidArgumentError(
          absl::StrCat(file, ": not a readable JPEG: ", jpeg.message()));
    }
    if (jpeg.precision != 8) {
      return absl::InvalidArgumentError(absl::StrCat(
          file, ": ", jpeg.precision,
          "-bit JPEG samples are not supported (8-bit only); export the slices as 16-bit TIFF "
          "or PNG"));
    }
    SliceHeader h;
    h.width = jpeg.width;
    h.height = jpeg.height;
    h.dtype = DType::kUInt8;
    h.kind = JpegKind(jpeg.components);
    const std::string what = absl::StrCat(file, " (", h.width, "x", h.height, " ", h.kind, ")");
    SM_RETURN_IF_ERROR(CheckCompressionRatio(int64_t{h.width} * h.height, SizeOf(fp.get()),
                                             kMaxJpegPixelsPerByte, what));
    SM_RETURN_IF_ERROR(CheckAllocation(int64_t{h.width} * h.height, limits, what));
    return h;
  }

  absl::Status ReadSlice(const std::string& file, const SliceHeader& expected, DType dtype,
                         std::span<std::byte> out) const override {
    SM_ASSIGN_OR_RETURN(FilePtr fp, OpenForRead(file));
    JpegFile jpeg(fp.get());
    if (!jpeg.Begin()) {
      return absl::InvalidArgumentError(
          absl::StrCat(file, ": not a readable JPEG: ", jpeg.message()));
    }
    if (jpeg.width != expected.width || jpeg.height != expected.height || dtype != DType::kUInt8 ||
        jpeg.precision != 8) {
      return absl::InvalidArgumentError(absl::StrCat(file, ": slice is ", jpeg.width, "x",
                                                     jpeg.height, " ", jpeg.precision,
                                                     "-bit but the first slice is ", expected.width,
                                                     "x", expected.height, " ", expected.kind));
    }
    std::vector<JSAMPROW> rows(jpeg.height);
    for (uint32_t y = 0; y < jpeg.height; ++y) {
      rows[y] = reinterpret_cast<JSAMPROW>(out.data() + static_cast<size_t>(y) * jpeg.width);
    }
    if (!jpeg.Read(rows.data())) {
      return absl::InvalidArgumentError(
          absl::StrCat(file, ": JPEG data cannot be decoded: ", jpeg.message()));
    }
    if (jpeg.warnings() > 0) {
      return absl::InvalidArgumentError(
          absl::StrCat(file, ": JPEG data is corrupt or cut short (", jpeg.warning(), ")"));
    }
    return absl::OkStatus();
  }
};

}  // namespace

std::unique_ptr<SliceCodec> MakePngSliceCodec() { return std::make_unique<PngSliceCodec>(); }
std::unique_ptr<SliceCodec> MakeJpegSliceCodec() { return std::make_unique<JpegSliceCodec>(); }

}  // namespace sheetmesh
