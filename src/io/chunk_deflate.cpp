#include "chunk_deflate.hpp"

#include <libdeflate.h>

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>

#include "h5_util.hpp"

namespace hypershape::io {

namespace {

struct CompressorDeleter {
  void operator()(libdeflate_compressor* c) const { libdeflate_free_compressor(c); }
};

/// One compressor per thread, kept: its allocation is larger than a small array's chunk.
libdeflate_compressor* compressor() {
  thread_local std::unique_ptr<libdeflate_compressor, CompressorDeleter> c(
      libdeflate_alloc_compressor(kDeflateLevel));
  if (!c) throw std::runtime_error("libdeflate: cannot allocate a compressor");
  return c.get();
}

/// HDF5's shuffle filter (H5Z_FILTER_SHUFFLE): byte j of element i goes to j * count + i (the
/// filter leaves a one-byte type as it is, and so does the caller).
void shuffle(const unsigned char* in, std::size_t count, std::size_t elem, unsigned char* out) {
  for (std::size_t j = 0; j < elem; ++j) {
    unsigned char* o = out + j * count;
    for (std::size_t i = 0; i < count; ++i) o[i] = in[i * elem + j];
  }
}

}  // namespace

void declare_deflated_chunks(hid_t dcpl, const std::vector<hsize_t>& chunk, const std::string& what) {
  check(H5Pset_chunk(dcpl, int(chunk.size()), chunk.data()), what);
  check(H5Pset_shuffle(dcpl), what);
  check(H5Pset_deflate(dcpl, kDeflateLevel), what);
}

void write_deflated_chunks(hid_t ds, const void* data, const std::vector<hsize_t>& dims,
                           const std::vector<hsize_t>& chunk, std::size_t elem) {
  std::size_t row = elem;  // bytes of one index along the first axis
  for (std::size_t a = 1; a < dims.size(); ++a) row *= std::size_t(dims[a]);
  const std::size_t rows = std::size_t(chunk[0]), bytes = rows * row;
  std::vector<unsigned char> tail, shuffled(elem > 1 ? bytes : 0);
  std::vector<unsigned char> packed(libdeflate_zlib_compress_bound(compressor(), bytes));
  std::vector<hsize_t> offset(dims.size(), 0);
  const auto* src = static_cast<const unsigned char*>(data);
  for (hsize_t r0 = 0; r0 < dims[0]; r0 += chunk[0]) {
    const std::size_t n = std::min<std::size_t>(rows, std::size_t(dims[0] - r0)) * row;
    const unsigned char* in = src + std::size_t(r0) * row;
    if (n < bytes) {  // a chunk past the end of the first axis is stored whole, its tail zero (never read)
      tail.assign(in, in + n);
      tail.resize(bytes, 0);
      in = tail.data();
    }
    if (elem > 1) {
      shuffle(in, bytes / elem, elem, shuffled.data());
      in = shuffled.data();
    }
    const std::size_t size = libdeflate_zlib_compress(compressor(), in, bytes, packed.data(), packed.size());
    if (size == 0) throw std::runtime_error("libdeflate: a chunk did not fit its bound");
    offset[0] = r0;
    check(H5Dwrite_chunk(ds, H5P_DEFAULT, 0, offset.data(), size, packed.data()), "write a chunk");
  }
}

std::uint32_t crc32_update(std::uint32_t crc, const void* bytes, std::size_t n) {
  return libdeflate_crc32(crc, bytes, n);
}

}  // namespace hypershape::io
