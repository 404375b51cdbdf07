#include "tests/testing/hostile_files.h"

// clang-format off
#include <cstddef>
#include <cstdio>
#include <jpeglib.h>
// clang-format on
#include <hdf5.h>
#include <png.h>
#include <zlib.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "tests/testing/bad_volumes.h"

namespace sheetmesh::testing {
namespace {

void Check(bool ok, const std::string& what) {
  if (!ok) throw std::runtime_error("making a hostile file: " + what);
}

// Closes an HDF5 id with its own close function.
struct Closer {
  hid_t id;
  herr_t (*close)(hid_t);
  ~Closer() {
    if (id >= 0) close(id);
  }
};

hid_t Create(const std::string& path) {
  const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  Check(f >= 0, "create " + path);
  return f;
}

std::string WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

}  // namespace

std::string Hdf5WithExternalStorage(const std::string& path, const std::string& external,
                                    int64_t offset) {
  Closer f{Create(path), H5Fclose};
  hsize_t dims[3] = {1, 1, 1};
  Closer space{H5Screate_simple(3, dims, nullptr), H5Sclose};
  Closer dcpl{H5Pcreate(H5P_DATASET_CREATE), H5Pclose};
  Check(H5Pset_external(dcpl.id, external.c_str(), offset, 1) >= 0, "external storage");
  Closer ds{
      H5Dcreate2(f.id, "/data", H5T_NATIVE_UINT8, space.id, H5P_DEFAULT, dcpl.id, H5P_DEFAULT),
      H5Dclose};
  Check(ds.id >= 0, "external dataset");
  return path;
}

std::string Hdf5Plain(const std::string& path, const std::string& dataset) {
  Closer f{Create(path), H5Fclose};
  hsize_t dims[3] = {8, 8, 8};
  std::vector<uint8_t> v(512, 0);
  for (int z = 0; z < 8; ++z) {
    for (int y = 0; y < 8; ++y) v[z * 64 + y * 8 + 4] = 255;  // the plane x = 4
  }
  Closer space{H5Screate_simple(3, dims, nullptr), H5Sclose};
  Closer lcpl{H5Pcreate(H5P_LINK_CREATE), H5Pclose};
  H5Pset_create_intermediate_group(lcpl.id, 1);
  Closer ds{H5Dcreate2(f.id, dataset.c_str(), H5T_NATIVE_UINT8, space.id, lcpl.id, H5P_DEFAULT,
                       H5P_DEFAULT),
            H5Dclose};
  Check(
      ds.id >= 0 && H5Dwrite(ds.id, H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0,
      "plain dataset");
  return path;
}

std::string Hdf5Virtual(const std::string& path, const std::string& source_file,
                        const std::string& source_dataset) {
  Closer f{Create(path), H5Fclose};
  hsize_t dims[3] = {4, 4, 4};
  Closer space{H5Screate_simple(3, dims, nullptr), H5Sclose};
  Closer src{H5Screate_simple(3, dims, nullptr), H5Sclose};
  Closer dcpl{H5Pcreate(H5P_DATASET_CREATE), H5Pclose};
  Check(H5Pset_virtual(dcpl.id, space.id, source_file.c_str(), source_dataset.c_str(), src.id) >= 0,
        "virtual mapping");
  Closer ds{
      H5Dcreate2(f.id, "/data", H5T_NATIVE_UINT8, space.id, H5P_DEFAULT, dcpl.id, H5P_DEFAULT),
      H5Dclose};
  Check(ds.id >= 0, "virtual dataset");
  return path;
}

std::string Hdf5ExternalLink(const std::string& path, const std::string& target_file,
                             const std::string& target_object) {
  Closer f{Create(path), H5Fclose};
  Check(H5Lcreate_external(target_file.c_str(), target_object.c_str(), f.id, "/data", H5P_DEFAULT,
                           H5P_DEFAULT) >= 0,
        "external link");
  return path;
}

std::string Hdf5HugeChunk(const std::string& path, int chunk) {
  Closer f{Create(path), H5Fclose};
  hsize_t dims[3] = {48, 48, 48};
  hsize_t max[3] = {H5S_UNLIMITED, H5S_UNLIMITED, H5S_UNLIMITED};
  hsize_t chunks[3] = {hsize_t(chunk), hsize_t(chunk), hsize_t(chunk)};
  Closer space{H5Screate_simple(3, dims, max), H5Sclose};
  Closer dcpl{H5Pcreate(H5P_DATASET_CREATE), H5Pclose};
  Check(H5Pset_chunk(dcpl.id, 3, chunks) >= 0 && H5Pset_deflate(dcpl.id, 9) >= 0, "chunking");
  Closer ds{
      H5Dcreate2(f.id, "/data", H5T_NATIVE_UINT8, space.id, H5P_DEFAULT, dcpl.id, H5P_DEFAULT),
      H5Dclose};
  std::vector<uint8_t> v(48 * 48 * 48, 0);
  for (size_t i = 0; i < v.size(); i += 48) v[i + 24] = 255;
  Check(
      ds.id >= 0 && H5Dwrite(ds.id, H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0,
      "huge chunk dataset");
  return path;
}

std::string Hdf5NestedGroups(const std::string& path, int depth) {
  Closer f{Create(path), H5Fclose};
  hid_t parent = f.id;
  std::vector<hid_t> groups;
  for (int i = 0; i < depth; ++i) {
    const hid_t g = H5Gcreate2(parent, "g", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    Check(g >= 0, "nested group");
    groups.push_back(g);
    parent = g;
  }
  hsize_t dims[3] = {4, 4, 4};
  Closer space{H5Screate_simple(3, dims, nullptr), H5Sclose};
  Closer ds{
      H5Dcreate2(parent, "data", H5T_NATIVE_UINT8, space.id, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
      H5Dclose};
  std::vector<uint8_t> v(64, 1);
  H5Dwrite(ds.id, H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  for (auto it = groups.rbegin(); it != groups.rend(); ++it) H5Gclose(*it);
  return path;
}

std::string Hdf5NeverWritten(const std::string& path, int n) {
  Closer f{Create(path), H5Fclose};
  hsize_t dims[3] = {hsize_t(n), hsize_t(n), hsize_t(n)};
  Closer space{H5Screate_simple(3, dims, nullptr), H5Sclose};
  Closer ds{
      H5Dcreate2(f.id, "/data", H5T_NATIVE_UINT8, space.id, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
      H5Dclose};
  Check(ds.id >= 0, "unwritten dataset");
  return path;
}

std::string NpyWithLongShape(const std::string& path, int extents) {
  std::string dict = "{'descr': '|u1', 'fortran_order': False, 'shape': (";
  for (int i = 0; i < extents; ++i) dict += "1,";
  dict += "), }";
  while ((dict.size() + 13) % 64 != 0) dict += ' ';
  dict += '\n';
  std::string out = "\x93NUMPY";
  out += '\x02';
  out += '\x00';
  const uint32_t len = static_cast<uint32_t>(dict.size());
  out.append(reinterpret_cast<const char*>(&len), 4);
  out += dict;
  out += '\x01';
  return WriteBytes(path, out);
}

std::string JpegClaiming(const std::string& dir, int width, int height) {
  std::filesystem::create_directories(dir);
  jpeg_compress_struct c{};
  jpeg_error_mgr err{};
  c.err = jpeg_std_error(&err);
  jpeg_create_compress(&c);
  unsigned char* mem = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&c, &mem, &size);
  c.image_width = 16;
  c.image_height = 16;
  c.input_components = 1;
  c.in_color_space = JCS_GRAYSCALE;
  jpeg_set_defaults(&c);
  jpeg_start_compress(&c, TRUE);
  std::vector<unsigned char> row(16, 200);
  while (c.next_scanline < c.image_height) {
    JSAMPROW r = row.data();
    jpeg_write_scanlines(&c, &r, 1);
  }
  jpeg_finish_compress(&c);
  std::string bytes(reinterpret_cast<char*>(mem), size);
  jpeg_destroy_compress(&c);
  std::free(mem);
  // SOF0: FF C0, length (2), precision (1), height (2), width (2), big-endian.
  const size_t sof = bytes.find("\xFF\xC0");
  Check(sof != std::string::npos, "SOF0 marker");
  bytes[sof + 5] = static_cast<char>(height >> 8);
  bytes[sof + 6] = static_cast<char>(height & 0xff);
  bytes[sof + 7] = static_cast<char>(width >> 8);
  bytes[sof + 8] = static_cast<char>(width & 0xff);
  WriteBytes(dir + "/slice_0000.jpg", bytes);
  return dir;
}

std::string PngClaiming(const std::string& dir, int width, int height) {
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/slice_0000.png";
  FILE* fp = std::fopen(path.c_str(), "wb");
  Check(fp != nullptr, path);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_init_io(png, fp);
  png_set_IHDR(png, info, 16, 16, 8, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  std::vector<png_byte> row(16, 7);
  for (int y = 0; y < 16; ++y) png_write_row(png, row.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(fp);
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // IHDR: length (4) at 8, "IHDR" at 12, width at 16, height at 20, CRC over 12..28 at 29.
  auto put32 = [&](size_t at, uint32_t v) {
    for (int k = 0; k < 4; ++k) bytes[at + k] = static_cast<char>((v >> (24 - 8 * k)) & 0xff);
  };
  put32(16, static_cast<uint32_t>(width));
  put32(20, static_cast<uint32_t>(height));
  put32(29, static_cast<uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(bytes.data() + 12), 17)));
  WriteBytes(path, bytes);
  return dir;
}

std::string VdbCutTo(const std::string& path, int64_t bytes) {
  Check(WriteVolume(path, SheetVolume({48, 40, 32})).ok(), "vdb");
  std::filesystem::resize_file(path, static_cast<uintmax_t>(bytes));
  return path;
}

}  // namespace sheetmesh::testing
